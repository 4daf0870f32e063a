"""Tuning only (seeds < 100,000): candidate pilots for an analytic frame above ANALYTIC_OWN_PIXELS.

    python benches/tune_est4k.py SEED WxH [--own]

One scene, one size, in its own process: the analytic frame (render, no estimate), the limit
(cached, float32), and from the pilot errors: the 1080p pilot (no carry, the tail carried with
half or all its trend), the 160x120 pilot carried (the rule before), and with --own the frame as
its own pilot. Appends a JSON row to out/est4k/tune.jsonl."""

from __future__ import annotations

import json
import math
import resource
import sys
import time
from pathlib import Path

import numpy as np

import motionblur as mb
from motionblur.evaluation.random_scenes import random_scene
from motionblur.methods import _estimate as E

OUT = Path("out/est4k")


def rmse(a, b) -> float:
    return float(np.sqrt(np.mean(np.square(np.asarray(a, np.float64) - b))))


def _tail_trend(pixel_mse: np.ndarray) -> float:
    """``beta`` in [0, 1]: the typical MSE of ``n`` of these pixels grows as ``n**beta``, read
    from random sixteenths and quarters of them: `128` random orders (a fixed
    seed), each cut into 16 and into 4 disjoint parts, and the typical MSE of a part is the mean
    of the middle half of the parts' MSEs (a median of few parts jumps with the whole count of
    rare errors a part holds; this read moves by about 0.03 between seeds where that one moved
    by 0.16). 0 where every pixel is about as far off (or none is); 1, the steepest, where the
    squared errors are so heavy-tailed that a sixteenth typically holds none of them; a Pareto
    tail of index ``a`` in (1/2, 1) gives about ``1/a - 1``."""
    e2 = pixel_mse.ravel()
    n = e2.size
    order = np.random.default_rng(0).random((128, n)).argsort(axis=1)
    parts = {}
    for k in (16, 4):
        part = max(1, n // k)
        parts[k] = e2[order[:, : k * part]].reshape(-1, part).mean(axis=1)
    return _beta(e2, parts)


def tail_trend(pixel_mse, permutations=16) -> float:
    """_tail_trend's read with fewer random orders, one at a time (memory O(n))."""
    e2 = pixel_mse.ravel()
    n = e2.size
    rng = np.random.default_rng(0)
    parts = {16: [], 4: []}
    for _ in range(permutations):
        order = rng.permutation(n)
        for k in (16, 4):
            part = max(1, n // k)
            parts[k].append(e2[order[: k * part]].reshape(-1, part).mean(axis=1))
    return _beta(e2, {k: np.concatenate(v) for k, v in parts.items()})


def _beta(e2: np.ndarray, parts: dict) -> float:
    """``beta`` from the MSEs of the sixteenths (``parts[16]``) and quarters (``parts[4]``) of
    the pixels ``e2``: the typical MSE of each, the mean of the middle half of the sorted parts."""
    typical = []
    for k in (16, 4):
        mse = np.sort(parts[k])
        q = mse.size // 4
        typical.append(float(mse[q : mse.size - q].mean()))
    m16, m4 = typical
    if not m4 > 0.0:
        return 1.0 if e2.max() > 0.0 else 0.0
    if not m16 > 0.0:
        return 1.0
    return min(max(math.log(m4 / m16) / math.log(4.0), 0.0), 1.0)


def main() -> None:
    seed, size = int(sys.argv[1]), sys.argv[2]
    own = "--own" in sys.argv
    w, h = map(int, size.split("x"))
    scene = random_scene(seed, w, h)
    t = time.perf_counter()
    f = mb.render(scene, "analytic", error_estimate=False)
    row = {"seed": seed, "size": size, "render_s": time.perf_counter() - t}
    k = 4.0 / 3.0
    n = w * h
    for name, pixels in (("p1080", 1920 * 1080), ("p160", 160 * 120)) + ((("own", n),) if own else ()):
        t = time.perf_counter()
        p = E.pilot_errors(scene, "analytic", {}, pixels, f.rgba if name == "own" else None, per_pixel=True)
        row[name + "_s"] = time.perf_counter() - t
        t2 = time.perf_counter()
        beta = (
            (_tail_trend if p["pixel_mse"].size < 100_000 else tail_trend)(p["pixel_mse"])
            if p["scale"] < 1.0
            else 0.0
        )
        row[name + "_trend_s"] = time.perf_counter() - t2
        ratio = n / p["pixel_mse"].size
        row[name] = {"size": p["size"], "rmse43": p["rmse"] * k, "beta": beta, "ratio": ratio}
        pm = p["pixel_mse"].ravel()
        top = np.sort(pm)[::-1]
        row[name]["top1_share"] = float(top[0] / pm.sum()) if pm.sum() > 0 else 0.0
        del p
    path = OUT / "refs" / f"{seed}_{size}.npy"
    if path.exists():
        ref = np.load(path).astype(np.float64)
        row["limit_s"] = None
    else:
        t = time.perf_counter()
        ref32 = E.limit(scene).rgba
        row["limit_s"] = time.perf_counter() - t
        path.parent.mkdir(parents=True, exist_ok=True)
        np.save(path, ref32)
        ref = ref32.astype(np.float64)
    row["measured"] = rmse(f.rgba, ref)
    e2 = np.mean(np.square(f.rgba.astype(np.float64) - ref), axis=-1).ravel()
    row["frame_top1_share"] = float(e2.max() / e2.sum()) if e2.sum() > 0 else 0.0
    row["maxrss_mib"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    m = row["measured"]
    for name in ("p1080", "p160", "own"):
        if name in row and m > 0:
            r = row[name]
            r["none"] = r["rmse43"] / m
            r["half"] = r["rmse43"] * r["ratio"] ** (r["beta"] / 4) / m
            r["full"] = r["rmse43"] * r["ratio"] ** (r["beta"] / 2) / m
    with open(OUT / "tune.jsonl", "a") as fh:
        fh.write(json.dumps(row) + "\n")
    print(json.dumps(row))


if __name__ == "__main__":
    main()
