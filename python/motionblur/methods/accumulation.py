"""The accumulation buffer (OpenGL Programming for the Advanced Programmer, section 14.2).

The frame is the mean of N renders at shutter times ``t_i``: the shutter filter's mass is cut
into N equal strata and ``t_i`` is the time at which the filter's cumulative weight W reaches the
stratum's stratified point ``(i + 0.5) / N`` (or a jittered one, ``(i + u_i) / N``), so every
sample weighs 1/N and the samples are denser where the filter weighs more (under the box shutter
``t_i = (i + 0.5) / N``; see `sample_times`). Static objects (and, with a still camera, everything that does not
move) are rasterized once into a static layer; each time sample then rasterizes only the moving
objects, inside the pixel window their motion covers, and composites them with the static layer
per sample by depth before accumulating. With a translucent object that one depth a pixel per
layer cannot sort (a surface between two of the other layer's), every object is drawn at every
sample instead, and objects of both shading modes in one rasterizer call, so the frame converges
to the exact time integral ([`motionblur.exact`][motionblur.exact]) there too. The dimmed-blur variant (``dim < 1``) loads the static
scene with weight ``1 - dim`` and accumulates the full scene with weight ``dim``, which makes the
blurred objects look faster (fainter).

`Sequence` keeps the accumulation buffer's running total across consecutive frames.
"""

from __future__ import annotations

from collections import deque

import numpy as np

from .._validate import as_array, as_bool, as_float, as_int, as_samples
from ..budget import need
from ..raster import Frame
from ..render import register
from ..scene import Scene
from ._accumulate import MAX_TIME_SAMPLES, HalfSums, accumulate, sample_times, uniform_times

__all__ = [
    "accumulation",
    "sample_times",
    "Sequence",
    "MAX_TIME_SAMPLES",
    "rolling_accumulation",
    "row_offsets",
]


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

    The even and the odd samples are drawn and summed apart by the compiled core
    (``_core._Painter.accumulate_still_parts`` / ``accumulate_moving``, ``src/accumulate/frame.rs``);
    their difference is the frame's ``stats["error_estimate"]`` (`_accumulate`), with ``aa`` 2
    or 4 and a stratified grid of an even count with an end term (`_accumulate.ends_factor`), at
    ``aa`` 4 divided by its over-read where the samples are about as many as the pixels the
    moving outlines travel (`_accumulate.resonance`). A stratified grid of 4 or
    8 samples is drawn in quarters, whose differences within each half tell how fast the error
    falls (`_accumulate.rate_factor`).

    A rolling shutter (``Scene(rolling=R)``): see `rolling_accumulation` (about N renders per
    row, each row weighing every render by its own window's filter).
    """
    times, weights = sample_times(scene, samples, sampling, seed)
    dim = as_float(dim, "dim")
    if not 0.0 < dim <= 1.0:
        raise ValueError(f"dim: must be in (0, 1], got {dim}")
    aa = as_samples(aa, "aa")
    if scene.rolling > 0.0:
        return rolling_accumulation(scene, len(times), sampling, seed, dim, aa)
    ref = int(np.argmin(np.abs(times - scene.reference_t)))
    halves = [np.arange(len(times))[j::2] for j in (0, 1)]
    if len(times) < 2 or min(float(weights[h].sum()) for h in halves) <= 0.0 or dim < 1.0:
        # No two halves to compare (or the dimmed look, whose bias they do not see): render()
        # estimates the error with its pilot.
        return accumulate(scene, times, weights, ref, dim, aa)
    sums = HalfSums(scene, aa, sampling)
    sums.add_grid(times, weights)
    return sums.frame()


def row_offsets(scene: Scene, height: int) -> np.ndarray:
    """(height,) float64: each pixel row's rolling-shutter offset ``o`` (``Scene(rolling=)``):
    ``R * y / H`` top to bottom, ``R * (H - 1 - y) / H`` bottom to top."""
    y = np.arange(height, dtype=np.float64)
    k = y if scene.rolling_direction == "top_to_bottom" else (height - 1) - y
    return scene.rolling * k / height


def rolling_accumulation(scene: Scene, samples: int, sampling: str, seed: int, dim: float, aa: int) -> Frame:
    """The accumulation buffer under a rolling shutter (``scene.rolling`` R > 0).

    The whole capture [0, 1] is cut into ``M = ceil(N / (1 - R))`` equal strata of time (at most
    `MAX_TIME_SAMPLES`), one render each at its stratified (or jittered) time (`uniform_times`:
    the rows' windows differ, so no one filter's mass can cut them); pixel row ``y``
    weighs render ``j`` by its filter's weight of stratum ``[a, b] = [j / M, (j + 1) / M]``
    within its own window, ``W((b - o) / s) - W((a - o) / s)`` (``o`` its offset, `row_offsets`;
    ``s = 1 - R``; W clamped to [0, 1]), so every row's weights sum to 1 and each row averages
    about N renders; only the strata cut by a window's ends are weighed in part. It converges to
    the analytic frame as N grows. Depth, ids and velocity of each row are those of the render
    nearest its reference instant ``o + s * reference_t``. ``stats["samples"]`` is M; the
    error estimate is ``render``'s pilot (no halves)."""
    s = 1.0 - scene.rolling
    m = min(int(np.ceil(samples / s)), MAX_TIME_SAMPLES)
    times = uniform_times(m, sampling, seed)
    height = scene.camera.height
    o = row_offsets(scene, height)[:, None]
    cdf = scene.shutter_cdf((np.arange(m + 1)[None, :] / m - o) / s)
    weights = np.diff(cdf, axis=1)  # (H, M): each row's filter weight of every stratum
    nearest = np.argmin(np.abs(times[None, :] - (o + s * scene.reference_t)), axis=1)
    rgba = depth = ids = velocity = None
    draw_calls = 0
    for j in range(len(times)):
        rows = weights[:, j] > 0.0
        if not rows.any() and not (nearest == j).any():
            continue
        f = accumulate(scene, times[j : j + 1], np.ones(1), 0, dim, aa)
        draw_calls += f.stats["draw_calls"]
        if rgba is None:
            rgba = np.zeros(f.rgba.shape, np.float64)
            depth, ids, velocity = f.depth.copy(), f.ids.copy(), np.zeros((*f.ids.shape, 2))
        rgba += weights[:, j, None, None] * f.rgba
        near = nearest == j
        depth[near], ids[near] = f.depth[near], f.ids[near]
        if f.velocity is not None:
            velocity[near] = f.velocity[near]
    frame = Frame(rgba.astype(np.float32), depth, ids, velocity)
    frame.stats.update(samples=m, draw_calls=draw_calls, rolling=scene.rolling)
    return frame


class Sequence:
    """The accumulation buffer's running total across consecutive frames.

    ``render_at(t) -> (H,W,4) array or Frame`` renders the scene sharp at (animation) time ``t``;
    ``samples`` N renders (1..``MAX_TIME_SAMPLES``) are averaged per frame, ``step`` apart in
    time. Frame k (from 0) is the mean of the renders at ``t0 + (k + j) * step``, j = 0..N-1.
    The first `next` draws N times; every later one draws twice: it adds the newest render
    and subtracts the oldest one, rendered again (``keep_images=False``, the book's way) or kept
    from before (``keep_images=True``: one draw per frame). The total is kept in float64 so the
    subtraction does not drift. ``draws`` counts the calls to ``render_at``.

    Memory: the running total (8 bytes a value) and the render being added, whatever N, with
    ``keep_images=False``; plus the N renders (as ``render_at`` returned them) with ``keep_images=True``. It is checked against the memory budget
    (``motionblur.set_memory_budget``) once the first render gives the image size, before the
    other N - 1 are drawn: past it ``MemoryError`` names ``samples`` and the bytes.

    Every render must be a Frame or a real, finite (H,W,4) array of the same shape as the
    first; otherwise `next` raises TypeError / ValueError naming ``render_at`` and the
    time. ``keep_images`` is True or False (anything else raises TypeError).
    """

    def __init__(
        self, render_at, samples: int, step: float = 1.0, t0: float = 0.0, keep_images: bool = False
    ):
        if not callable(render_at):
            raise TypeError("render_at: expected a callable t -> image")
        self.render_at = render_at
        self.samples = as_int(samples, "samples", minimum=1, maximum=MAX_TIME_SAMPLES)
        self.step = as_float(step, "step")
        if not self.step > 0:
            raise ValueError(f"step: must be > 0, got {self.step}")
        self.t0 = as_float(t0, "t0")
        self.keep_images = as_bool(keep_images, "keep_images")
        self.frame_index = -1
        self.draws = 0
        self._total = None
        self._shape: tuple[int, ...] | None = None
        self._kept: deque = deque()

    def _render(self, t: float) -> np.ndarray:
        self.draws += 1
        img = self.render_at(t)
        img = img.rgba if isinstance(img, Frame) else img
        name = f"render_at: its result at t={t:g}"
        if img is None or isinstance(img, (str, bytes)):
            raise TypeError(f"{name} is {type(img).__name__}; expected a Frame or an (H,W,4) array")
        want = (None, None, 4) if self._shape is None else self._shape
        out = as_array(img, name, np.float64, want)  # the checks; float64 for the total
        self._shape = out.shape
        raw = np.asarray(img)
        return raw if raw.dtype in (np.float32, np.float64) else out  # kept as rendered

    def _draw(self, t: float) -> np.ndarray:
        return np.asarray(self._render(t), dtype=np.float64)

    def _check_memory(self, first: np.ndarray) -> None:
        """The running total (and the kept renders) against the memory budget."""
        terms = [({"image values": first.size}, 2 * 8)]
        if self.keep_images:
            terms.append(({"samples": self.samples, "image values": first.size}, first.itemsize))
        need("Sequence", *terms)

    def time(self, j: int) -> float:
        """Time of the j-th render of the whole sequence."""
        return self.t0 + j * self.step

    def next(self) -> np.ndarray:
        """The next frame: (H,W,4) float32 mean of the last N renders."""
        n = self.samples
        self.frame_index += 1
        k = self.frame_index
        if self._total is None:
            # A running sum, one render at a time: only the total (and, when kept, the
            # renders) stays.
            for j in range(n):
                img = self._render(self.time(j))
                if j == 0:
                    self._check_memory(img)
                    total = np.array(img, dtype=np.float64)
                else:
                    total += img
                if self.keep_images:
                    self._kept.append(np.array(img, copy=True))
            self._total = total
        else:
            newest = self._render(self.time(k + n - 1))
            oldest = self._kept.popleft() if self.keep_images else self._draw(self.time(k - 1))
            self._total += np.asarray(newest, dtype=np.float64) - np.asarray(oldest, dtype=np.float64)
            if self.keep_images:
                self._kept.append(np.array(newest, copy=True))
        return (self._total / n).astype(np.float32)
