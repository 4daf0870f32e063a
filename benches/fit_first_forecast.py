"""Fit `auto.FIRST_FIT`: the forecast of accumulation's error from the scene's screen sweep.

    python benches/fit_first_forecast.py [--aa 1] [--sizes 96x72:120,192x144:80] [--first-seed 0]

For each tuning scene (`motionblur.evaluation.random_scenes`, seeds ``first-seed`` on, as many
as each size names) where something moves (no rolling shutter): its sweep
(`motionblur.methods._sweep.sweep_scale`), and for N = 2, 4, 8, 16, 32 stratified samples
(auto's own first render, `_Trials.accumulate`) the error estimate and the RMSE against
`motionblur.exact` at the same ``aa``. Then least squares of ``log y = c0 + c1 log sweep + c2 log
N``, ``y`` the RMSE at ``aa`` 1 and the estimate at 2 and 4 (what certifies the frame there), on
every row and cross-fitted (fitted on the odd seeds, tried on the even ones and back): the
10th, 50th and 90th percentiles of y / forecast. ``auto.FIRST_FIT[aa]`` holds the fit on every
row. Writes ``rows.jsonl`` and ``fit.json`` to ``out/bench/first_fit/aa<aa>``.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

import motionblur as mb
from motionblur.evaluation.metrics import rmse
from motionblur.evaluation.random_scenes import random_scene
from motionblur.methods import auto as A
from motionblur.methods._sweep import sweep_scale
from motionblur.raster import over_background
from motionblur.threads import set_num_threads

OUT = Path("out/bench/first_fit")
COUNTS = (2, 4, 8, 16, 32)


def scene_rows(seed: int, w: int, h: int, aa: int) -> list[dict]:
    """The rows of one scene (none where nothing moves or under a rolling shutter)."""
    scene = random_scene(seed, w, h)
    if not A._moves(scene) or scene.rolling > 0.0:
        return []
    ref = mb.exact(scene, aa=aa).rgba.astype(np.float64)
    sweep = sweep_scale(scene)
    rows = []
    for n in COUNTS:
        frame = A._Trials(scene, aa).accumulate(n)
        err = rmse(over_background(frame, scene.background).rgba, ref)
        est = float(frame.stats["error_estimate"])
        rows.append(
            {"seed": seed, "size": f"{w}x{h}", "aa": aa, "sweep": sweep, "n": n, "est": est, "err": err}
        )
    return rows


def fit(rows: list[dict], aa: int) -> dict:
    """The least-squares fit on every usable row and its cross-fitted spread (module docs)."""
    key = "err" if aa == 1 else "est"
    rows = [r for r in rows if r["sweep"] > 0 and r[key] > 0]
    x = np.array([[1.0, np.log(r["sweep"]), np.log(r["n"])] for r in rows])
    y = np.log([r[key] for r in rows])
    odd = np.array([r["seed"] % 2 == 1 for r in rows])
    c = np.linalg.lstsq(x, y, rcond=None)[0]
    ratios = []
    for train in (odd, ~odd):
        if train.any() and (~train).any():
            ct = np.linalg.lstsq(x[train], y[train], rcond=None)[0]
            ratios.append(np.exp(y[~train] - x[~train] @ ct))
    ratio = np.concatenate(ratios) if ratios else np.exp(y - x @ c)
    p10, p50, p90 = (float(np.percentile(ratio, q)) for q in (10, 50, 90))
    return {"aa": aa, "of": key, "rows": len(rows), "fit": [round(float(v), 3) for v in c],
            "cross_fitted_ratio": {"p10": p10, "median": p50, "p90": p90}}  # fmt: skip


def scene_specs(sizes: str, first_seed: int) -> list[tuple[int, int, int]]:
    """``(seed, width, height)`` for ``sizes`` ``"WxH:scenes,..."``: that many seeds from
    ``first_seed`` at each size, in order."""
    out = []
    for spec in sizes.split(","):
        size, count = spec.split(":")
        w, h = map(int, size.split("x"))
        out += [(seed, w, h) for seed in range(first_seed, first_seed + int(count))]
    return out


def main(argv: list[str] | None = None) -> dict:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--aa", type=int, default=1, choices=(1, 2, 4))
    p.add_argument("--sizes", default="96x72:120,192x144:80", help="WxH:scenes, comma-separated")
    p.add_argument("--first-seed", type=int, default=0)
    p.add_argument("--out", default=None, help="output folder (default out/bench/first_fit/aa<aa>)")
    args = p.parse_args(argv)
    set_num_threads(1)
    rows = [
        row
        for seed, w, h in scene_specs(args.sizes, args.first_seed)
        for row in scene_rows(seed, w, h, args.aa)
    ]
    result = fit(rows, args.aa)
    out = Path(args.out) if args.out else OUT / f"aa{args.aa}"
    out.mkdir(parents=True, exist_ok=True)
    (out / "rows.jsonl").write_text("".join(json.dumps(r) + "\n" for r in rows))
    (out / "fit.json").write_text(json.dumps(result, indent=1))
    print(json.dumps(result), f"(auto.FIRST_FIT[{args.aa}] = {A.FIRST_FIT[args.aa]})")
    return result


if __name__ == "__main__":
    main(sys.argv[1:])
