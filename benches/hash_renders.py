"""Hash the renders of every built-in scene and method, and of seeded random scenes.

A refactor that must not change behaviour runs this before and after and compares:

    python benches/hash_renders.py --out before.json     # on the old tree
    python benches/hash_renders.py --out after.json      # on the new tree
    python benches/hash_renders.py --compare before.json after.json

Each entry is the SHA-256 of a frame's arrays (rgba, depth, ids, velocity) at 64x48 and 96x72 with
the method's default options and one thread count. ``auto`` is left out: its plan compares timings.
Not a pass/fail test; the CHANGELOG names any entry a change meant to alter.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import sys
import warnings

import numpy as np

import motionblur as mb
from motionblur.evaluation.random_scenes import MEASURING_SEEDS, random_scene
from motionblur.render import methods_for

SIZES = ((64, 48), (96, 72))
RANDOM = 8
DOF = {"aperture": 0.05, "focus_distance": 5.0}


def _digest(frame: mb.Frame) -> str:
    h = hashlib.sha256()
    for a in (frame.rgba, frame.depth, frame.ids, frame.velocity):
        h.update(np.ascontiguousarray(a).tobytes())
    return h.hexdigest()[:16]


def _scenes():
    for name in sorted(mb.SCENES):
        for w, h in SIZES:
            yield f"{name}@{w}x{h}", mb.SCENES[name](width=w, height=h)
    for seed in list(MEASURING_SEEDS)[:RANDOM]:
        yield f"random{seed}@96x72", random_scene(seed, 96, 72)


def _one(scene, method: str, options: dict) -> str:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            return _digest(mb.render(scene, method, error_estimate=False, **options))
        except Exception as e:  # a refusal is behaviour too
            return f"raises {type(e).__name__}"


def hashes() -> dict[str, str]:
    """{scene@size/method[/options]: digest} for every applicable method but auto.

    Default options on every scene; each method's report sweep (its option sets) on the built-in
    scenes at the smaller size, so the way options cross into the core is covered too.
    """
    out: dict[str, str] = {}
    for label, scene in _scenes():
        for method in methods_for(scene):
            if method == "auto":
                continue
            out[f"{label}/{method}"] = _one(scene, method, {})
            if label.startswith("random") or not label.endswith(f"@{SIZES[0][0]}x{SIZES[0][1]}"):
                continue
            for options in mb.METHODS[method].sweep:
                key = ",".join(f"{k}={v}" for k, v in sorted(options.items()))
                out[f"{label}/{method}/{key}"] = _one(scene, method, options)
            out[f"{label}/{method}/dof"] = _one(scene, method, DOF)
    return out


def compare(before: str, after: str) -> int:
    a = json.load(open(before))
    b = json.load(open(after))
    keys = sorted(set(a) | set(b))
    diff = [k for k in keys if a.get(k) != b.get(k)]
    for k in diff:
        print(f"{k}: {a.get(k)} -> {b.get(k)}")
    print(f"{len(keys) - len(diff)} of {len(keys)} identical")
    return 1 if diff else 0


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--out", default="out/render_hashes.json")
    p.add_argument("--compare", nargs=2, metavar=("BEFORE", "AFTER"))
    args = p.parse_args()
    if args.compare:
        return compare(*args.compare)
    result = hashes()
    from pathlib import Path

    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text(json.dumps(result, indent=1, sort_keys=True))
    print(f"{len(result)} renders hashed into {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
