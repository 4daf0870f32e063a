"""Running the methods for the report: timings and errors.

Timings are wall-clock, the best of ``repeat`` runs after one warm-up run. In the sweeps the
static layer is kept across frames (as a real-time loop keeps it while the static objects and
the camera do not change), for every method alike.
"""

from __future__ import annotations

import inspect
import math
import time
from pathlib import Path

import numpy as np

from ..methods import clear_static_cache
from ..render import METHODS, render
from . import metrics
from . import reference as ref_mod
from .compare import equal_error

__all__ = ["sweep_scene", "reference_for", "paired_factor", "paired_times", "pyrender_comparison"]


def _best_ms(fn, repeat: int):
    best, out = float("inf"), None
    for i in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        dt = time.perf_counter() - t0
        best = min(best, dt)
        if i == 0 and dt > 2.0:  # one timing is enough for the slow runs
            break
    return best * 1e3, out


def reference_for(name: str, scene, times: int, spp: int, cache: Path, seed: int = 0):
    """(H,W,4) float32 Mitsuba reference of ``scene``, cached in ``cache`` as .npy."""
    cam = scene.camera
    key = f"{name}_{cam.width}x{cam.height}_K{times}_S{spp}_seed{seed}_{ref_mod.mitsuba_variant()}"
    path = Path(cache) / f"{key}.npy"
    if path.exists():
        return np.load(path), 0.0
    t0 = time.perf_counter()
    frame = ref_mod.mitsuba(scene, times=times, spp=spp, seed=seed, progress=True)
    path.parent.mkdir(parents=True, exist_ok=True)
    np.save(path, frame.rgba)
    return frame.rgba, (time.perf_counter() - t0) * 1e3


def _label(opts: dict) -> str:
    return " ".join(f"{k}={v}" for k, v in opts.items()) or "-"


def _with_aa(fn, opts: dict, aa) -> dict:
    """``opts`` plus ``aa`` when the method takes that option and the set does not fix it."""
    if aa is None or "aa" in opts:
        return dict(opts)
    try:
        params = inspect.signature(fn).parameters
    except (TypeError, ValueError):
        return dict(opts)
    return {**opts, "aa": aa} if "aa" in params else dict(opts)


def sweep_scene(name: str, scene, ref: np.ndarray, repeat=3, methods=None, flip=True, images=None, aa=None):
    """Rows (dicts) for every applicable method and option set on one scene (``aa`` added to the
    option sets of methods that take it)."""
    rows = []
    for mname, spec in METHODS.items():
        if methods is not None and mname not in methods:
            continue
        if not spec.applies(scene):
            continue
        for opts in (_with_aa(spec.fn, o, aa) for o in spec.sweep):
            render(scene, mname, **opts)  # warm caches (adjacency, first-call costs)
            ms, frame = _best_ms(lambda: render(scene, mname, **opts), repeat)  # noqa: B023
            row = {
                "scene": name,
                "method": mname,
                "options": _label(opts),
                "_opts": opts,
                "ms": ms,
                "rmse": metrics.rmse(frame, ref),
                "psnr": metrics.psnr(frame, ref),
                "flip": metrics.flip(frame, ref) if flip else float("nan"),
                "coverage_error": metrics.coverage_error(frame, ref),
            }
            rows.append(row)
            if images is not None:
                images[(name, mname, row["options"])] = frame
    return rows


def paired_factor(scene, rows, metric="rmse", rounds=7, burst=3):
    """Re-time the motion_volume option set with the best equal-error factor in the sweep (the
    setting a user would pick; the most accurate one when every factor is only a bound) against
    the two accumulation sample counts whose errors bracket it, round-robin (``rounds`` times,
    ``burst`` consecutive frames of each per round, best of all), so that both sides see the same
    machine load, each in its steady state (a real-time loop renders one method frame after
    frame); interpolate accumulation's time
    log-log at that error. Returns a dict (mv options, its error and ms, N_lo, N_hi, accumulation
    ms, bound, factor) or None when there is nothing to compare."""
    mv = [r for r in rows if r["method"] == "motion_volume" and r[metric] > 0 and math.isfinite(r[metric])]
    acc = sorted(
        (r for r in rows if r["method"] == "accumulation" and "samples" in r["_opts"]),
        key=lambda r: r["_opts"]["samples"],
    )
    if not mv or not acc:
        return None
    sweep = [(f, r) for r, _, bound, f in equal_error(rows, metric=metric) if bound == ""]
    m = max(sweep, key=lambda x: x[0])[1] if sweep else min(mv, key=lambda r: r[metric])
    e = m[metric]
    worse = [r for r in acc if r[metric] >= e]
    better = [r for r in acc if r[metric] < e]
    lo = max(worse, key=lambda r: r["_opts"]["samples"]) if worse else None
    hi = min(better, key=lambda r: r["_opts"]["samples"]) if better else None
    jobs = [("motion_volume", m)] + [("accumulation", r) for r in (lo, hi) if r is not None]
    best = [float("inf")] * len(jobs)
    for _ in range(rounds):
        for j, (method, r) in enumerate(jobs):
            # a burst of frames per job: a real-time loop renders one method frame after frame,
            # so a frame that follows another method's (cold caches) is not its steady cost
            for _ in range(burst):
                t0 = time.perf_counter()
                render(scene, method, error_estimate=False, **r["_opts"])
                best[j] = min(best[j], (time.perf_counter() - t0) * 1e3)
    t_mv = best[0]
    times = dict(zip([id(r) for _, r in jobs[1:]], best[1:]))
    if lo is not None and hi is not None:
        t_lo, t_hi = times[id(lo)], times[id(hi)]
        e_lo, e_hi = lo[metric], hi[metric]
        u = (math.log(e_lo) - math.log(e)) / (math.log(e_lo) - math.log(e_hi)) if e_lo != e_hi else 0.0
        t_acc, bound = math.exp(math.log(t_lo) + u * (math.log(t_hi) - math.log(t_lo))), ""
    elif hi is not None:  # even N = 1 is as accurate: its time bounds the equal-error time
        t_acc, bound = times[id(hi)], "<="
    else:
        t_acc, bound = times[id(lo)], ">="
    return {
        "options": m["options"],
        "error": e,
        "mv_ms": t_mv,
        "n_lo": lo["_opts"]["samples"] if lo else None,
        "n_hi": hi["_opts"]["samples"] if hi else None,
        "acc_ms": t_acc,
        "bound": bound,
        "factor": t_acc / t_mv,
    }


def paired_times(scene, jobs, rounds: int = 5, burst: int = 3) -> list[float]:
    """Best ms of each ``(method, options)`` of ``jobs`` on ``scene``, timed round-robin
    (``rounds`` rounds of ``burst`` consecutive frames of each, after one warm-up frame each), so
    that every job sees the same machine load, each in its steady state; each render's own cost,
    without the pilot error estimate ``render`` adds by default."""
    for method, opts in jobs:
        render(scene, method, error_estimate=False, **opts)
    best = [float("inf")] * len(jobs)
    for _ in range(rounds):
        for j, (method, opts) in enumerate(jobs):
            for _ in range(burst):
                t0 = time.perf_counter()
                render(scene, method, error_estimate=False, **opts)
                best[j] = min(best[j], (time.perf_counter() - t0) * 1e3)
    return best


def pyrender_comparison(name, scene, ref, repeat):
    """Accumulation (N = 16, static layer drawn once per frame) against 16-pose accumulation on
    pyrender, on the same scene: the best of ``repeat`` timings of each and their RMSE."""
    ref_mod.pyrender(scene, samples=16)  # context creation and shader compilation
    peer_ms, peer = _best_ms(lambda: ref_mod.pyrender(scene, samples=16), repeat)

    def ours_once():  # the static layer drawn once per frame, not kept from the frame before
        clear_static_cache()
        return render(scene, "accumulation", samples=16, error_estimate=False)

    ours_ms, ours = _best_ms(ours_once, repeat)
    return {
        "scene": name,
        "ours_ms": ours_ms,
        "pyrender_ms": peer_ms,
        "factor": peer_ms / ours_ms,
        "ours_rmse": metrics.rmse(ours, ref),
        "pyrender_rmse": metrics.rmse(peer, ref),
    }
