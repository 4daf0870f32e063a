"""Writing the report: the markdown tables, the csv, the settings, and the pictures (Pareto plots
and per-scene sheets, drawn by [`figures`][motionblur.evaluation.figures])."""

from __future__ import annotations

import csv
import json
import os
import platform
from pathlib import Path

import numpy as np

from ..raster import Frame
from .figures import pareto_plot, sheet
from .sweep import _label

__all__ = ["write", "save_reference", "matched"]


def limit_label(settings) -> str:
    """The own-limit reference of a run's ``settings``, in words."""
    n = settings.get("limit_samples")
    return "the exact time integral (motionblur.exact)" if n is None else f"accumulation, N = {n}"


def write(
    out: Path,
    names,
    rows,
    fronts,
    settings,
    *,
    comparisons,
    flip_comparisons,
    paired,
    equal_times,
    pyrender_rows,
    fronts_limit=None,
    frames=None,
    references=None,
    landings=None,
    save_images=False,
    images=None,
) -> dict:
    """Write the report into ``out``: ``pareto_<scene>.png`` per scene of ``names`` (error
    against both references, [`figures.pareto_plot`][motionblur.evaluation.figures.pareto_plot]), ``results.csv`` (the rows, ``fronts``
    and ``fronts_limit`` marking the Pareto fronts against Mitsuba and against the own limit),
    ``results.md``, ``settings.json`` and, given ``frames`` ({(scene, method, options): rgba}) and
    ``references`` ({scene: {"mitsuba": rgba, "limit": rgba}}), ``sheet_<scene>.png``: both
    references and, per method, its most accurate option set (own-limit RMSE) within the matched
    time (`matched`), labelled with method, options, ms and both RMSEs (against Mitsuba,
    then against the own limit: the two reference tiles say so); with
    ``save_images`` every frame under ``images/``. ``images`` ({key: Frame}) is the old form of
    ``frames``. Returns the paths written."""
    if images:
        frames = {**(frames or {}), **{k: f.rgba for k, f in images.items()}}
    fronts_limit = fronts_limit or [False] * len(rows)
    paths = {"md": out / "results.md", "csv": out / "results.csv"}
    for name in names:
        sel = [(r, f, g) for r, f, g in zip(rows, fronts, fronts_limit) if r["scene"] == name]
        paths[f"pareto_{name}"] = out / f"pareto_{name}.png"
        pareto_plot(name, [r for r, _, _ in sel], [f for _, f, _ in sel], paths[f"pareto_{name}"],
                    front_limit=[g for _, _, g in sel])  # fmt: skip
    with open(out / "results.csv", "w", newline="") as fh:
        keys = list(dict.fromkeys(k for r in rows for k in r if not k.startswith("_")))
        wr = csv.DictWriter(fh, fieldnames=[*keys, "pareto", "pareto_limit"], restval="")
        wr.writeheader()
        for r, f, g in zip(rows, fronts, fronts_limit):
            wr.writerow({**{k: r[k] for k in keys if k in r}, "pareto": int(f), "pareto_limit": int(g)})
    paths["md"].write_text(
        _markdown(rows, fronts, comparisons, pyrender_rows, settings, flip_comparisons, paired, equal_times)
        + _auto_markdown(landings or {}, rows, settings)
    )
    (out / "settings.json").write_text(json.dumps({**settings, "machine": _machine()}, indent=1))
    if frames and save_images:
        for (scene, m, opts), rgba in frames.items():
            _frame(rgba).save_png(
                out / "images" / f"{scene}_{m}_{opts.replace(' ', '_').replace('=', '')}.png"
            )
    if frames:
        for name in names:
            tiles = []
            ref = (references or {}).get(name, {})
            if "mitsuba" in ref:
                tiles.append(
                    (
                        f"reference: Mitsuba\nK = {settings['times']} x {settings['spp']} spp\n"
                        "each image's 1st RMSE is against this",
                        ref["mitsuba"],
                    )
                )
            if "limit" in ref:
                tiles.append(
                    (
                        f"reference: own limit\n{limit_label(settings)}\neach image's 2nd RMSE is against this",
                        ref["limit"],
                    )
                )
            for r in matched([r for r in rows if r["scene"] == name])[1]:
                rgba = frames.get((name, r["method"], r["options"]))
                if rgba is not None:
                    tiles.append((f"{r['method']}\n{r['options']}\n{r['ms']:.1f} ms  {_errors(r)}", rgba))
            if tiles:
                paths[f"sheet_{name}"] = out / f"sheet_{name}.png"
                sheet(tiles, paths[f"sheet_{name}"])
    return paths


def _errors(r) -> str:
    """A sheet label's error: the RMSE against Mitsuba, then against the own limit (the two
    reference tiles say which is which), both over premultiplied linear RGBA."""
    if "rmse_limit" in r and r["rmse_limit"] == r["rmse_limit"]:
        return f"RMSE {r['rmse']:.4f} Mitsuba / {r['rmse_limit']:.4f} own"
    return f"RMSE {r['rmse']:.5f} Mitsuba"


def _frame(rgba) -> Frame:
    h, w = rgba.shape[:2]
    return Frame(rgba, np.zeros((h, w)), np.zeros((h, w), np.int32), np.zeros((h, w, 2)))


def matched(rows) -> tuple[float, list]:
    """``(T, picks)`` for one scene's rows: the matched time T is the ``auto`` row's time when
    there is one, else the median of the rows' times; each method's pick is its most accurate row
    (RMSE against the own limit, or against Mitsuba when the rows have no other) taking at most T,
    or its fastest row when none does; ``auto``'s row first."""
    if not rows:
        return 0.0, []
    metric = "rmse_limit" if all("rmse_limit" in r for r in rows) else "rmse"
    autos = [r for r in rows if r["method"] == "auto"]
    t = autos[0]["ms"] if autos else float(np.median([r["ms"] for r in rows]))
    picks = autos[:1]
    for m in dict.fromkeys(r["method"] for r in rows if r["method"] != "auto"):
        rs = [r for r in rows if r["method"] == m]
        within = [r for r in rs if r["ms"] <= t * 1.0001]
        picks.append(min(within, key=lambda r: r[metric]) if within else min(rs, key=lambda r: r["ms"]))
    return t, picks


def save_reference(out: Path, name: str, ref: np.ndarray) -> None:
    """The reference image of scene ``name`` as ``images/<name>_reference.png``."""
    _frame(ref).save_png(out / "images" / f"{name}_reference.png")


def _ratio(landing: dict) -> float:
    """The headline ratio of a landing: re-timed in pairs when it was, else from the sweep."""
    return landing.get("paired_ratio", landing["ratio"])


def _plan_label(plan: dict) -> str:
    """The render ``auto`` kept (its ``stats["plan"]["kept"]``) and how many it made (timing
    pilots left out), e.g. ``accumulation samples=8 (1 render)``; ``?`` without a plan."""
    kept = plan.get("kept")
    if not kept:
        return "?"
    renders = sum(1 for t in plan.get("tried", []) if "pilot" not in t.get("options", {}))
    opts = _label(kept.get("options", {}))
    label = kept["method"] if opts in ("", "-") else f"{kept['method']} {opts}"
    return f"{label} ({renders} render{'s' if renders != 1 else ''})"


def _auto_markdown(landings: dict, rows, settings) -> str:
    if not landings:
        return ""
    tol = settings.get("tolerance")
    lines = ["", "## auto against the Pareto front", ""]
    lines += [
        f"`auto` at its default tolerance (RMSE {tol} against the own limit). The front at auto's error = the "
        "fastest swept run at least as accurate (own-limit RMSE) as auto's frame; ratio = auto's ms / its ms "
        "(target <= 1.25), from the sweep's timings and re-timed in pairs (auto and that run round-robin, "
        "5 rounds of 3 frames each, best of all, both under the same load: the headline). The plan is the "
        "render auto kept, and how many renders it made.",
        "",
        "| scene | plan | auto ms | own-limit RMSE | RMSE vs Mitsuba | front run at that error | its ms | ratio | "
        "in pairs: auto / front ms | ratio | meets tolerance |",
        "|---|---|---:|---:|---:|---|---:|---:|---|---:|:-:|",
    ]
    for r in (r for r in rows if r["method"] == "auto"):
        lg = landings.get(r["scene"])
        if lg is None:
            continue
        pa, pf = lg.get("paired_auto_ms", float("nan")), lg.get("paired_front_ms", float("nan"))
        lines.append(
            f"| {r['scene']} | {_plan_label(r.get('_plan', {}))} | {r['ms']:.2f} | {r['rmse_limit']:.5f} | {r['rmse']:.5f} | "
            f"{lg.get('front', '')} | {lg['front_ms']:.2f} | {lg['ratio']:.2f} | {pa:.2f} / {pf:.2f} | {_ratio(lg):.2f} | "
            f"{'yes' if lg['meets'] else 'no'} |"
        )
    n = len(landings)
    within = sum(1 for x in landings.values() if _ratio(x) <= 1.25)
    meets = sum(1 for x in landings.values() if x["meets"])
    lines += [
        "",
        f"Within 1.25x of the front (re-timed in pairs): {within} of {n} scenes; tolerance met: {meets} of {n}.",
        "",
    ]
    return "\n".join(lines) + "\n"


def _machine() -> str:
    return f"{platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}"


def _equal_error_table(comparisons: dict, metric: str, label: str, fmt: str) -> list[str]:
    """Markdown lines: per scene the most accurate motion_volume row by ``metric`` and its
    `equal_error` factor, and the best factor over all the scene's option sets."""
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
        f"Machine: {_machine()} (shared with other jobs: timings are best of {settings['repeat']}, each the "
        "render's own cost, without the error estimate `render` adds by default). "
        f"Images {settings['width']}x{settings['height']}, methods at aa = {settings['aa']} (spatial samples per pixel per axis); reference: Mitsuba {settings['variant']}, "
        f"K = {settings['times']} shutter times x {settings['spp']} spp; second reference: each method's own limit, "
        f"{limit_label(settings)} on our rasterizer (no shadows: the blur "
        "method's own error). Pareto marks the front against Mitsuba. Error: RMSE over premultiplied RGBA; "
        "coverage error is signed (alpha summed over the image, relative)."
    )
    if settings.get("phases"):
        lines += ["", f"Run time before this report was written: {settings['phases']}."]
    lines.append("")
    for scene in dict.fromkeys(r["scene"] for r in rows):
        sel = [(r, f) for r, f in zip(rows, fronts) if r["scene"] == scene]
        lines += [
            f"## {scene}",
            "",
            "| method | options | ms | RMSE (Mitsuba) | RMSE (own limit) | PSNR dB | FLIP | coverage err | Pareto |",
            "|---|---|---:|---:|---:|---:|---:|---:|:-:|",
        ]
        for r, f in sorted(sel, key=lambda x: x[0]["ms"]):
            lines.append(
                f"| {r['method']} | {r['options']} | {r['ms']:.2f} | {r['rmse']:.5f} | {r.get('rmse_limit', float('nan')):.5f} | "
                f"{r['psnr']:.2f} | {r['flip']:.4f} | {r['coverage_error']:+.3f} | {'*' if f else ''} |"
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
