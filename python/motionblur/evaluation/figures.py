"""Pictures of the report: a labelled side-by-side sheet per scene and the Pareto plots.

- [`sheet`][motionblur.evaluation.figures.sheet]: the reference and every method's image of one scene side by side, each tile
  labelled with the method, its options, its time (ms) and its RMSE against the reference
  (``sheet_<scene>.png``, written by the demo and by ``bench --images``);
- [`pareto_plot`][motionblur.evaluation.figures.pareto_plot]: error against time, log-log, one colour per method that is the same in
  every plot ([`method_colors`][motionblur.evaluation.figures.method_colors], from the sorted names of every registered method), the
  Pareto front drawn and each of its points labelled with its options.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .._optional import require
from ..raster import Frame
from ..render import METHODS

__all__ = ["method_colors", "pareto_plot", "sheet", "TILE_LABEL_LINES"]

#: lines of text under each tile of a sheet: method, options, "ms  RMSE"
TILE_LABEL_LINES = 3
_LINE_PX = 13
_PAD = 4
_PALETTE = [
    "#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f", "#bcbd22",
    "#17becf", "#393b79", "#637939", "#8c6d31", "#843c39", "#7b4173",
]  # fmt: skip


def method_colors(names=None) -> dict[str, str]:
    """{method: colour} for every registered method (and ``names``), fixed by the sorted names,
    so a method has the same colour in every plot whichever methods a plot shows."""
    every = sorted(set(METHODS) | set(names or ()))
    return {m: _PALETTE[i % len(_PALETTE)] for i, m in enumerate(every)}


def _panel(ax, rows, front, metric: str, colors: dict, ylabel: str) -> list[str]:
    for m in sorted({r["method"] for r in rows}):
        sel = [r for r in rows if r["method"] == m]
        marker = "*" if m == "auto" else "o"
        ax.scatter([r["ms"] for r in sel], [r[metric] for r in sel], label=m, s=70 if m == "auto" else 24,
                   color=colors[m], marker=marker, zorder=3)  # fmt: skip
    fr = sorted((r for r, f in zip(rows, front) if f), key=lambda r: r["ms"])
    ax.plot([r["ms"] for r in fr], [r[metric] for r in fr], "k--", lw=1, label="Pareto front", zorder=2)
    labels = []
    for i, r in enumerate(fr):
        text = f"{r['method']} {r['options']}" if r["options"] != "-" else r["method"]
        labels.append(text)
        ax.annotate(text, (r["ms"], r[metric]), textcoords="offset points", xytext=(5, -11 if i % 2 else 4),
                    fontsize=6.5, color=colors[r["method"]])  # fmt: skip
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("time per frame (ms, best of runs)")
    ax.set_ylabel(ylabel)
    ax.grid(True, which="both", alpha=0.3)
    return labels


def pareto_plot(name: str, rows, front, path, front_limit=None) -> dict:
    """Plot one scene's ``rows`` (dicts with method, options, ms, rmse and optionally
    rmse_limit) with ``front`` (bools, the Pareto front against Mitsuba) to ``path``; with
    ``rmse_limit`` in the rows, a second panel of the error against the own-limit reference and
    its front (``front_limit``). Every point of a front is annotated with its method and options
    (readable without hovering). Returns ``{"colors": {method: colour}, "labels": [front point
    labels of the first panel], "labels_limit": [...]}`` (what the plot shows, for tests)."""
    matplotlib = require("matplotlib")
    matplotlib.use("Agg")
    plt = require("matplotlib.pyplot", "the Pareto plots of the report")
    colors = method_colors(r["method"] for r in rows)
    two = bool(rows) and all("rmse_limit" in r for r in rows)
    fig, axes = plt.subplots(1, 2 if two else 1, figsize=(14.0 if two else 7.2, 5.2), dpi=110, squeeze=False)
    labels = _panel(axes[0][0], rows, front, "rmse", colors, "RMSE against Mitsuba (premultiplied RGBA)")
    axes[0][0].set_title(f"{name}: error against Mitsuba")
    labels_limit = []
    if two:
        fl = front_limit if front_limit is not None else [False] * len(rows)
        labels_limit = _panel(
            axes[0][1], rows, fl, "rmse_limit", colors, "RMSE against the own limit (accumulation, large N)"
        )
        axes[0][1].set_title(f"{name}: error against the method's own limit")
    axes[0][0].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)
    return {"colors": {m: colors[m] for m in sorted({r["method"] for r in rows})}, "labels": labels,
            "labels_limit": labels_limit}  # fmt: skip


def _tile_rgb(rgba: np.ndarray, background: float = 0.0) -> np.ndarray:
    """(H,W,3) uint8 sRGB of premultiplied linear ``rgba`` over a grey ``background`` level."""
    h, w = rgba.shape[:2]
    srgb = Frame(rgba, np.zeros((h, w)), np.zeros((h, w), np.int32), np.zeros((h, w, 2))).to_srgb8()
    a = srgb[..., 3:4].astype(np.float64) / 255.0
    return np.round(srgb[..., :3] * a + background * 255.0 * (1.0 - a)).astype(np.uint8)


def sheet(tiles, path, columns: int = 4) -> list[str]:
    """Write the PNG ``path``: ``tiles`` (a list of ``(label, rgba)``, label up to
    `TILE_LABEL_LINES` lines, rgba (H,W,4) premultiplied linear, all the same size) on a
    grid of ``columns``, each image over black with its label under it on white. Returns the
    labels as drawn (for tests)."""
    image = require("PIL.Image", "the demo's sheets")
    draw_mod = require("PIL.ImageDraw", "the demo's sheets")
    font_mod = require("PIL.ImageFont", "the demo's sheets")
    tiles = list(tiles)
    if not tiles:
        raise ValueError("tiles: expected at least one (label, rgba) tile")
    h, w = np.asarray(tiles[0][1]).shape[:2]
    cols = max(1, min(int(columns), len(tiles)))
    rows = -(-len(tiles) // cols)
    cell_h = h + TILE_LABEL_LINES * _LINE_PX + 2 * _PAD
    canvas = np.full((rows * cell_h, cols * (w + _PAD) + _PAD, 3), 255, np.uint8)
    for k, (_, rgba) in enumerate(tiles):
        rgba = np.asarray(rgba, np.float32)
        if rgba.shape[:2] != (h, w):
            raise ValueError(f"tiles: tile {k} is {rgba.shape[:2]}, the first {(h, w)}")
        y, x = (k // cols) * cell_h + _PAD, (k % cols) * (w + _PAD) + _PAD
        canvas[y : y + h, x : x + w] = _tile_rgb(rgba)
    im = image.fromarray(canvas, mode="RGB")
    draw = draw_mod.Draw(im)
    try:
        font = font_mod.load_default(size=11)
    except TypeError:  # Pillow < 10.1: the bitmap font, one size
        font = font_mod.load_default()
    labels = []
    for k, (label, _) in enumerate(tiles):
        lines = str(label).splitlines()[:TILE_LABEL_LINES]
        labels.append("\n".join(lines))
        y, x = (k // cols) * cell_h + _PAD + h + 2, (k % cols) * (w + _PAD) + _PAD
        for i, line in enumerate(lines):
            draw.text((x, y + i * _LINE_PX), line, fill=(0, 0, 0), font=font)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    im.save(path)
    return labels
