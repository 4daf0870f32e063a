"""The accumulation buffer's kernel call and its two halves, shared by ``accumulation`` and ``auto``.

`accumulate` renders the weighted mean of a set of shutter times (the compiled core draws
and sums them in one call). `HalfSums` keeps an accumulation as two interleaved halves of
its time samples (even and odd strata), each a weighted mean with its weight: the frame is their
sum, and their RMS difference measures the frame's own error against the exact time integral
(see `HALVES_FACTOR`). ``auto`` and the pilot estimate's reference add samples to the halves
they already have instead of rendering again (`add_stratified`).
"""

from __future__ import annotations

import math
from functools import lru_cache
from typing import NamedTuple

import numpy as np

from .. import _core
from .._validate import as_int
from ..raster import Frame
from ..scene import Scene, Trapezoid, shutter_cdf
from ._layers import Layer, object_draw, raster_layer, resolve_arrays, static_layer, supersampled
from ._painter import painter_for
from ._sweep import sweep_path

__all__ = [
    "accumulate",
    "sample_times",
    "shutter_quantiles",
    "uniform_times",
    "QUANTILE_KNOTS",
    "HalfSums",
    "HALVES_FACTOR",
    "ends_factor",
    "PLAIN_SHARE",
    "RESONANCE",
    "resonance",
    "QUARTERS_MAX",
    "rate_factor",
    "grid_parts",
    "Part",
    "time_index",
    "add_stratified",
    "MAX_TIME_SAMPLES",
]

#: Most time samples a frame (``accumulation``'s ``samples``) or a `Sequence` averages.
MAX_TIME_SAMPLES = 1 << 16


#: The error of an N-sample frame over the RMS difference of its two interleaved halves (each
#: normalised) times 2 sqrt(wA wB) / (wA + wB) (1 for equal halves), by sampling; chosen on the
#: tuning scenes of [`motionblur.evaluation.random_scenes`][motionblur.evaluation.random_scenes] (``benches/bench_error_control.py
#: --set tuning``). Stratified halves are two regular grids offset by one stratum: their errors
#: are anti-correlated, so the difference overstates the frame's error by about 4 (with ``aa`` 2
#: or 4 an even grid's halves are read with an end term instead: `ends_factor`).
#: ``"trapezoid"``: ``auto``'s trapezoid grid, whose halves are the trapezoid and the midpoint
#: rules of half its strata: their difference read 0.80-0.83x that of a stratified grid of as
#: many samples (median over tuning scenes, 8 to 96 samples) for the same error.
#: ``"refined 1/4"`` and ``"refined 1/2"``: a stratified grid with a quarter or a half of its
#: strata's boundaries added (`motionblur.methods._refine`), whose halves are the even cells
#: with the boundaries ``4i + 1`` and the odd cells with ``4i + 3``: the factors that give
#: their estimate / error the stratified grid's 5th percentile, 0.93 (tuning scenes with the
#: box shutter, the one auto refines under; 8 to 32 strata; ``benches/study_refined_grids.py``;
#: medians 1.13 and 1.18, against 1.08). The factors that would put their medians at 1.1,
#: 0.229 and 0.199, left 5th percentiles of 0.90 and 0.86, and auto, which stops on the
#: estimate, kept a 1/4 frame 1.04x over its tolerance on a fresh scene with them.
HALVES_FACTOR = {
    "stratified": 0.25,
    "jittered": 0.38,
    "trapezoid": 0.31,
    "refined 1/4": 0.235,
    "refined 1/2": 0.213,
}

#: A stratified frame of at most this many samples, a multiple of 4, is drawn in quarters (sample
#: ``j`` in quarter ``j % 4``) so that its estimate can see how fast its error falls
#: (`rate_factor`): at 4 to 8 samples a frame whose samples are far apart in time (a detailed
#: object turning fast) has halves whose errors are independent rather than opposed, and
#: `HALVES_FACTOR` alone read half its error. From 16 samples up the halves alone were within
#: 0.73-2 of the error on the tuning scenes.
QUARTERS_MAX = 8


def ends_factor(n: int) -> float:
    """The error of a stratified frame of an even ``n`` samples over the RMS of its halves'
    difference with the end term: ``sqrt(n / (12 (n - 1)))``. The even half is the grid's midpoint
    rule shifted a quarter of its strata earlier, the odd half later, so each is off by a
    quarter stratum times the pixel's change from the shutter's opening to its close, in
    opposite directions, which the frame is not; the core adds that change over the grid's
    samples, ``(v_last - v_first) / n``, to the difference (the parts' ``end``, `grid_parts`).
    With ``aa`` 2 and 4 a pixel's value changes in as many steps as it has subsamples, smooth
    over the shutter where the frame's error is small, and without the term the difference read
    1.4x-1.5x (aa 2) and 2.3x-2.6x (aa 4) the error at the median on tuning seeds 0-39 at 96x72,
    with the term 1.0x-1.3x and 1.0x-1.5x. A pixel whose value steps once at a uniformly random
    time moves the difference by the step over n unless the step falls before the first sample
    or after the last (a share 1/n of the shutter, as far off but unseen), and the frame is off
    by the step over n times the step's distance in strata from the nearest stratum edge, whose
    mean square is 1/12. At ``aa`` 1 the term holds too (0.97x-1.02x at the median, 4 to 32
    samples) but costs two more kernel parts a frame, and the plain halves are calibrated there
    (`HALVES_FACTOR`)."""
    return math.sqrt(n / (12.0 * (n - 1)))


#: With ``aa`` 2 or 4, the share of the plain halves' reading (their difference without the end
#: term, read with `HALVES_FACTOR`) that the estimate never goes under. A pixel's subsamples
#: step one after another at a fixed spacing in time (an outline at constant speed crosses them
#: in turn); when that spacing is about an odd number of strata, successive steps fall in
#: strata of opposite halves and cancel in the halves' difference with the end term while they
#: add in the frame's error (an icosphere moving 8 pixels read 0.32x its error at 16 samples,
#: ``aa`` 2; 2.27x at 8, 1.61x at 24). The plain difference keeps the term of each half's shift,
#: which does not cancel so, and over-reads instead (1.5x the error at the median at ``aa`` 2,
#: 2.4x at ``aa`` 4). The shares are the largest (in steps of 0.05) that kept the share of
#: frames read within 0.5x-2x of their error within 0.3 points of the reading without them on
#: tuning seeds 0-299 at 64x48 and 0-149 at 96x72 (4 to 32 samples); estimates under 0.5x the
#: error went from 18 and 4 frames to 10 and 0 (``aa`` 2), from 19 and 7 to 10 and 0 (``aa`` 4).
PLAIN_SHARE = {2: 0.6, 4: 0.3}


#: With ``aa`` 4, the halves' reading over-reads where a frame's samples are about as many as
#: the pixels its moving outlines travel: a pixel's 4 x 4 subsamples are crossed by an outline
#: in turn, about a quarter of a stratum apart when N is that path, so their steps fall at
#: phases a quarter apart within their strata and the frame's errors cancel over the pixel,
#: while the halves' difference (of strata twice as long) cancels only in part. On the tuning
#: seeds (0-79 at 64x48 and 96x72, 0-39 at 192x144; 4 to 128 samples; against `mb.exact` at
#: ``aa`` 4) the reading's median over the error rose from about 1.0 at N / path under 0.1 and
#: over 2 to 1.9 at N / path 0.7-1.5, where 60-65% of the frames were read within 0.5x-2x
#: (``path``: `_sweep.sweep_path`). The estimate is the reading over ``1 + h exp(-ln(N / (x0
#: path))^2 / (2 w^2))`` with ``(h, x0, w)`` = RESONANCE[aa]: of heights 0.2-1.2, centres
#: 0.6-2 and widths 0.4-1.3 on those rows, the lowest height of those that left no more frames
#: under 0.5x than the reading did (3 of 1,720), taking the share within 0.5x-2x from 88% to
#: 96%-99% per size.
RESONANCE = {4: (0.4, 1.0, 0.6)}


def resonance(n: int, path: float, aa: int) -> float:
    """The over-read of the halves' reading at ``aa`` for ``n`` samples of a scene whose moving
    outlines travel ``path`` pixels (`RESONANCE`): at least 1, and 1 where ``aa`` has none or
    nothing moves on screen."""
    if aa not in RESONANCE or not path > 0.0:
        return 1.0
    h, x0, w = RESONANCE[aa]
    return 1.0 + h * math.exp(-(math.log(n / (x0 * path)) ** 2) / (2.0 * w * w))


def grid_parts(
    n: int,
    sampling: str = "stratified",
    drawn: np.ndarray | None = None,
    ends: bool = False,
    residues: bool = False,
) -> list[tuple[np.ndarray, int, int | None, int]]:
    """How samples ``drawn`` (indices into a grid of N; default all) are drawn in `HalfSums`:
    ``(indices, half, quarter, end)`` parts, the even and the odd samples, or the four quarters
    ``j % 4`` of a whole stratified grid of at most `QUARTERS_MAX` samples that 4 divides
    (`rate_factor`); with ``residues`` a stratified grid's samples are drawn in the four parts
    ``j % 4`` at any N (without a quarter beyond those: a grid that `_refine` may reweight
    part by part); with ``ends`` (a frame of ``aa`` 2 or 4) a stratified grid of an even N has
    its first and its last sample apart, ``end`` -1 and +1 (`ends_factor`; 0 for the others).
    No part is empty."""
    j = np.arange(n) if drawn is None else np.asarray(drawn, np.int64)
    quarters = drawn is None and sampling == "stratified" and n % 4 == 0 and n <= QUARTERS_MAX
    if quarters or (residues and sampling == "stratified"):
        groups = [(j[j % 4 == q], q % 2, q if quarters else None) for q in range(4)]
    else:
        groups = [(j[j % 2 == h], h, None) for h in (0, 1)]
    if not ends or sampling != "stratified" or n % 2:
        return [(idx, half, q, 0) for idx, half, q in groups if len(idx)]
    parts = []
    for idx, half, q in groups:
        first, last = idx[idx == 0], idx[idx == n - 1]
        parts += [(first, half, q, -1), (idx[(idx != 0) & (idx != n - 1)], half, q, 0), (last, half, q, 1)]
    return [p for p in parts if len(p[0])]


def rate_factor(halves_sq: float, quarters_sq: float) -> float:
    """The estimate's factor, at least 1, from the mean squared difference of the two halves
    (``halves_sq``) and of the two quarters within each half (``quarters_sq``, averaged over the
    halves). Their ratio rho = sqrt(quarters_sq / halves_sq) is 2^r for an error falling as
    N^-r. Two estimates of one integral whose errors have correlation c differ by
    sqrt(2 (1 - c)) times each one's error, and their mean is sqrt((1 + c) / 2) times it; an
    error falling as N^-r means (1 + c) / 2 = 4^-r, so the mean's error is
    f(r) = 2^-r / (2 sqrt(1 - 4^-r)) times the halves' difference. `HALVES_FACTOR` holds for the
    regular rate r = 1 (opposed halves); the factor is f(r) / f(1) for r = log2(rho) within
    [0.5, 1] (0.5: independent halves, at most 1.73), never below 1 (a faster rate is left to
    `HALVES_FACTOR`'s measured value)."""
    if not (halves_sq > 0.0 and quarters_sq > 0.0):
        return 1.0
    r = min(1.0, max(0.5, 0.5 * float(np.log2(quarters_sq / halves_sq))))

    def f(r: float) -> float:
        return 2.0**-r / (2.0 * (1.0 - 4.0**-r) ** 0.5)

    return max(1.0, f(r) / f(1.0))


def _nearest_part(times: list[np.ndarray], target: float) -> int:
    """The first of the parts (each its ``times``) holding the time nearest ``target``: the
    part `HalfSums` keeps depth and ids for, and pastes."""
    return min(range(len(times)), key=lambda k: float(np.min(np.abs(times[k] - target))))


def _nearest(values: np.ndarray, target: float) -> int:
    """The position in ``values`` of the value nearest ``target``."""
    return int(np.argmin(np.abs(values - target)))


def _strata(n: int, sampling: str, seed: int) -> np.ndarray:
    """(N,) float64 points of [0, 1): ``(i + 0.5) / N`` stratified, ``(i + u_i) / N`` jittered."""
    if sampling == "stratified":
        u = np.full(n, 0.5)
    elif sampling == "jittered":
        u = np.random.default_rng(as_int(seed, "seed", minimum=0)).random(n)
    else:
        raise ValueError(f"sampling: expected 'stratified' or 'jittered', got {sampling!r}")
    return (np.arange(n) + u) / n


#: Knots of the tabulated shutter CDF that `shutter_quantiles` inverts for the gaussian filter
#: (no closed-form inverse): the piecewise-linear table is within ~1e-7 of W.
QUANTILE_KNOTS = 4097


@lru_cache(maxsize=16)
def _cdf_table(shutter) -> tuple[np.ndarray, np.ndarray]:
    knots = np.linspace(0.0, 1.0, QUANTILE_KNOTS)
    return knots, shutter_cdf(shutter, knots)


def _trapezoid_quantiles(shape: Trapezoid, u: np.ndarray) -> np.ndarray:
    """W^-1(u) of a trapezoid (its rise, hold and fall inverted in closed form; (0, 0): u)."""
    o, c = shape.open, shape.close
    h = 1.0 / (1.0 - 0.5 * (o + c))
    rise = np.sqrt(2.0 * o * u / h) if o > 0 else np.zeros_like(u)
    fall = 1.0 - np.sqrt(np.maximum(2.0 * c * (1.0 - u) / h, 0.0)) if c > 0 else np.ones_like(u)
    return np.where(u < 0.5 * h * o, rise, np.where(u <= h * (1.0 - c - 0.5 * o), u / h + 0.5 * o, fall))


def shutter_quantiles(shutter, u) -> np.ndarray:
    """(N,) float64 shutter times ``t`` with ``W(t) = u`` for ``u`` (N,) in [0, 1], ``W`` the
    shutter's cumulative weight (`motionblur.scene.shutter_cdf`): the first such time (for
    ``u = 0`` the last, where the shutter opens), so a time never falls inside a part of zero
    weight, except the left end of a gap in the middle of the shutter (at that gap's level of
    ``u``). Closed form for the box (``t = u``, bit for
    bit), ramp, triangle and `Trapezoid`; a (M,) weights shutter inverts its piecewise-linear W
    exactly; the gaussian inverts W tabulated at `QUANTILE_KNOTS` points."""
    u = np.asarray(u, np.float64)
    if isinstance(shutter, str) and shutter in ("box", "ramp", "triangle"):
        if shutter == "box":
            return u.copy()
        if shutter == "ramp":
            return np.sqrt(u)
        return np.where(u <= 0.5, np.sqrt(0.5 * u), 1.0 - np.sqrt(0.5 * (1.0 - u)))
    if isinstance(shutter, Trapezoid):
        return _trapezoid_quantiles(shutter, u)
    if isinstance(shutter, np.ndarray):
        knots = np.linspace(0.0, 1.0, len(shutter) + 1)
        cum = shutter_cdf(shutter, knots)
    else:
        knots, cum = _cdf_table(shutter)
    k = np.clip(np.searchsorted(cum, u, side="left") - 1, 0, len(knots) - 2)
    d = cum[k + 1] - cum[k]
    f = np.clip((u - cum[k]) / np.where(d > 0, d, 1.0), 0.0, 1.0)
    t = knots[k] + (knots[k + 1] - knots[k]) * f
    # u = 0 (the trapezoid grid's first time): where the shutter opens, the last time W is 0,
    # not time 0 when the shutter starts closed
    opens = knots[np.clip(np.searchsorted(cum, 0.0, side="right") - 1, 0, len(knots) - 1)]
    return np.where(u <= 0.0, opens, t)


def sample_times(scene: Scene, n: int, sampling: str = "stratified", seed: int = 0):
    """(times (N,), weights (N,)) of N shutter samples of equal weight: the shutter's mass cut
    into N equal strata, sample i at the stratified (``u = (i + 0.5) / N``) or jittered
    (``u = (i + u_i) / N``) point of its stratum, time ``W^-1(u)`` (`shutter_quantiles`; W
    the shutter's cumulative weight). Weights are the strata's mass, 1/N each (summing to 1).
    Under the box shutter the times are ``(i + 0.5) / N``; under any shutter the times of N
    samples are among those of k N for odd k, which is how ``auto`` refines a frame."""
    n = as_int(n, "samples", minimum=1, maximum=MAX_TIME_SAMPLES)
    u = _strata(n, sampling, seed)
    edges = np.arange(n + 1) / n
    w = np.diff(edges)
    return shutter_quantiles(scene.shutter, u), w / w.sum()


def uniform_times(n: int, sampling: str = "stratified", seed: int = 0) -> np.ndarray:
    """(N,) float64 times of N equal strata of the whole shutter interval (not of its mass):
    stratified ``(i + 0.5) / N`` or jittered; the rolling shutter's renders, which every pixel
    row weighs by its own window's filter (`motionblur.methods.accumulation.rolling_accumulation`)."""
    n = as_int(n, "samples", minimum=1, maximum=MAX_TIME_SAMPLES)
    return _strata(n, sampling, seed)


class Piece(NamedTuple):
    """One accumulation before it is pasted into a frame (`accumulate_piece`): ``base``
    (rgba, depth, ids) the pixels outside ``window`` (read-only: the static layer's, or the
    whole frame with a moving camera), ``window`` (x0, y0, x1, y1) the pixels drawn (None when
    nothing was) and ``drawn`` (rgba, depth, ids) there, ``stats`` the kernel call's."""

    base: tuple[np.ndarray, np.ndarray, np.ndarray]
    window: tuple[int, int, int, int] | None
    drawn: tuple[np.ndarray, np.ndarray, np.ndarray] | None
    stats: dict
    owned: bool = False  # ``base`` is this piece's own (a moving camera's whole frame)

    def pasted(self, keep: bool = False) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(rgba, depth, ids) of the full frame: the base with the drawn pixels pasted in, in
        fresh arrays (an owned base is handed over as it is unless ``keep``: the piece is used
        again)."""
        rgba, depth, ids = self.base if self.owned and not keep else (a.copy() for a in self.base)
        if self.window is not None:
            x0, y0, x1, y1 = self.window
            rgba[y0:y1, x0:x1], depth[y0:y1, x0:x1], ids[y0:y1, x0:x1] = self.drawn
        return rgba, depth, ids

    def frame(self) -> Frame:
        """The full frame (`pasted`), with a zero velocity."""
        rgba, depth, ids = self.pasted()
        frame = Frame(rgba, depth, ids, np.zeros((*rgba.shape[:2], 2), np.float32))
        frame.stats.update(self.stats)
        return frame


def accumulate(scene: Scene, times, weights, ref: int, dim: float, aa: int) -> Frame:
    """The accumulation buffer of ``times`` with ``weights`` (summing to 1), depth and ids of
    sample ``ref``; the method's body (see `accumulation`)."""
    return accumulate_piece(scene, times, weights, ref, dim, aa).frame()


def accumulate_piece(scene: Scene, times, weights, ref: int, dim: float, aa: int) -> Piece:
    """`accumulate` before its pixels are pasted into a frame (`Piece`): `HalfSums` sums many
    such over their window without copying a frame for each."""
    return PieceMaker(scene, aa)(times, weights, ref, dim)


class _StillParts:
    """A still camera's split of the objects: the static layer of ``static_objs`` and the painter
    of ``moving`` (drawn at every sample), with the core's camera options and layer arrays."""

    def __init__(self, scene: Scene, cam, static_objs, moving, aa: int) -> None:
        c = np.ascontiguousarray
        self.static = static_layer(scene, cam, static_objs, aa)
        self.static_draws = 0 if (self.static.cached or not static_objs) else 1
        self.painter = painter_for(scene, moving, eye=cam.pose[:3, 3])
        self.camera = {
            "view": c(cam.view), "projection": c(cam.projection), "view_projection": c(cam.view_projection),
            "width": cam.width, "height": cam.height, "aa": aa,
        }  # fmt: skip
        layer = self.static.layer
        self.layer = Layer(c(layer.rgba), c(layer.depth), c(layer.ids))


class PieceMaker:
    """What every `accumulate_piece` of one scene sets up once (the camera, the static layer, the
    painter of the objects drawn at every sample), called with ``(times, weights, ref, dim)``
    for each piece: `HalfSums` draws all its parts with one."""

    def __init__(self, scene: Scene, aa: int) -> None:
        self.scene, self.aa = scene, aa
        self.cam = supersampled(scene.camera, aa)
        self._everything = list(enumerate(scene.objects))
        self._static_objs = [(k, o) for k, o in self._everything if not o.is_moving]
        self._moving = [(k, o) for k, o in self._everything if o.is_moving]
        self._transparent = any(o.is_transparent for o in scene.objects)
        self._still: dict[bool, _StillParts] = {}
        self._painter = None

    def _parts(self, dim: float) -> _StillParts:
        """The still camera's split (`_StillParts`) for a piece of dimming ``dim``."""
        # A transparent surface between two others cannot be composited with one depth a pixel
        # per layer: every object is drawn at every sample, sorted together (exact).
        together = dim >= 1.0 and bool(self._static_objs) and self._transparent
        if together not in self._still:
            split = ([], self._everything) if together else (self._static_objs, self._moving)
            self._still[together] = _StillParts(self.scene, self.cam, *split, self.aa)
        return self._still[together]

    def pieces(
        self, parts: list[tuple[np.ndarray, np.ndarray, int]], dim: float, keep: int | None = None
    ) -> list[Piece]:
        """``self(times, weights, ref, dim)`` of each of ``parts``: a still camera's in one core
        call (`motionblur._core._Painter.accumulate_still_parts`), the same pieces. With
        ``keep`` a part's index, only that piece gets depth and ids (the others' ``drawn`` are
        (rgba, None, None): they cannot be `Piece.pasted`), without supersampling only."""
        if self.scene.camera_moves:
            return [self._moving_piece(t, w, ref, dim) for t, w, ref in parts]
        split = self._parts(dim)
        outs = split.painter.core.accumulate_still_parts(
            [{"times": t, "weights": w, "reference": ref} for t, w, ref in parts],
            split.camera, split.layer, split.static.opaque, keep if self.aa == 1 else None,
        )  # fmt: skip
        return [self._still_piece(split, len(t), out, dim) for (t, _, _), out in zip(parts, outs)]

    def _still_piece(self, parts: _StillParts, samples: int, out, dim: float) -> Piece:
        """The `Piece` of a still-camera core call's ``out`` over ``samples`` samples."""
        static = parts.static
        stats = {"samples": samples, "draw_calls": 0, "static_draws": parts.static_draws, "window": None}
        stats["static_cached"] = static.cached
        base = (static.rgba, static.depth, static.ids)
        if out is None:
            return Piece(base, None, None, stats)
        win, acc, depth, ids, stats["draw_calls"] = out
        stats["window"] = win
        x0, y0, x1, y1 = win
        if dim < 1.0:
            acc = (1.0 - dim) * parts.layer.rgba[y0:y1, x0:x1] + dim * acc
        acc = np.asarray(acc, np.float32)
        drawn = (acc, None, None) if depth is None else resolve_arrays(Layer(acc, depth, ids), self.aa)
        return Piece(base, tuple(v // self.aa for v in win), drawn, stats)

    def __call__(self, times, weights, ref: int, dim: float) -> Piece:
        return self.pieces([(times, weights, ref)], dim)[0]

    def _moving_piece(self, times, weights, ref: int, dim: float) -> Piece:
        """A moving camera's piece: whole frames at every sample, one view each."""
        scene, aa, cam = self.scene, self.aa, self.cam
        stats = {"samples": len(times), "draw_calls": len(times), "static_draws": 0, "window": None}
        if self._painter is None:
            self._painter = painter_for(scene, self._everything)
        views = np.linalg.inv(scene.camera_poses_at(times))  # each sample's camera_at(t).view
        rgba, depth, ids = self._painter.core.accumulate_moving(
            {"times": times, "weights": weights, "reference": ref}, views,
            np.ascontiguousarray(cam.projection), cam.width, cam.height,
        )  # fmt: skip
        if dim < 1.0:
            cam = supersampled(scene.camera_at(scene.reference_t), aa)
            static = [(o, object_draw(o, scene.reference_t, k)) for k, o in self._static_objs]
            rgba = (1.0 - dim) * raster_layer(cam, scene, static).rgba + dim * rgba
        # The core's float32 sum as it is: astype would copy the whole frame (a dim < 1 blend is float64)
        whole = resolve_arrays(Layer(np.asarray(rgba, np.float32), depth, ids), aa)
        return Piece(whole, None, None, stats, owned=True)


class Part(NamedTuple):
    """One kernel call's samples in `HalfSums`: the ``half`` (0 or 1) and ``quarter`` (0 to 3,
    ``half == quarter % 2``; None when the grid is not drawn in quarters) they belong to, their
    ``times`` and ``weights`` (the shutter's mass of each one's stratum), the `Piece` drawn and
    ``end``: -1 for a stratified grid's first sample, +1 for its last, else 0 (`ends_factor`)."""

    half: int
    times: np.ndarray
    weights: np.ndarray
    piece: Piece
    quarter: int | None = None
    end: int = 0


class HalfSums:
    """An accumulation kept as its even and odd halves of time samples (see the module docs).

    ``add(times, weights, half)`` renders ``times`` (weights: the shutter's mass of each one's
    stratum, on the frame's final grid) into half 0 or 1 (``add_all`` takes a ``quarter`` and
    an ``end`` too);
    `regrid` moves every sample rendered so far onto a finer grid that holds its time, with that
    grid's weight (each part keeping its samples' relative weights); `frame` is
    the sum with ``stats["error_estimate"]`` from the halves (`HALVES_FACTOR`, or `ends_factor`
    for a stratified grid of an even count, at least `PLAIN_SHARE` of the plain halves' reading,
    and for one drawn in quarters `rate_factor` from the quarters: the halves' reading, kept as
    ``reading``) over its `resonance` at this ``aa``."""

    def __init__(self, scene: Scene, aa: int, sampling: str = "stratified") -> None:
        self.scene, self.aa, self.sampling = scene, aa, sampling
        self.parts: list[Part] = []
        self.maker = PieceMaker(scene, aa)
        self.path: float | None = None  # `_sweep.sweep_path`, once an estimate at an aa of `RESONANCE` asks
        self.reading = 0.0  # the last `frame`'s halves' reading, before `resonance`

    def add(self, times, weights, half: int) -> None:
        self.add_all([(times, weights, half)])

    def add_grid(
        self, times: np.ndarray, weights: np.ndarray, drawn: np.ndarray | None = None, residues: bool = False
    ) -> None:
        """`add_all` of the samples ``drawn`` (indices; default all) of the grid of ``times`` and
        ``weights`` (N,), in `grid_parts`' parts for this sampling (by ``j % 4`` with
        ``residues``), with the end term when ``aa`` is above 1."""
        parts = grid_parts(len(times), self.sampling, drawn, ends=self.aa > 1, residues=residues)
        self.add_all([(times[k], weights[k], *rest) for k, *rest in parts])

    def add_all(self, parts) -> None:
        """`add` of each ``(times, weights, half)`` or ``(times, weights, half, quarter, end)`` of
        ``parts``, drawn in one core call."""
        got = []
        for times, weights, half, *quarter in parts:
            times, weights = (
                np.ascontiguousarray(times, np.float64),
                np.ascontiguousarray(weights, np.float64),
            )
            got.append((half, times, weights, _nearest(times, self.scene.reference_t), *quarter))
        # the one part `frame` may paste: the first holding the time nearest the reference (the
        # first of all calls' parts is the first of its own call's)
        keep = _nearest_part([g[1] for g in got], self.scene.reference_t)
        pieces = self.maker.pieces([(g[1], g[2] / float(g[2].sum()), g[3]) for g in got], 1.0, keep)
        self.parts.extend(Part(g[0], g[1], g[2], p, *g[4:]) for g, p in zip(got, pieces))

    def regrid(self, times: np.ndarray, weights: np.ndarray, half: np.ndarray) -> np.ndarray | None:
        """Every sample drawn moved onto a new grid of nodes: ``times`` (K,) increasing, each
        node's ``weights`` (the shutter's mass it stands for) and ``half`` (0 or 1). A sample
        takes the weight and half of the node nearest its time; its part moves to that half, no
        longer an end or a quarter (the new grid's ends are new samples). A part was summed with
        its samples' relative weights, so it can move only when its new weights are positive,
        proportional to its old ones and of one half: when a part cannot, nothing changes and
        the result is None. Else (K,) bool: the nodes a drawn sample now stands for (the others
        are the new grid's samples still to draw)."""
        moved = []
        for part in self.parts:
            at = np.atleast_1d(time_index(times, part.times))
            ratio = weights[at] / part.weights
            if not (ratio > 0).all() or np.ptp(ratio) > 1e-9 * ratio.max() or np.ptp(half[at]):
                return None
            moved.append((at, Part(int(half[at[0]]), part.times, weights[at], part.piece)))
        held = np.zeros(len(times), bool)
        for at, _ in moved:
            held[at] = True
        self.parts = [p for _, p in moved]
        return held

    @property
    def samples(self) -> int:
        return sum(len(p.times) for p in self.parts)

    def _window(self) -> tuple[int, int, int, int] | None:
        """The pixels (x0, y0, x1, y1) any part drew moving objects in (the whole image with a
        moving camera), None when none did: outside it every part is the same static layer."""
        h, w = self.parts[0].piece.base[0].shape[:2]
        if self.scene.camera_moves:
            return 0, 0, w, h
        wins = [p.piece.stats["window"] for p in self.parts if p.piece.stats["window"] is not None]
        if not wins:
            return None
        return tuple(f(v[i] for v in wins) // self.aa for i, f in enumerate((min, min, max, max)))

    def _quartered(self) -> bool:
        """Whether the grid is stratified and drawn in four quarters of equal samples."""
        if self.sampling != "stratified" or any(p.quarter is None for p in self.parts):
            return False
        counts = [sum(len(p.times) for p in self.parts if p.quarter == q) for q in range(4)]
        return min(counts) > 0 and len(set(counts)) == 1

    def halves(self, win: tuple[int, int, int, int]):
        """Over ``win`` (x0, y0, x1, y1), in one core pass (`motionblur._core._halves`): the sums
        of squares of the halves' difference with the end term (`ends_factor`) composited over the
        scene's background, drawn in quarters of the two quarters within each half, summed
        over both halves (else None), and with an end term of the difference without it (else
        None; `PLAIN_SHARE`);
        the frame (float32) and the halves' masses: each half the mean of its parts by their
        masses, the frame both halves by theirs."""
        c = np.ascontiguousarray
        quartered = self._quartered()
        masses = [float(p.weights.sum()) for p in self.parts]
        total = sum(masses)
        parts = [
            (
                p.half,
                m,
                c(p.piece.base[0]),
                p.piece.window,
                None if p.piece.window is None else c(p.piece.drawn[0]),
                p.quarter // 2 if quartered else None,
                p.end * m / total,
            )
            for p, m in zip(self.parts, masses)
        ]
        bg = np.asarray(self.scene.background, np.float64)
        pre = (float(bg[0] * bg[3]), float(bg[1] * bg[3]), float(bg[2] * bg[3]), float(bg[3]))
        return _core._halves(parts, win, pre)

    def frame(self) -> Frame:
        nearest = self.parts[_nearest_part([p.times for p in self.parts], self.scene.reference_t)].piece
        (rgba, depth, ids), square_sum, plain_sq, factor = nearest.pasted(keep=True), 0.0, None, 1.0
        win = self._window()
        if win is not None:  # the halves' sums over the window only
            (square_sum, quarters_sq, plain_sq), inside, (ma, mb) = self.halves(win)
            rgba[win[1] : win[3], win[0] : win[2]] = inside
            m = (ma * mb) ** 0.5 / (ma + mb)
            if quarters_sq is not None:
                factor = rate_factor(square_sum, quarters_sq / 2.0)
        frame = Frame(rgba, depth, ids, None)
        calls = [p.piece.stats for p in self.parts]
        wins = [c["window"] for c in calls if c["window"] is not None]
        frame.stats.update(
            samples=self.samples,
            draw_calls=sum(c["draw_calls"] for c in calls),
            static_draws=max(c["static_draws"] for c in calls),
            static_cached=calls[0].get("static_cached", False),
            window=tuple(f(w[i] for w in wins) for i, f in enumerate((min, min, max, max))) if wins else None,
        )
        base = ends_factor(self.samples) if any(p.end for p in self.parts) else HALVES_FACTOR[self.sampling]
        scale = base * 2.0 * m * factor if win is not None else 0.0
        estimate = scale * np.sqrt(square_sum / rgba.size)
        if plain_sq is not None:  # never under a share of the plain halves' reading
            plain = HALVES_FACTOR[self.sampling] * 2.0 * m * np.sqrt(plain_sq / rgba.size)
            estimate = max(estimate, PLAIN_SHARE[self.aa] * plain)
        self.reading = float(estimate)
        frame.stats["error_estimate"] = self.reading / self._resonance()
        frame.stats["error_estimate_how"] = "halves: the even and the odd time samples compared"
        return frame

    def _resonance(self) -> float:
        """`resonance` of this frame's samples (the scene's path found once); 1 for a grid other
        than the stratified one (jittered, trapezoid, refined: not measured so)."""
        if self.aa not in RESONANCE or self.sampling != "stratified":
            return 1.0
        if self.path is None:
            self.path = sweep_path(self.scene)
        return resonance(self.samples, self.path, self.aa)


def time_index(times: np.ndarray, t) -> np.ndarray | int:
    """The index in ``times`` (increasing) of the time nearest each of ``t`` (or of the scalar)."""
    x = np.asarray(t, np.float64)
    if len(times) == 1:
        k = np.zeros(x.shape, np.int64)
    else:
        k = np.clip(np.searchsorted(times, x), 1, len(times) - 1)
        k = np.where(x - times[k - 1] < times[k] - x, k - 1, k)
    return int(k) if k.ndim == 0 else k


def add_stratified(sums: HalfSums, scene: Scene, n: int, kept: int = 0, residues: bool = False) -> None:
    """Accumulation's own ``n`` stratified samples of ``scene`` (`sample_times`) added to
    ``sums``. With ``kept``, the count of the stratified grid ``sums`` already holds (``n`` an odd
    multiple of it, so that its times are among the new ones under any shutter, whose strata are
    of the shutter's mass): those samples are kept, each weighted 1/n and moved to the half of
    its new position, and only the others are drawn. With ``residues`` the samples drawn are in
    parts by their position modulo 4 (`grid_parts`); a kept grid drawn so stays so, since sample
    ``i`` of it is sample ``k i + (k - 1) / 2`` of the new one, whose residue depends on
    ``i % 4`` alone for odd ``k``."""
    times, weights = sample_times(scene, n)
    new = None  # a fresh grid: all of it, in halves or in quarters (`HalfSums.add_grid`)
    if kept:
        step = n // kept
        if step * kept != n or step % 2 == 0:
            raise ValueError(f"n: expected an odd multiple of kept={kept}, got {n}")
        held = sums.regrid(times, np.full(n, 1.0 / n), np.arange(n) % 2)
        if held is None:  # the kept grid's samples are on it, every one weighing 1/n
            raise ValueError(f"kept: the grid sums holds is not the stratified grid of {kept}")
        new = np.flatnonzero(~held)  # the new times only (never the new grid's ends)
    sums.add_grid(times, weights, new, residues)
