"""A study for `auto`'s refinement: stratified grids refined by some of their strata's boundaries.

    python benches/study_refined_grids.py [--sizes 96x72:60,192x144:40] [--first-seed 0]

`auto` refines a frame that narrowly missed its tolerance to the trapezoid grid of twice the
strata (2N + 1 samples): with equal weights nothing finer holds the N drawn samples. With
unequal weights it can: add the boundaries ``(4i + 1) / N`` (family A) and then ``(4i + 3) / N``
(B) of the N strata and weight each sample by its nearest-time cell (a midpoint 3/4 of a stratum
beside one new boundary, a boundary 1/2). The weights are then uniform within each quarter of the
cells (``i % 4``), so N drawn in four parts can be reweighted part by part. A costs 1.25 N
samples, A and B 1.5 N; for a pixel stepping once at a uniformly random time their RMS error is
0.90x and 0.79x the N-sample grid's (fresh grids of 1.25 N and 1.5 N: 0.80x and 0.67x), and C
and D (``(4i + 2) / N``, ``4i / N``) complete the trapezoid grid of 2N strata.

For each tuning scene where something moves under a shutter auto refines under (any but a
weights shutter; ``--box`` the box shutter's only), at `aa` 1 and N = 8, 12, 16, 24,
32: the N-sample grid (S), S refined by A and by A and B, each with its halves' estimate at a
factor of 1 (the halves: the even and the odd cells, A's boundaries with the even, B's with the
odd), and fresh stratified grids of 1.25 N and 1.5 N, each against `motionblur.exact`. Prints
per grid the halves factor that puts the median estimate / error at 1.1 with the 5th and 95th
percentiles it leaves, the factor that gives it the stratified grid's 5th percentile at its
shipped factor (what `HALVES_FACTOR` ships for the refined grids), and each grid's error over
S's. Writes ``rows.jsonl`` to ``out/bench/refined_grids``. Tuning scenes only.
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
from motionblur.methods import _accumulate
from motionblur.methods import auto as A
from motionblur.methods._accumulate import HalfSums, shutter_quantiles
from motionblur.raster import over_background
from motionblur.threads import set_num_threads

sys.path.insert(0, str(Path(__file__).resolve().parent))
from fit_first_forecast import scene_specs  # noqa: E402  (the script beside this one)

OUT = Path("out/bench/refined_grids")
COUNTS = (8, 12, 16, 24, 32)
#: Each family's first boundary within four strata and the half it joins.
FAMILIES = {"A": (1, 0), "B": (3, 1), "C": (2, 0), "D": (0, 1)}
GRIDS = {"S": (), "A": ("A",), "AB": ("A", "B")}


def refined(scene, n: int, families) -> tuple[float, float, int]:
    """(estimate at a halves factor of 1, frame, samples) of ``n`` strata (4 divides n) refined
    by the boundary ``families``, every sample weighted by its nearest-time cell. (The parts
    carry no quarters, so the estimate is the stratified factor times the halves' difference:
    divided out.)"""
    sums = HalfSums(scene, 1)
    first = {FAMILIES[f][0] for f in families}

    def present(b: int) -> bool:
        return 0 < b < n and b % 4 in first

    parts = []
    for r in range(4):
        cells = np.arange(r, n, 4)
        beside = present(r) + present(r + 1)  # the same for every cell of the quarter
        weights = np.full(len(cells), (1.0 - 0.25 * beside) / n)
        parts.append((shutter_quantiles(scene.shutter, (cells + 0.5) / n), weights, r % 2))
    for f in families:
        b0, half = FAMILIES[f]
        b = np.arange(b0, n, 4)
        b = b[(b > 0) & (b < n)]
        parts.append((shutter_quantiles(scene.shutter, b / n), np.full(len(b), 0.5 / n), half))
    sums.add_all(parts)
    frame = sums.frame()
    raw = frame.stats["error_estimate"] / _accumulate.HALVES_FACTOR["stratified"]
    return raw, frame, sum(len(p[0]) for p in parts)


def scene_rows(seed: int, w: int, h: int, box_only: bool = False) -> list[dict]:
    scene = random_scene(seed, w, h)
    box = isinstance(scene.shutter, str) and scene.shutter == "box"
    # every shutter but a weights one (whose closed gaps the grids do not split); auto refines
    # under the box only, and the other shutters' rows say why
    if not A._moves(scene) or scene.rolling > 0.0 or isinstance(scene.shutter, np.ndarray):
        return []
    if box_only and not box:
        return []
    ref = mb.exact(scene).rgba.astype(np.float64)
    rows = []
    for n in COUNTS:
        row: dict = {"seed": seed, "size": f"{w}x{h}", "n": n, "shutter": "box" if box else "other"}
        for name, families in GRIDS.items():
            est, frame, count = refined(scene, n, families)
            row[name] = (est, rmse(over_background(frame, scene.background).rgba, ref), count)
        for count, name in ((n * 5 // 4, "fresh 1.25N"), (n * 3 // 2, "fresh 1.5N")):
            frame = A._Trials(scene, 1).accumulate(count)
            err = rmse(over_background(frame, scene.background).rgba, ref)
            row[name] = (frame.stats["error_estimate"], err, count)
        rows.append(row)
    return rows


def summary(rows: list[dict]) -> list[str]:
    rows = [r for r in rows if r["S"][1] > 1e-6]
    out = [f"{len(rows)} rows"]
    for g in GRIDS:
        raw = np.array([r[g][0] / r[g][1] for r in rows])
        f = 1.1 / np.median(raw)
        q = raw * f
        out.append(
            f"{g}: halves factor {f:.3f}, estimate / error p5 {np.percentile(q, 5):.2f} "
            f"p95 {np.percentile(q, 95):.2f}, within 0.5x-2x {np.mean((q >= 0.5) & (q <= 2)):.0%}"
        )
    # the factors auto ships (`HALVES_FACTOR`): each refined grid's 5th percentile of estimate /
    # error at the stratified grid's, with its shipped factor
    s5 = np.percentile([r["S"][0] * _accumulate.HALVES_FACTOR["stratified"] / r["S"][1] for r in rows], 5)
    for g in ("A", "AB"):
        f = s5 / np.percentile([r[g][0] / r[g][1] for r in rows], 5)
        q = np.array([r[g][0] * f / r[g][1] for r in rows])
        out.append(
            f"{g}: at the stratified grid's 5th percentile {s5:.2f}: factor {f:.3f}, median {np.median(q):.2f}"
        )
    for g in ("A", "AB", "fresh 1.25N", "fresh 1.5N"):
        r = np.array([row[g][1] / row["S"][1] for row in rows])
        out.append(
            f"{g}: error / S's, median {np.median(r):.3f} (p10 {np.percentile(r, 10):.3f}, p90 {np.percentile(r, 90):.3f})"
        )
    return out


def main(argv: list[str] | None = None) -> list[str]:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--sizes", default="96x72:60,192x144:40", help="WxH:scenes, comma-separated")
    p.add_argument("--first-seed", type=int, default=0)
    p.add_argument("--box", action="store_true", help="box-shutter scenes only")
    args = p.parse_args(argv)
    set_num_threads(1)
    rows = [
        row
        for seed, w, h in scene_specs(args.sizes, args.first_seed)
        for row in scene_rows(seed, w, h, args.box)
    ]
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / "rows.jsonl").write_text("".join(json.dumps(r) + "\n" for r in rows))
    lines = summary(rows)
    for kind in ("box", "other"):
        part = [r for r in rows if r.get("shutter") == kind and r["S"][1] > 1e-6]
        lines += [f"-- {kind} shutter:", *(summary(part) if part else ["no rows"])]
    print("\n".join(lines))
    return lines


if __name__ == "__main__":
    main(sys.argv[1:])
