"""The accumulation buffer (OpenGL Programming for the Advanced Programmer, section 14.2).

The frame is the weighted mean of N renders at shutter times ``t_i``: stratified ``(i + 0.5) / N``
or jittered ``(i + u_i) / N``, each weighted by the shutter filter's integral over its stratum
``[i / N, (i + 1) / N]``. Static objects (and, with a still camera, everything that does not
move) are rasterized once into a static layer; each time sample then rasterizes only the moving
objects, inside the pixel window their motion covers, and composites them with the static layer
per sample by depth before accumulating. The dimmed-blur variant (``dim < 1``) loads the static
scene with weight ``1 - dim`` and accumulates the full scene with weight ``dim``, which makes the
blurred objects look faster (fainter).

:class:`Sequence` keeps the accumulation buffer's running total across consecutive frames.
"""

from __future__ import annotations

from collections import deque

import numpy as np

from .. import _core
from .._validate import as_float, as_int, as_samples
from ..raster import Frame
from ..render import register
from ..scene import Scene
from ._layers import (
    Layer,
    aligned_window,
    composite,
    object_draw,
    paste,
    raster_layer,
    resolve,
    static_layer,
    supersampled,
    window_projection,
)
from ._painter import Painter, Placements, sample_windows

__all__ = ["accumulation", "sample_times", "Sequence"]


def sample_times(scene: Scene, n: int, sampling: str = "stratified", seed: int = 0):
    """(times (N,), weights (N,)) of N shutter samples: stratified or jittered times, weights the
    shutter filter's integral over each stratum (summing to 1)."""
    n = as_int(n, "samples", minimum=1, maximum=1 << 16)
    if sampling == "stratified":
        u = np.full(n, 0.5)
    elif sampling == "jittered":
        u = np.random.default_rng(as_int(seed, "seed", minimum=0)).random(n)
    else:
        raise ValueError(f"sampling: expected 'stratified' or 'jittered', got {sampling!r}")
    times = (np.arange(n) + u) / n
    w = np.diff(scene.shutter_cdf(np.arange(n + 1) / n))
    return times, w / w.sum()


def _crop(layer: Layer, win) -> Layer:
    x0, y0, x1, y1 = win
    return Layer(layer.rgba[y0:y1, x0:x1], layer.depth[y0:y1, x0:x1], layer.ids[y0:y1, x0:x1])


@register(
    "accumulation",
    sweep=[{"samples": n} for n in (1, 2, 4, 8, 16, 32, 64, 128, 256)],
    applies=lambda scene: True,
)
def accumulation(
    scene: Scene, samples: int = 16, sampling: str = "stratified", seed: int = 0, dim=1.0, aa: int = 1
):
    """Accumulation buffer: the weighted mean of ``samples`` renders over the shutter.

    Options: ``samples`` N >= 1 time samples; ``sampling`` ``"stratified"`` or ``"jittered"``
    (``seed`` for the jitter); ``dim`` in (0, 1], the dimmed-blur variant's weight of the moving
    scene (1: plain accumulation); ``aa`` 1, 2 or 4 spatial samples per pixel along each axis.
    Returns a Frame (rgba premultiplied; depth and ids of the sample nearest the reference time).
    ``stats``: ``samples``, ``draw_calls`` (rasterizer passes over moving geometry),
    ``static_draws`` (0 or 1) and ``window`` (the pixel rectangle redrawn per sample).
    """
    times, weights = sample_times(scene, samples, sampling, seed)
    dim = as_float(dim, "dim")
    if not 0.0 < dim <= 1.0:
        raise ValueError(f"dim: must be in (0, 1], got {dim}")
    aa = as_samples(aa, "aa")
    ref = int(np.argmin(np.abs(times - scene.reference_t)))
    stats = {"samples": len(times), "draw_calls": 0, "static_draws": 0, "window": None}
    everything = list(enumerate(scene.objects))

    if scene.camera_moves:
        # Everything moves on screen: whole frames at every sample.
        painter = Painter(scene, everything)
        acc = None
        keep = None
        for i, t in enumerate(times):
            cam = supersampled(scene.camera_at(t), aa)
            layer = painter.layer(t, cam.view, cam.projection, cam.width, cam.height)
            stats["draw_calls"] += 1
            if acc is None:
                acc = layer.rgba * np.float32(weights[i])
            else:  # acc += w * rgba in one pass, in place (the same float32 products and sums)
                _core._accumulate(acc, layer.rgba, layer.depth, None, float(weights[i]))
            if i == ref:
                keep = layer
        if dim < 1.0:
            cam = supersampled(scene.camera_at(scene.reference_t), aa)
            static = [(o, object_draw(o, scene.reference_t, k)) for k, o in everything if not o.is_moving]
            acc = (1.0 - dim) * raster_layer(cam, scene, static).rgba + dim * acc
        frame = resolve(Layer(acc.astype(np.float32), keep.depth, keep.ids), aa)
        frame.stats.update(stats)
        return frame

    cam = supersampled(scene.camera, aa)
    static_objs = [(k, o) for k, o in everything if not o.is_moving]
    moving = [(k, o) for k, o in everything if o.is_moving]
    static = static_layer(scene, cam, static_objs, aa)
    stats["static_draws"] = 0 if (static.cached or not static_objs) else 1
    stats["static_cached"] = static.cached
    placement = Placements()
    per_sample = sample_windows(cam, times, [o for _, o in moving], placement) if moving else []
    found = [w for w in per_sample if w is not None]
    if not found:
        frame = Frame(
            static.rgba.copy(), static.depth.copy(), static.ids.copy(), np.zeros((*static.ids.shape, 2))
        )
        frame.stats.update(stats)
        return frame
    a = np.array(found)
    win = (int(a[:, 0].min()), int(a[:, 1].min()), int(a[:, 2].max()), int(a[:, 3].max()))
    win = aligned_window(win, aa, cam.width, cam.height)
    stats["window"] = win
    x0, y0, x1, y1 = win
    view = np.ascontiguousarray(cam.view)
    base = _crop(static.layer, win)
    base = Layer(np.ascontiguousarray(base.rgba), np.ascontiguousarray(base.depth), base.ids)
    painter = Painter(scene, moving, eye=cam.pose[:3, 3], placement=placement)
    # Per sample i the composite is M_i over S where M_i is nearer, else S (exact for an opaque
    # static layer), so sum_i w_i out_i = A + S (1 - A.alpha) with A = sum_i w_i M_i [M_i nearer]:
    # the static layer is composited once, after the loop. Each sample is rasterized only inside
    # its own rectangle (the moving objects' bounds at that time) and added there.
    has_static = bool(np.isfinite(base.depth).any())
    exact_sum = not has_static or static.opaque
    acc = np.zeros((y1 - y0, x1 - x0, 4), np.float32)
    keep = Layer(base.rgba, base.depth.copy(), base.ids.copy())  # only depth and ids are written
    for i, (t, sw) in enumerate(zip(times, per_sample)):
        w = np.float32(weights[i])
        if sw is None:
            if not exact_sum:
                acc += w * base.rgba
            continue
        sx0, sy0, sx1, sy1 = sw[0] - x0, sw[1] - y0, sw[2] - x0, sw[3] - y0  # inside the window
        proj = np.ascontiguousarray(window_projection(cam.projection, cam.width, cam.height, sw))
        layer = painter.layer(t, view, proj, sx1 - sx0, sy1 - sy0)
        stats["draw_calls"] += 1
        sub = Layer(base.rgba[sy0:sy1, sx0:sx1], base.depth[sy0:sy1, sx0:sx1], base.ids[sy0:sy1, sx0:sx1])
        if i == ref:
            c = composite(layer, sub)
            keep.depth[sy0:sy1, sx0:sx1], keep.ids[sy0:sy1, sx0:sx1] = c.depth, c.ids
        if exact_sum:
            # one fused pass in Rust: acc += w * M where M is in front of the static surface
            limit = base.depth if has_static else None
            _core._accumulate(acc, layer.rgba, layer.depth, limit, float(w), sx0, sy0)
        else:
            full = base.rgba.copy()
            full[sy0:sy1, sx0:sx1] = composite(layer, sub).rgba
            acc += w * full
    if has_static and static.opaque:
        _core._over(acc, base.rgba)
    if dim < 1.0:
        acc = (1.0 - dim) * base.rgba + dim * acc
    frame = paste(static, win, Layer(acc, keep.depth, keep.ids), aa)
    frame.stats.update(stats)
    return frame


class Sequence:
    """The accumulation buffer's running total across consecutive frames.

    ``render_at(t) -> (H,W,4) array or Frame`` renders the scene sharp at (animation) time ``t``;
    ``samples`` N renders are averaged per frame, ``step`` apart in time. Frame k (from 0) is the
    mean of the renders at ``t0 + (k + j) * step``, j = 0..N-1. The first :meth:`next` draws N
    times; every later one draws twice: it adds the newest render and subtracts the oldest one,
    rendered again (``keep_images=False``, the book's way) or kept from before
    (``keep_images=True``: N images of memory, one draw per frame). The total is kept in float64
    so the subtraction does not drift. ``draws`` counts the calls to ``render_at``.
    """

    def __init__(
        self, render_at, samples: int, step: float = 1.0, t0: float = 0.0, keep_images: bool = False
    ):
        if not callable(render_at):
            raise TypeError("render_at: expected a callable t -> image")
        self.render_at = render_at
        self.samples = as_int(samples, "samples", minimum=1)
        self.step = as_float(step, "step")
        if not self.step > 0:
            raise ValueError(f"step: must be > 0, got {self.step}")
        self.t0 = as_float(t0, "t0")
        self.keep_images = bool(keep_images)
        self.frame_index = -1
        self.draws = 0
        self._total = None
        self._kept: deque = deque()

    def _draw(self, t: float) -> np.ndarray:
        self.draws += 1
        img = self.render_at(t)
        img = img.rgba if isinstance(img, Frame) else img
        return np.asarray(img, dtype=np.float64)

    def time(self, j: int) -> float:
        """Time of the j-th render of the whole sequence."""
        return self.t0 + j * self.step

    def next(self) -> np.ndarray:
        """The next frame: (H,W,4) float32 mean of the last N renders."""
        n = self.samples
        self.frame_index += 1
        k = self.frame_index
        if self._total is None:
            imgs = [self._draw(self.time(j)) for j in range(n)]
            self._total = np.sum(imgs, axis=0)
            if self.keep_images:
                self._kept.extend(imgs)
        else:
            newest = self._draw(self.time(k + n - 1))
            oldest = self._kept.popleft() if self.keep_images else self._draw(self.time(k - 1))
            self._total += newest - oldest
            if self.keep_images:
                self._kept.append(newest)
        return (self._total / n).astype(np.float32)
