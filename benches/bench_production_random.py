"""Issue 27's claims on seeded random scenes nobody picked, against the exact integral.

`bench_production.py` and `bench_production_image.py` measure chosen scenes (a bunny and a knot
translating, a camera pan). This renders fresh scenes of the measuring set
(`motionblur.evaluation.random_scenes`: one to three meshes, half of them held-out meshes,
turning about random axes, coming toward the camera, curved paths, some with camera motion) and
prints, per size: each image-space method's time over one sharp frame (the 2x target), its time
against accumulation's at the same error (``compare.equal_error`` over 1 to 256 samples: does
the blur pay for itself?) and its RMSE over the sharp frame's; the analytic frame's time over
accumulation-256's and both errors. Errors against ``mb.exact``; times wall-clock ms of
``render(..., error_estimate=False)``, best of 3 (the analytic frame: 1) after a warm-up.

Usage: python benches/bench_production_random.py [--first 1002666] [--scenes 30]
[--sizes 320x240,640x480] [--large-first 1002696] [--large-scenes 20] [--large 1920x1080]
Writes out/bench/production_random.jsonl and production_random.md.
"""

from __future__ import annotations

import argparse
import json
import time
import warnings
from pathlib import Path

import numpy as np

import motionblur as mb
from motionblur.evaluation.compare import equal_error
from motionblur.evaluation.metrics import rmse
from motionblur.evaluation.random_scenes import HELD_OUT_MESHES, random_scene

METHODS = ("velocity", "opaque_image", "camera_velocity", "analytic")
COUNTS = (1, 2, 4, 8, 16, 32, 64, 128, 256)


def best(fn, n: int = 3):
    fn()
    ms, out = float("inf"), None
    for _ in range(n):
        t0 = time.perf_counter()
        out = fn()
        ms = min(ms, (time.perf_counter() - t0) * 1e3)
    return ms, out


def measure(seed: int, w: int, h: int) -> dict:
    """One scene's row: accumulation at `COUNTS`, each method of `METHODS` that applies."""
    s = random_scene(seed, w, h)
    movers = [o.name for o in s.objects if o.is_moving or s.camera_moves]
    row = {"seed": seed, "size": f"{w}x{h}", "camera_moves": bool(s.camera_moves), "movers": movers,
           "held_out": any(n.rstrip("0123456789") in HELD_OUT_MESHES for n in movers)}  # fmt: skip
    ref = mb.exact(s).rgba
    acc = []
    for n in COUNTS:
        ms, f = best(lambda n=n: mb.render(s, "accumulation", samples=n, error_estimate=False))
        acc.append({"method": "accumulation", "ms": ms, "rmse": rmse(f.rgba, ref)})
    row.update(
        sharp_ms=acc[0]["ms"], sharp_rmse=acc[0]["rmse"], acc256_ms=acc[-1]["ms"], acc256_rmse=acc[-1]["rmse"]
    )
    for m in METHODS:
        if not mb.METHODS[m].applies(s):
            continue
        try:
            ms, f = best(lambda m=m: mb.render(s, m, error_estimate=False), 1 if m == "analytic" else 3)
        except ValueError:
            row[m] = "refused"
            continue
        e = rmse(f.rgba, ref)
        eq = equal_error([*acc, {"method": m, "ms": ms, "rmse": e}], method=m)
        _, t_eq, bound, factor = eq[0] if eq else (None, float("nan"), "exact", float("nan"))
        row[m] = {"ms": ms, "rmse": e, "acc_eq_ms": t_eq, "bound": bound, "factor": factor}
    return row


def _q(a: np.ndarray) -> str:
    return f"{np.median(a):.2f} ({np.percentile(a, 10):.2f}-{np.percentile(a, 90):.2f})"


def summary(rows: list[dict]) -> list[str]:
    lines = [
        "| size | method | frames | time / sharp frame: median (p10-p90) | within 2x | accumulation at "
        "equal error / method | method cheaper | RMSE / sharp frame's |",
        "|---|---|---:|---:|---:|---:|---:|---:|",
    ]
    for size in sorted({r["size"] for r in rows}, key=lambda z: int(z.split("x")[0])):
        sel = [r for r in rows if r["size"] == size]
        for m in METHODS[:-1]:
            got = [r for r in sel if isinstance(r.get(m), dict)]
            if not got:
                continue
            t = np.array([r[m]["ms"] / r["sharp_ms"] for r in got])
            f = np.array([r[m]["factor"] for r in got if np.isfinite(r[m]["factor"])])
            e = np.array([r[m]["rmse"] / r["sharp_rmse"] for r in got if r["sharp_rmse"] > 0])
            lines.append(f"| {size} | {m} | {len(got)} | {_q(t)} | {np.mean(t <= 2):.0%} | {_q(f)} | "
                         f"{np.mean(f > 1):.0%} | {_q(e)} |")  # fmt: skip
        got = [r for r in sel if isinstance(r.get("analytic"), dict)]
        if got:
            t = np.array([r["analytic"]["ms"] / r["acc256_ms"] for r in got])
            ea = np.array([r["analytic"]["rmse"] for r in got])
            e256 = np.array([r["acc256_rmse"] for r in got])
            lines.append(f"| {size} | analytic / accumulation-256 | {len(got)} | {_q(t)} | within acc-256's time: "
                         f"{np.mean(t <= 1):.0%} | error under acc-256's: {np.mean(ea < e256):.0%} | | |")  # fmt: skip
    return lines


def main() -> None:
    warnings.simplefilter("ignore")
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--first", type=int, default=1_002_666)
    p.add_argument("--scenes", type=int, default=30)
    p.add_argument("--sizes", default="320x240,640x480")
    p.add_argument("--large-first", type=int, default=1_002_696)
    p.add_argument("--large-scenes", type=int, default=20)
    p.add_argument("--large", default="1920x1080", help="the production size ('' for none)")
    a = p.parse_args()
    runs = [(size, a.first, a.scenes) for size in a.sizes.split(",") if size]
    runs += [(a.large, a.large_first, a.large_scenes)] if a.large else []
    out = Path("out/bench")
    out.mkdir(parents=True, exist_ok=True)
    rows = []
    with open(out / "production_random.jsonl", "w") as f:
        for size, first, count in runs:
            w, h = map(int, size.split("x"))
            for seed in range(first, first + count):
                rows.append(measure(seed, w, h))
                f.write(json.dumps(rows[-1]) + "\n")
                print(f"{size} seed {seed}", flush=True)
    text = "\n".join(["# Issue 27 on random measuring scenes, against mb.exact", "", *summary(rows), ""])
    (out / "production_random.md").write_text(text)
    print(text)


if __name__ == "__main__":
    main()
