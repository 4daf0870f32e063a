"""The speed-against-error report: every registered method on every built-in scene.

For each scene of :data:`motionblur.SCENES` and each method of :data:`motionblur.METHODS` whose
``applies(scene)`` is true, every option set of the method's ``sweep`` is rendered; the best of
``repeat`` wall-clock timings of :func:`motionblur.render` and the error against the Mitsuba
time-sampled reference (RMSE over premultiplied RGBA, PSNR, FLIP, signed coverage error) are
recorded. References are cached under ``<out>/references/`` (keyed by scene, size, K, spp, seed
and the Mitsuba variant). Outputs in ``<out>``: ``results.csv``, ``results.md`` (a table per
scene, the Pareto front marked, and the two comparisons below) and ``pareto_<scene>.png``
(error against time, log-log, the front drawn).

Comparisons, measured in the same run:

- motion_volume against accumulation at equal error: for each motion-volume option set, the time
  accumulation needs for the same RMSE, interpolated log-log between the two N that bracket it
  (if even N = 1 is better, its time is an upper bound and the factor is marked ``<=``; if even
  the largest N is worse, ``>=``). The factor is accumulation's time over motion_volume's.
- every method against accumulation at equal time (:func:`equal_time`): for each run of a
  method, accumulation's RMSE in the same time, interpolated log-log on accumulation's error
  against time, beside the method's own.
- accumulation with the static layer drawn once (N = 16) against 16-pose accumulation on pyrender
  (every object at every pose, :func:`motionblur.reference.pyrender`), on the same scene and size;
  ours at ``aa=1`` like pyrender under OSMesa, its static layer drawn once per frame (the cache
  cleared before every run).

In the sweeps the static layer is kept across frames (as a real-time loop keeps it while the
static objects and the camera do not change), for every method alike; timings are the best of
``repeat`` runs after one warm-up run.
"""

from __future__ import annotations

import csv
import inspect
import json
import math
import os
import platform
import time
from pathlib import Path

import numpy as np

from . import metrics
from . import reference as ref_mod
from .methods import clear_static_cache
from .render import METHODS, render
from .scenes_builtin import SCENES

__all__ = ["run", "sweep_scene", "reference_for", "pareto_front", "equal_error", "equal_time", "main"]


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


def pareto_front(rows) -> list[bool]:
    """Whether each row is on the Pareto front of (ms, rmse): no other row is at least as fast
    and as accurate and strictly better in one."""
    out = []
    for r in rows:
        dominated = any(
            (o["ms"] <= r["ms"] and o["rmse"] <= r["rmse"]) and (o["ms"] < r["ms"] or o["rmse"] < r["rmse"])
            for o in rows
        )
        out.append(not dominated)
    return out


def equal_error(rows, method="motion_volume", baseline="accumulation", metric="rmse"):
    """For each ``method`` row of one scene: (row, baseline ms at the same error, bound, factor);
    bound is ``""``, ``"<="`` or ``">="`` (see the module docs). ``metric``: ``"rmse"`` or
    ``"flip"`` (any positive error column of the rows)."""
    base = sorted((r for r in rows if r["method"] == baseline), key=lambda r: r["ms"])
    if not base:
        return []
    # errors of the baseline as its cost grows, made monotone (the best error reached so far)
    pts, best = [], float("inf")
    for r in base:
        if r[metric] < best:
            best = r[metric]
            pts.append((r["ms"], r[metric]))
    out = []
    for r in rows:
        if r["method"] != method:
            continue
        e = r[metric]
        if not (e > 0 and math.isfinite(e)):
            continue
        if e >= pts[0][1]:
            t, bound = pts[0][0], "<="
        elif e < pts[-1][1]:
            t, bound = pts[-1][0], ">="
        else:
            for (t0, e0), (t1, e1) in zip(pts, pts[1:]):
                if e1 <= e < e0 or e == e0:
                    u = (math.log(e0) - math.log(e)) / (math.log(e0) - math.log(e1)) if e0 != e1 else 0.0
                    t = math.exp(math.log(t0) + u * (math.log(t1) - math.log(t0)))
                    bound = ""
                    break
        out.append((r, t, bound, t / r["ms"]))
    return out


def _envelope(rows, baseline: str, metric: str):
    """(ms, error) of the ``baseline`` rows sorted by time, kept only where the error improves
    (the best error reached for that time or less)."""
    pts, best = [], float("inf")
    for r in sorted((r for r in rows if r["method"] == baseline), key=lambda r: r["ms"]):
        e = r[metric]
        if math.isfinite(e) and e > 0 and e < best:
            best = e
            pts.append((r["ms"], e))
    return pts


def equal_time(rows, methods=None, baseline="accumulation", metric="rmse"):
    """Each method's error beside the baseline's at the same time, for the rows of one scene.

    For every row of a method other than ``baseline`` (or of ``methods``): ``(row, baseline
    error at the row's time, bound, ratio)``. The baseline's error against time is its lower
    envelope (the best error reached in that time or less), interpolated log-log between the
    two timings that bracket the row's time. If the row is faster than the fastest baseline
    run, the baseline cannot be run in that time: its fastest error is a lower bound (``">="``);
    if slower than the slowest, the slowest's error is an upper bound (``"<="``); else ``""``.
    ``ratio`` = baseline error / the row's error (> 1: the method is more accurate than the
    baseline in the same time)."""
    pts = _envelope(rows, baseline, metric)
    if not pts:
        return []
    out = []
    for r in rows:
        if r["method"] == baseline or (methods is not None and r["method"] not in methods):
            continue
        e, t = r[metric], r["ms"]
        if not (e > 0 and math.isfinite(e) and t > 0):
            continue
        if t < pts[0][0]:
            eb, bound = pts[0][1], ">="
        elif t >= pts[-1][0]:
            eb, bound = pts[-1][1], "<=" if t > pts[-1][0] else ""
        else:
            for (t0, e0), (t1, e1) in zip(pts, pts[1:]):
                if t0 <= t < t1:
                    u = (math.log(t) - math.log(t0)) / (math.log(t1) - math.log(t0))
                    eb, bound = math.exp(math.log(e0) + u * (math.log(e1) - math.log(e0))), ""
                    break
        out.append((r, eb, bound, eb / e))
    return out


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
                render(scene, method, **r["_opts"])
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


def _pyrender_comparison(name, scene, ref, repeat):
    ref_mod.pyrender(scene, samples=16)  # context creation and shader compilation
    peer_ms, peer = _best_ms(lambda: ref_mod.pyrender(scene, samples=16), repeat)

    def ours_once():  # the static layer drawn once per frame, not kept from the frame before
        clear_static_cache()
        return render(scene, "accumulation", samples=16)

    ours_ms, ours = _best_ms(ours_once, repeat)
    return {
        "scene": name,
        "ours_ms": ours_ms,
        "pyrender_ms": peer_ms,
        "factor": peer_ms / ours_ms,
        "ours_rmse": metrics.rmse(ours, ref),
        "pyrender_rmse": metrics.rmse(peer, ref),
    }


def _plot(name, rows, front, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.4, 4.4), dpi=110)
    for m in sorted({r["method"] for r in rows}):
        sel = [r for r in rows if r["method"] == m]
        ax.scatter([r["ms"] for r in sel], [r["rmse"] for r in sel], label=m, s=22)
    fr = sorted((r for r, f in zip(rows, front) if f), key=lambda r: r["ms"])
    ax.plot([r["ms"] for r in fr], [r["rmse"] for r in fr], "k--", lw=1, label="Pareto front")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("time per frame (ms, best of runs)")
    ax.set_ylabel("RMSE against Mitsuba (premultiplied RGBA)")
    ax.set_title(f"{name}: error against time")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def _machine() -> str:
    return f"{platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}"


def _equal_error_table(comparisons: dict, metric: str, label: str, fmt: str) -> list[str]:
    """Markdown lines: per scene the most accurate motion_volume row by ``metric`` and its
    :func:`equal_error` factor, and the best factor over all the scene's option sets."""
    most = "most accurate motion_volume" + ("" if metric == "rmse" else f" ({label})")
    lines = [
        f"| scene | {most} | its ms | its {label} | accumulation ms at that {label} | factor | best factor (options) |",
        "|---|---|---:|---:|---:|---:|---|",
    ]
    for scene, comp in comparisons.items():
        if not comp:
            lines.append(f"| {scene} | (not applicable) | | | | | |")
            continue
        r, t, bound, factor = min(comp, key=lambda c: c[0][metric])
        rb, _tb, bb, fb = max(comp, key=lambda c: c[3])
        lines.append(
            f"| {scene} | {r['options']} | {r['ms']:.2f} | {r[metric]:{fmt}} | {bound}{t:.2f} | {bound}{factor:.2f} | "
            f"{bb}{fb:.2f} ({rb['options']}, {label} {rb[metric]:.4f}) |"
        )
    return [*lines, ""]


def _markdown(
    rows, fronts, comparisons, pyrender_rows, settings, flip_comparisons=None, paired=None, equal_times=None
) -> str:
    lines = ["# Speed against error", ""]
    lines.append(
        f"Machine: {_machine()} (shared with other jobs: timings are best of {settings['repeat']}). "
        f"Images {settings['width']}x{settings['height']}, methods at aa = {settings['aa']} (spatial samples per pixel per axis); reference: Mitsuba {settings['variant']}, "
        f"K = {settings['times']} shutter times x {settings['spp']} spp. Error: RMSE over premultiplied RGBA; "
        "coverage error is signed (alpha summed over the image, relative)."
    )
    lines.append("")
    for scene in dict.fromkeys(r["scene"] for r in rows):
        sel = [(r, f) for r, f in zip(rows, fronts) if r["scene"] == scene]
        lines += [
            f"## {scene}",
            "",
            "| method | options | ms | RMSE | PSNR dB | FLIP | coverage err | Pareto |",
            "|---|---|---:|---:|---:|---:|---:|:-:|",
        ]
        for r, f in sorted(sel, key=lambda x: x[0]["ms"]):
            lines.append(
                f"| {r['method']} | {r['options']} | {r['ms']:.2f} | {r['rmse']:.5f} | {r['psnr']:.2f} | "
                f"{r['flip']:.4f} | {r['coverage_error']:+.3f} | {'*' if f else ''} |"
            )
        lines.append("")
    if equal_times:
        lines += ["## Each method against accumulation at equal time", ""]
        lines += [
            "Accumulation's RMSE in the time each run took (its best RMSE reached in that time or less, "
            "interpolated log-log between the two accumulation timings that bracket it; `>=`: faster than "
            "accumulation with N = 1, whose RMSE is then a lower bound; `<=`: slower than the largest N). "
            "Ratio = accumulation's RMSE / the method's (> 1: the method is more accurate in the same time).",
            "",
            "| scene | method | options | ms | RMSE | accumulation RMSE at that time | ratio |",
            "|---|---|---|---:|---:|---:|---:|",
        ]
        for scene, comp in equal_times.items():
            if not comp:
                lines.append(f"| {scene} | (no method besides accumulation) | | | | | |")
                continue
            for r, eb, bound, ratio in sorted(comp, key=lambda c: (c[0]["method"], c[0]["ms"])):
                lines.append(
                    f"| {scene} | {r['method']} | {r['options']} | {r['ms']:.2f} | {r['rmse']:.5f} | "
                    f"{bound}{eb:.5f} | {bound}{ratio:.2f} |"
                )
        lines.append("")
    lines += ["## motion_volume against accumulation at equal error", ""]
    lines += [
        "Factor = accumulation's time for the same RMSE / motion_volume's time (> 1: motion_volume is faster).",
        "",
    ]
    lines += [
        "Per scene: the most accurate motion_volume option set, and the best factor over all its option sets.",
        "",
    ]
    lines += _equal_error_table(comparisons, "rmse", "RMSE", ".5f")
    if paired:
        lines += [
            "Re-timed in pairs (the motion_volume option set with the best factor in the sweep above, or the most "
            "accurate one when every factor there is a bound, and the two accumulation sample counts whose RMSE "
            "brackets it, round-robin, 3 consecutive frames of each per round, best of all), so both sides see the "
            "same load, each in its steady state; this is the headline factor:",
            "",
            "| scene | motion_volume options | RMSE | motion_volume ms | accumulation N bracket | "
            "accumulation ms at that RMSE | factor |",
            "|---|---|---:|---:|---|---:|---:|",
        ]
        for scene, p in paired.items():
            if p is None:
                lines.append(f"| {scene} | (not applicable) | | | | | |")
                continue
            lines.append(
                f"| {scene} | {p['options']} | {p['error']:.5f} | {p['mv_ms']:.2f} | {p['n_lo']}..{p['n_hi']} | "
                f"{p['bound']}{p['acc_ms']:.2f} | {p['bound']}{p['factor']:.2f} |"
            )
        lines.append("")
    if flip_comparisons and any(flip_comparisons.values()):
        lines += ["The same at equal FLIP (NVIDIA's perceptual difference):", ""]
        lines += _equal_error_table(flip_comparisons, "flip", "FLIP", ".4f")
    if pyrender_rows:
        lines += ["## accumulation (static drawn once, N = 16) against 16-pose pyrender accumulation", ""]
        lines += [
            "Ours at aa = 1 (pyrender under OSMesa has no multisampling), static layer drawn once per frame (no cache).",
            "",
        ]
        lines += [
            "| scene | ours ms | pyrender ms | factor (pyrender / ours) | ours RMSE | pyrender RMSE |",
            "|---|---:|---:|---:|---:|---:|",
        ]
        for p in pyrender_rows:
            lines.append(
                f"| {p['scene']} | {p['ours_ms']:.2f} | {p['pyrender_ms']:.2f} | {p['factor']:.2f} | "
                f"{p['ours_rmse']:.5f} | {p['pyrender_rmse']:.5f} |"
            )
        lines += [
            "",
            "pyrender draws lambert objects FLAT (its lighting is not lambert), so its RMSE on lit scenes is not comparable.",
        ]
    return "\n".join(lines) + "\n"


def run(
    out="out/bench",
    scenes=None,
    width: int = 320,
    height: int = 240,
    times: int = 256,
    spp: int = 4,
    repeat: int = 3,
    methods=None,
    sweeps=None,
    flip: bool = True,
    pyrender_peer: bool = True,
    save_images: bool = False,
    aa: int | None = 2,
    log=print,
) -> dict:
    """Run the report and write it to ``out``; returns ``{"rows", "comparisons", "pyrender", "paths"}``.

    ``scenes``: names from SCENES (default all); ``sweeps``: optional ``{method: [options, ...]}``
    replacing the registered sweeps (the demo's small version); ``methods``: restrict to these;
    ``aa``: spatial samples per pixel per axis given to every method that takes ``aa`` (2 by
    default: with one sample per pixel the aliasing of long static edges, about 0.017 RMSE on the
    cube scene, hides the motion-blur error the report is about). The pyrender comparison runs
    ours at ``aa=1``, as pyrender under OSMesa has no multisampling.
    """
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    names = list(SCENES) if scenes is None else list(scenes)
    saved = {}
    if sweeps:
        for m, s in sweeps.items():
            saved[m] = METHODS[m].sweep
            METHODS[m].sweep = [dict(o) for o in s]
    rows, comparisons, flip_comparisons, pyr, paired, equal_times = [], {}, {}, [], {}, {}
    images = {} if save_images else None
    try:
        for name in names:
            scene = SCENES[name](width=width, height=height)
            ref, ref_ms = reference_for(name, scene, times, spp, out / "references")
            log(f"[{name}] reference {'cached' if ref_ms == 0 else f'{ref_ms / 1e3:.1f} s'}")
            if save_images:
                from .raster import Frame

                h, w = ref.shape[:2]
                Frame(ref, np.zeros((h, w)), np.zeros((h, w), np.int32), np.zeros((h, w, 2))).save_png(
                    out / "images" / f"{name}_reference.png"
                )
            scene_rows = sweep_scene(name, scene, ref, repeat, methods, flip, images, aa)
            rows += scene_rows
            comparisons[name] = equal_error(scene_rows)
            equal_times[name] = equal_time(scene_rows)
            flip_comparisons[name] = equal_error(scene_rows, metric="flip") if flip else []
            paired[name] = paired_factor(scene, scene_rows, "rmse", max(3, repeat))
            if pyrender_peer:
                pyr.append(_pyrender_comparison(name, scene, ref, repeat))
            for r in scene_rows:
                log(f"  {r['method']:<14} {r['options']:<28} {r['ms']:9.2f} ms  RMSE {r['rmse']:.5f}")
    finally:
        for m, s in saved.items():
            METHODS[m].sweep = s
    fronts = []
    for name in names:
        sel = [r for r in rows if r["scene"] == name]
        f = pareto_front(sel)
        fronts += f
        _plot(name, sel, f, out / f"pareto_{name}.png")
    with open(out / "results.csv", "w", newline="") as fh:
        keys = [k for k in rows[0] if not k.startswith("_")]
        wr = csv.DictWriter(fh, fieldnames=[*keys, "pareto"])
        wr.writeheader()
        for r, f in zip(rows, fronts):
            wr.writerow({**{k: r[k] for k in keys}, "pareto": int(f)})
    settings = dict(
        width=width,
        height=height,
        times=times,
        spp=spp,
        repeat=repeat,
        aa=aa,
        variant=ref_mod.mitsuba_variant(),
    )
    (out / "results.md").write_text(
        _markdown(rows, fronts, comparisons, pyr, settings, flip_comparisons, paired, equal_times)
    )
    (out / "settings.json").write_text(json.dumps({**settings, "machine": _machine()}, indent=1))
    if images:
        for (scene, m, opts), frame in images.items():
            frame.save_png(out / "images" / f"{scene}_{m}_{opts.replace(' ', '_').replace('=', '')}.png")
    return {
        "rows": rows,
        "comparisons": comparisons,
        "flip_comparisons": flip_comparisons,
        "paired": paired,
        "equal_time": equal_times,
        "pyrender": pyr,
        "paths": {"md": out / "results.md", "csv": out / "results.csv"},
    }


def main(argv=None) -> int:
    import argparse

    p = argparse.ArgumentParser(prog="python -m motionblur bench", description=__doc__.splitlines()[0])
    p.add_argument("--out", default="out/bench")
    p.add_argument("--scenes", nargs="*", default=None, help=f"subset of {', '.join(SCENES)}")
    p.add_argument("--size", default="320x240", help="WxH")
    p.add_argument("--aa", type=int, default=2, help="spatial samples per pixel per axis for every method")
    p.add_argument("--times", type=int, default=256, help="Mitsuba shutter times K")
    p.add_argument("--spp", type=int, default=4, help="Mitsuba samples per pixel per time")
    p.add_argument("--repeat", type=int, default=3)
    p.add_argument("--no-flip", action="store_true")
    p.add_argument("--quick", action="store_true", help="160x120, K = 64, one timing")
    a = p.parse_args(argv)
    w, h = (int(x) for x in a.size.lower().split("x"))
    if a.quick:
        w, h, a.times, a.repeat = 160, 120, 64, 1
    res = run(a.out, a.scenes, w, h, a.times, a.spp, a.repeat, flip=not a.no_flip, aa=a.aa)
    md = res["paths"]["md"].read_text()
    start = md.find("## Each method against")
    print(md[start if start >= 0 else md.index("## motion_volume against") :])
    print(f"written: {res['paths']['md']}, {res['paths']['csv']}, {a.out}/pareto_*.png")
    return 0
