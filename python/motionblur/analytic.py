"""Analytic motion blur for numpy users: meshes given at the boundaries of shutter segments,
rasterized with the exact time each sample is covered.

Within each segment ``[times[k], times[k+1]]`` every vertex moves linearly in clip space, so a
triangle's edge functions at a sample are quadratics in time and the covered times are found
from their roots (Korein and Badler's continuous algorithm in Gribel et al.'s rasterizer form).
Visibility is resolved over time per sample (linear depth per covered span, split where two
surfaces cross) and colour is integrated with the shutter filter at Gauss points in time.
[`rasterize_motion`][motionblur.analytic.rasterize_motion] is the kernel behind ``render(scene, "analytic")``.
"""

from __future__ import annotations

from collections.abc import Sequence
from types import SimpleNamespace

import numpy as np

from . import _core
from ._validate import as_array, as_choice, as_faces, as_float, as_int, as_rgba
from .raster import Camera, Frame, _readonly
from .scene import Trapezoid

__all__ = ["MovingDraw", "rasterize_motion", "coverage", "TILE_BUDGET_BYTES"]

#: Most bytes one pass over a tile of 32 x 32 samples may hold in fragments (the spans of time
#: the triangles cover its samples), their chains and the triangles they come from, per thread.
#: Past it the tile is done again in halves (rows, then columns, down to single samples): the
#: result is the same bits, only slower (``stats["splits"]`` counts the halvings). A single
#: sample that alone needs more (thousands of moving triangles stacked over it) raises
#: ``MemoryError`` naming it; raise this setting to let it through. Each thread's buffers may
#: reach twice this and are kept for its next tile until the strip of tile rows (below) is
#: done. Twice this bounds the triangle set-ups held at once (about 124 bytes per triangle and
#: segment): past it the frame is set up and rendered strip by strip of tile rows
#: (``stats["strips"]``), the same bits.
TILE_BUDGET_BYTES = 64 << 20


class MovingDraw:
    """One mesh moving over the shutter.

    ``positions`` (K+1,V,3) float world positions at the K+1 segment boundaries; ``faces``
    (F,3) int, counter-clockwise is front; ``rgba`` straight linear colour: (3,)/(4,) for every
    vertex or (V,3)/(V,4) per vertex, alpha in [0, 1]; ``normals`` (K+1,V,3) world normals at
    the boundaries for lambert shading (None: area-weighted normals of the positions);
    ``object_id`` int32 written to ``Frame.ids``; ``cull_back`` drops back faces; ``shading``
    ``"flat"`` (unlit colour) or ``"lambert"`` (the frame's lights and ambient). The arrays are
    stored as read-only float64 / int64 / float32 copies or views; the caller's arrays are never
    written.
    """

    def __init__(
        self,
        positions,
        faces,
        rgba=(1.0, 1.0, 1.0),
        normals=None,
        object_id=0,
        cull_back=True,
        shading: str = "flat",
    ):
        p = as_array(positions, "positions", np.float64, (None, None, 3))
        f = as_faces(faces, "faces", p.shape[1], allow_empty=True)
        c = as_rgba(rgba, "rgba", p.shape[1])
        n = None if normals is None else as_array(normals, "normals", np.float32, p.shape)
        self.positions, self.faces, self.rgba = _readonly(p), _readonly(f), _readonly(c)
        self.normals = _readonly(n)
        self.object_id = as_int(object_id, "object_id", minimum=-(2**31), maximum=2**31 - 1)
        if not isinstance(cull_back, (bool, np.bool_)):
            raise TypeError(f"cull_back: expected a bool, got {type(cull_back).__name__}")
        self.cull_back = bool(cull_back)
        if not isinstance(shading, str):
            raise TypeError(f"shading: expected a string, got {type(shading).__name__}")
        if shading not in ("flat", "lambert"):
            raise ValueError(f"shading: expected 'flat' or 'lambert', got {shading!r}")
        self.shading = shading

    def __repr__(self) -> str:
        k, v = self.positions.shape[:2]
        return (
            f"MovingDraw({k} boundaries, {v} vertices, {len(self.faces)} faces, object_id={self.object_id})"
        )


def _view_projections(cameras, k1: int):
    cams = [cameras] if isinstance(cameras, Camera) else list(cameras)
    if not cams or not all(isinstance(c, Camera) for c in cams):
        raise TypeError("cameras: expected a motionblur.Camera or a sequence of them (one per boundary)")
    if len(cams) not in (1, k1):
        raise ValueError(f"cameras: expected 1 or {k1} cameras (one per boundary), got {len(cams)}")
    w, h = cams[0].width, cams[0].height
    if any((c.width, c.height) != (w, h) for c in cams):
        raise ValueError("cameras: every camera must have the same image size")
    return np.ascontiguousarray(np.stack([c.view_projection for c in cams])), w, h


def _shutter_arg(shutter):
    if isinstance(shutter, (str, Trapezoid)):
        return shutter  # a Trapezoid crosses as its open and close ramps
    w = as_array(shutter, "shutter", np.float64, (None,))
    return np.ascontiguousarray(w)


def rasterize_motion(
    cameras,
    draws: Sequence[MovingDraw],
    times,
    samples: int = 1,
    shutter="box",
    lights=(),
    ambient=0.0,
    gauss="auto",
    reference_time: float = 1.0,
    background=None,
    shade: bool = True,
    exposure: int | None = None,
    rolling: float = 0.0,
    rolling_direction: str = "top_to_bottom",
) -> Frame:
    """Rasterizes moving meshes with the exact covered time per sample.

    ``cameras``: one [`Camera`][motionblur.analytic.Camera], or one per boundary (a moving camera; same image size).
    ``draws``: [`MovingDraw`][motionblur.analytic.MovingDraw] s. ``times`` (K+1,) float: the segment boundaries, strictly
    increasing from 0 to 1 (normalised shutter time). ``samples``: 1, 2 or 4 per pixel along
    each axis. ``shutter``: ``"box"``, ``"ramp"``, ``"triangle"``, ``"gaussian"`` or (M,) weights
    of M equal strata. ``lights`` (pairs (direction (3,), intensity float or (3,))) and
    ``ambient`` light the lambert draws. ``gauss``: points in time per visible piece, 1 to
    4, or ``"auto"`` (1 to 3 by the piece's length); a piece is cut where the triangle covering
    the sample changes, so each triangle is shaded at its own points, and where a light grazes
    a lambert triangle (the kink of ``max(0, n . l)``). ``reference_time`` in [0, 1]: the instant depth, ids and velocity describe.
    ``background``: an opaque layer the draws are depth-tested and composited against, one
    entry per sample: ``(rgba (HS,WS,4) float32 premultiplied, depth (HS,WS) float32 view
    depth (inf where empty), ids (HS,WS) int32)``. ``shade=False`` gives coverage only (every
    surface opaque white). ``exposure``: None, or the number N of object ids (every draw's
    ``object_id`` and every ``background`` id in -1..N-1) to also return the exposure channel
    in ``stats["exposure"]``: a dict of ``fraction``, ``first`` and ``last``, each (H,W,N+1)
    float32, plane k for object id k and the last plane for id -1 (no surface): see
    [`exposure`][motionblur.ground_truth.exposure] for what they hold. ``rolling``: a rolling
    shutter's readout ``R`` in [0, 1) and ``rolling_direction`` (``"top_to_bottom"`` or
    ``"bottom_to_top"``): pixel row ``y`` of ``H`` is exposed over ``[o, o + 1 - R]`` only,
    ``o = R * y / H`` (``R * (H - 1 - y) / H`` bottom to top), the filter rescaled to it, and
    depth, ids and velocity describe its instant ``o + (1 - R) * reference_time`` (see
    [`Scene`][motionblur.scene.Scene]); 0 (the default) is a global shutter, the same bits as
    before. The exposure channel's times stay the scene's.

    Returns a [`Frame`][motionblur.analytic.Frame]: ``rgba`` (H,W,4) float32 premultiplied, the shutter-weighted
    time integral; ``depth`` (H,W) float32, ``ids`` (H,W) int32 and ``velocity`` (H,W,2) float32
    (pixels, the surface's screen motion from the first to the last boundary) of the surface in
    front at ``reference_time`` (of each pixel's nearest sample); ``stats`` with ``prims``,
    ``bin_entries``, ``intervals`` (covered spans found), ``pieces`` (stretches of time shaded, each of fixed layers and triangles),
    ``splits`` (tile passes redone in halves to stay within `TILE_BUDGET_BYTES`),
    ``segments``, ``strips`` (strips of tile rows set up and rendered one at a time: past twice
    `TILE_BUDGET_BYTES` of triangle set-ups, a frame is done strip by strip, the same bits) and
    ``ms_*`` per stage. Bit-identical for any thread count and any budget; the
    GIL is released. ``MemoryError`` (naming the sample) where one sample alone needs more than
    the budget.
    """
    t = as_array(times, "times", np.float64, (None,))
    vps, w, h = _view_projections(cameras, len(t))
    draws = _checked_draws(draws, len(t))
    samples = as_int(samples, "samples")
    if isinstance(gauss, str):
        if gauss != "auto":
            raise ValueError(f"gauss: expected 'auto' or 1 to 4, got {gauss!r}")
    else:
        gauss = as_int(gauss, "gauss")  # its range is the core's to check
    light_args = _light_args(lights)
    amb = _rgb(ambient, "ambient")
    bd = None if background is None else _background_arg(background)
    if not isinstance(shade, (bool, np.bool_)):
        raise TypeError(f"shade: expected a bool, got {type(shade).__name__}")
    if exposure is not None:
        exposure = as_int(exposure, "exposure", minimum=0, maximum=2**31 - 1)
    options = {
        "width": w,
        "height": h,
        "samples": samples,
        "times": np.ascontiguousarray(t),
        "view_projections": vps,
        "shutter": _shutter_arg(shutter),
        "lights": light_args,
        "ambient": tuple(map(float, amb)),
        "gauss": gauss,
        "reference_time": as_float(reference_time, "reference_time"),
        "shade": bool(shade),
        "tile_budget": as_int(TILE_BUDGET_BYTES, "TILE_BUDGET_BYTES", minimum=1),
        "exposure": exposure,
    }
    readout = as_float(rolling, "rolling")
    if not 0.0 <= readout < 1.0:
        raise ValueError(f"rolling: the readout must be in [0, 1), got {readout}")
    direction = as_choice(rolling_direction, "rolling_direction", ("top_to_bottom", "bottom_to_top"))
    if readout > 0.0:
        options["rolling"] = readout
        options["rolling_bottom_to_top"] = direction == "bottom_to_top"
    rgba, depth, ids, velocity, stats, planes = _core._analytic(draws, options, bd)
    frame = Frame(rgba, depth, ids, velocity, stats)
    if planes is not None:
        frame.stats["exposure"] = dict(zip(("fraction", "first", "last"), planes))
    return frame


def _checked_draws(draws, boundaries: int) -> list:
    """``draws`` as a list, each a `MovingDraw` with positions at ``boundaries`` boundaries."""
    draws = list(draws)
    for i, d in enumerate(draws):
        if not isinstance(d, MovingDraw):
            raise TypeError(f"draws: item {i} is a {type(d).__name__}, not a motionblur.MovingDraw")
        if d.positions.shape[0] != boundaries:
            raise ValueError(
                f"draws: item {i} has {d.positions.shape[0]} boundaries of positions, times has {boundaries}"
            )
    return draws


def _rgb(value, name: str) -> np.ndarray:
    """A float or 3 floats as (3,) float64 (errors name ``name``)."""
    v = np.asarray(value, dtype=np.float64)
    return as_array(np.broadcast_to(v, (3,)) if v.ndim == 0 else v, name, np.float64, (3,))


def _light_args(lights) -> list[tuple[tuple[float, ...], tuple[float, ...]]]:
    """The core's lights: each pair (direction (3,), intensity float or (3,)) as two 3-tuples."""
    out = []
    for i, li in enumerate(lights):
        try:
            d, k = li
        except (TypeError, ValueError):
            raise TypeError(f"lights: item {i} must be a pair (direction, intensity)") from None
        dv = as_array(d, "lights", np.float64, (3,))
        out.append((tuple(map(float, dv)), tuple(map(float, _rgb(k, "lights")))))
    return out


def _background_arg(background) -> SimpleNamespace:
    """The core's backdrop from the triple (rgba, depth, ids), each contiguous in its dtype."""
    try:
        rgba, depth, ids = background
    except (TypeError, ValueError):
        raise TypeError("background: expected a triple (rgba, depth, ids)") from None
    c = np.ascontiguousarray
    return SimpleNamespace(
        rgba=c(rgba, dtype=np.float32), depth=c(depth, dtype=np.float32), ids=c(ids, dtype=np.int32)
    )


def coverage(cameras, draws: Sequence[MovingDraw], times, samples: int = 1, shutter="box") -> np.ndarray:
    """(H,W) float32: the shutter-weighted fraction of the time each pixel is covered by any of
    the ``draws`` (see [`rasterize_motion`][motionblur.analytic.rasterize_motion] for the arguments), without shading."""
    f = rasterize_motion(cameras, draws, times, samples=samples, shutter=shutter, shade=False)
    return f.rgba[..., 3].copy()
