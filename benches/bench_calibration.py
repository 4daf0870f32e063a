"""Calibration only: every non-accumulation method's error estimate against its measured RMSE.

    python benches/bench_calibration.py [--set measuring|tuning] [--scenes 30] [--sizes 96x72,192x144]

The part of ``bench_error_control.py`` that measures ``stats["error_estimate"]`` (without auto's
runs), with each scene's features (motion kinds, camera motion, shutter, translucency) beside
each row so that the frames outside 0.5x-2x can be read. The method's frame and its measured
RMSE are cached (``out/bench/calibration/frames``): the estimate alone is recomputed when only
the estimator changed. Writes ``rows.json`` and ``results.md`` to ``out/bench/calibration/<set>``.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import sys
import time
import warnings
from pathlib import Path

import numpy as np

import motionblur as mb
from motionblur.evaluation.random_scenes import MEASURING_SEEDS, TUNING_SEEDS, random_scene
from motionblur.render import ESTIMATOR

sys.path.insert(0, str(Path(__file__).parent))
import bench_error_control  # noqa: E402  (its cached references)

OUT = Path("out/bench/calibration")
METHODS = ("analytic", "motion_volume", "opaque_image", "velocity", "blur_shell", "camera_velocity")


def rmse(a, b) -> float:
    return float(np.sqrt(np.mean(np.square(np.asarray(a, np.float64) - b))))


def features(scene) -> list[str]:
    """Short labels of what the scene holds (from its motions, camera, shutter, colours)."""
    out = []
    back = scene.camera.pose[:3, 2]
    for o in scene.objects:
        m = o.motion
        if m is None:
            continue
        if m.vertices is not None:
            out.append("deforming")
            continue
        r0, r1 = m.transforms[0][:3, :3], m.transforms[-1][:3, :3]
        s = np.cbrt(np.linalg.det(r0))
        cosang = np.clip((np.trace(r0.T @ r1) / (s * s) - 1) / 2, -1, 1)
        d = m.transforms[-1][:3, 3] - m.transforms[0][:3, 3]
        if len(m.times) > 2:
            out.append(
                "curved" if np.ptp(np.diff(m.transforms[:, :3, 3], axis=0), axis=0).max() > 1e-6 else "turn"
            )
        elif abs(d @ back) > 0.5 * np.linalg.norm(d):
            out.append("toward")
        else:
            out.append("translate")
        if np.arccos(cosang) > 1e-3 and out[-1] in ("translate", "toward"):
            out[-1] += "+rot"
        if o.color[3] < 1.0:
            out.append("translucent")
    if scene.camera_motion is not None:
        out.append("camera")
    if not isinstance(scene.shutter, str) or scene.shutter != "box":
        out.append("shutter")
    return out


def reference(scene, seed, size) -> np.ndarray:
    return bench_error_control.reference(scene, seed, size)  # the same cache


def method_row(scene, ref, seed, size, method) -> dict:
    """The method's measured RMSE and render time (cached by seed, size, method and build)."""
    build = hashlib.sha1(Path(mb._core.__file__).read_bytes()).hexdigest()[:8]
    path = OUT / "frames" / f"{seed}_{size}_{method}_{build}.json"
    if path.exists():
        return json.loads(path.read_text())
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            t0 = time.perf_counter()
            f = mb.render(scene, method, error_estimate=False)
            ms = (time.perf_counter() - t0) * 1e3
        row = {"measured": rmse(f.rgba, ref), "render_ms": ms}
    except ValueError as exc:
        row = {"refused": str(exc)[:100]}
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(row))
    return row


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--set", choices=("measuring", "tuning"), default="measuring")
    p.add_argument("--scenes", type=int, default=30)
    p.add_argument("--first", type=int, default=0)
    p.add_argument("--sizes", default="96x72,192x144")
    p.add_argument("--methods", default=",".join(METHODS))
    args = p.parse_args()
    seeds = (MEASURING_SEEDS if args.set == "measuring" else TUNING_SEEDS)[
        args.first : args.first + args.scenes
    ]
    rows = []
    for size in args.sizes.split(","):
        w, h = map(int, size.split("x"))
        for seed in seeds:
            scene = random_scene(seed, w, h)
            ref = reference(scene, seed, size)
            feats = features(scene)
            for method in args.methods.split(","):
                if not mb.METHODS[method].applies(scene):
                    continue
                row = {"seed": seed, "size": size, "method": method, "features": feats}
                row.update(method_row(scene, ref, seed, size, method))
                if "refused" not in row:
                    with warnings.catch_warnings():
                        warnings.simplefilter("ignore")
                        t0 = time.perf_counter()
                        est = ESTIMATOR[0](scene, method, {})
                        row["estimate_ms"] = (time.perf_counter() - t0) * 1e3
                    row["estimate"] = est["error_estimate"]
                    row["ratio"] = (
                        est["error_estimate"] / row["measured"] if row["measured"] > 0 else float("nan")
                    )
                rows.append(row)
            print(size, seed, flush=True)
    out = OUT / args.set
    out.mkdir(parents=True, exist_ok=True)
    (out / "rows.json").write_text(json.dumps(rows, indent=1))
    text = summarise(rows, seeds, args.sizes)
    (out / "results.md").write_text(text)
    print(text)


def summarise(rows, seeds, sizes) -> str:
    lines = [f"seeds {seeds.start}..{seeds.stop - 1}, sizes {sizes}", ""]
    lines += [
        "| method | frames | in [0.5, 2] | below 0.5 | median | min | max | estimate ms / render ms (median) |"
    ]
    lines += ["|---|---|---|---|---|---|---|---|"]
    for method in METHODS:
        sel = [r for r in rows if r["method"] == method and "ratio" in r and r["measured"] >= 1e-5]
        if not sel:
            continue
        a = np.array([r["ratio"] for r in sel])
        cost = np.median([r["estimate_ms"] / r["render_ms"] for r in sel])
        lines.append(
            f"| {method} | {len(a)} | {np.mean((a >= 0.5) & (a <= 2)):.0%} | {int((a < 0.5).sum())} | "
            f"{np.median(a):.2f} | {a.min():.2f} | {a.max():.2f} | {cost:.2f} |"
        )
    lines += ["", "Outside [0.5, 2]:", ""]
    for r in rows:
        if "ratio" in r and r["measured"] >= 1e-5 and not 0.5 <= r["ratio"] <= 2:
            lines.append(
                f"- {r['method']} {r['seed']} {r['size']}: {r['ratio']:.2f} (est {r['estimate']:.2e}, "
                f"measured {r['measured']:.2e}) {' '.join(r['features'])}"
            )
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    main()
