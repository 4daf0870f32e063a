"""The analytic estimate above ANALYTIC_OWN_PIXELS (1440p, 4K), measured: estimate / measured RMSE.

    MOTIONBLUR_NUM_THREADS=1 python benches/bench_estimate_large.py --seeds 1000900-1000912 \\
        --sizes 3840x2160,2560x1440 [--set measuring]

(without arguments, as ``make bench`` runs it: seeds 1000900-1000901 at 2560x1440 only).

Each scene of ``random_scene(seed, w, h)`` and size, one at a time in a fresh process (a 4K
limit holds about 1.3 GB): ``mb.render(scene, "analytic")`` with its estimate (its render time
``stats["ms"]`` and the estimate's ``stats["estimate_ms"]``), measured against
``motionblur.methods._estimate.limit`` (over the background, as bench_error_control does; cached
under ``out/bench/estimate_large/refs``). Rows go to ``rows.jsonl``, the table (frames with a
measured error of at least 1e-6) to ``results.md``, in ``out/bench/estimate_large/<set>``.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np

OUT = Path("out/bench/estimate_large")


def one(seed: int, size: str, path: Path) -> None:
    import motionblur as mb
    from motionblur.evaluation import random_scenes
    from motionblur.evaluation.random_scenes import random_scene
    from motionblur.methods import _estimate, _segments

    w, h = map(int, size.split("x"))
    scene = random_scene(seed, w, h)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        f = mb.render(scene, "analytic")
    build = b"".join(Path(m.__file__).read_bytes() for m in (mb._core, _segments, random_scenes))
    key = hashlib.sha1(f"{seed}{size}{_estimate.LIMIT_OPTIONS}".encode() + build).hexdigest()[:12]
    ref_path = OUT / "refs" / f"{seed}_{size}_{key}.npy"
    if ref_path.exists():
        ref = np.load(ref_path)
    else:
        ref = _estimate.limit(scene).rgba
        ref_path.parent.mkdir(parents=True, exist_ok=True)
        np.save(ref_path, ref)
    measured = float(np.sqrt(np.mean(np.square(f.rgba.astype(np.float64) - ref.astype(np.float64)))))
    row = {
        "seed": seed, "size": size, "measured": measured, "estimate": f.stats["error_estimate"],
        "how": f.stats["error_estimate_how"], "ms": f.stats["ms"], "estimate_ms": f.stats["estimate_ms"],
    }  # fmt: skip
    with open(path, "a") as fh:
        fh.write(json.dumps(row) + "\n")
    print(json.dumps(row), flush=True)


def table(rows: list[dict]) -> str:
    lines = [
        "| size | frames | in [0.5, 2] | below 0.5 | median | min | max | estimate / render time, median (min-max) |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for size in dict.fromkeys(r["size"] for r in rows):
        rs = [r for r in rows if r["size"] == size and r["measured"] >= 1e-6]
        cost = np.array([r["estimate_ms"] / r["ms"] for r in rows if r["size"] == size])
        if not rs:
            continue
        q = np.array([r["estimate"] / r["measured"] for r in rs])
        inside = np.mean((q >= 0.5) & (q <= 2.0)) * 100
        lines.append(
            f"| {size} | {len(rs)} | {inside:.0f}% | {int(np.sum(q < 0.5))} | {np.median(q):.2f} | {q.min():.2f} "
            f"| {q.max():.2f} | {np.median(cost):.2f} ({cost.min():.2f}-{cost.max():.2f}) |"
        )
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser()
    # the defaults (what `make bench` runs) are a short check, about 3 minutes; the docs' table
    # is --seeds 1000900-1000912 --sizes 3840x2160,2560x1440 (an hour on one thread)
    ap.add_argument("--seeds", default="1000900-1000901", help="first-last (inclusive)")
    ap.add_argument("--sizes", default="2560x1440")
    ap.add_argument("--set", default="measuring", choices=("measuring", "tuning"))
    ap.add_argument("--one", nargs=2, help=argparse.SUPPRESS)
    a = ap.parse_args()
    out = OUT / a.set
    out.mkdir(parents=True, exist_ok=True)
    path = out / "rows.jsonl"
    if a.one:
        one(int(a.one[0]), a.one[1], path)
        return
    from motionblur.evaluation.random_scenes import MEASURING_SEEDS, TUNING_SEEDS

    first, last = map(int, a.seeds.split("-"))
    seeds = range(first, last + 1)
    allowed = MEASURING_SEEDS if a.set == "measuring" else TUNING_SEEDS
    if any(s not in allowed for s in seeds):
        raise SystemExit(f"seeds {a.seeds}: not all in the {a.set} set")
    done = set()
    if path.exists():
        done = {(r["seed"], r["size"]) for r in map(json.loads, path.read_text().splitlines())}
    for seed in seeds:
        for size in a.sizes.split(","):
            if (seed, size) not in done:
                subprocess.run(
                    [sys.executable, __file__, "--set", a.set, "--seeds", a.seeds, "--one", str(seed), size],
                    check=True,
                )
    rows = [json.loads(line) for line in path.read_text().splitlines()]
    text = table(rows)
    (out / "results.md").write_text(text + "\n")
    print(text)


if __name__ == "__main__":
    main()
