"""Writing the report: the markdown tables, the csv, the settings, and the pictures (Pareto plots
and per-scene sheets, drawn by :mod:`.figures`)."""

from __future__ import annotations

import csv
import json
import os
import platform
from pathlib import Path

import numpy as np

from ..raster import Frame
from .figures import pareto_plot, sheet

__all__ = ["write", "save_reference"]


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
    images=None,
    references=None,
) -> dict:
    """Write the report into ``out``: ``pareto_<scene>.png`` per scene of ``names``,
    ``results.csv`` (the rows, ``fronts`` marking the Pareto front), ``results.md``,
    ``settings.json`` and, when given, ``images`` ({(scene, method, options): Frame}) under
    ``images/`` with ``sheet_<scene>.png`` per scene: the reference (``references``: {scene:
    (H,W,4) rgba}) and every method's image side by side, labelled with method, options, ms and
    RMSE (:func:`.figures.sheet`). Returns the paths of the table and the csv."""
    for name in names:
        sel = [(r, f) for r, f in zip(rows, fronts) if r["scene"] == name]
        pareto_plot(name, [r for r, _ in sel], [f for _, f in sel], out / f"pareto_{name}.png")
    with open(out / "results.csv", "w", newline="") as fh:
        keys = [k for k in rows[0] if not k.startswith("_")]
        wr = csv.DictWriter(fh, fieldnames=[*keys, "pareto"])
        wr.writeheader()
        for r, f in zip(rows, fronts):
            wr.writerow({**{k: r[k] for k in keys}, "pareto": int(f)})
    (out / "results.md").write_text(
        _markdown(rows, fronts, comparisons, pyrender_rows, settings, flip_comparisons, paired, equal_times)
    )
    (out / "settings.json").write_text(json.dumps({**settings, "machine": _machine()}, indent=1))
    paths = {"md": out / "results.md", "csv": out / "results.csv"}
    if images:
        for (scene, m, opts), frame in images.items():
            frame.save_png(out / "images" / f"{scene}_{m}_{opts.replace(' ', '_').replace('=', '')}.png")
        for name in names:
            tiles = (
                [(f"reference\nMitsuba, K = {settings['times']} x {settings['spp']} spp\n", references[name])]
                if references and name in references
                else []
            )
            for r in (r for r in rows if r["scene"] == name):
                frame = images.get((name, r["method"], r["options"]))
                if frame is not None:
                    tiles.append(
                        (
                            f"{r['method']}\n{r['options']}\n{r['ms']:.2f} ms   RMSE {r['rmse']:.5f}",
                            frame.rgba,
                        )
                    )
            if tiles:
                paths[f"sheet_{name}"] = out / f"sheet_{name}.png"
                sheet(tiles, paths[f"sheet_{name}"])
    return paths


def save_reference(out: Path, name: str, ref: np.ndarray) -> None:
    """The reference image of scene ``name`` as ``images/<name>_reference.png``."""
    h, w = ref.shape[:2]
    Frame(ref, np.zeros((h, w)), np.zeros((h, w), np.int32), np.zeros((h, w, 2))).save_png(
        out / "images" / f"{name}_reference.png"
    )


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
