"""The error estimate every frame carries: its RMSE against the exact time integral.

``render()`` puts ``stats["error_estimate"]`` on every frame: the estimated RMSE of the frame
(premultiplied linear RGBA, composited over the scene's background, all four channels) against
[`exact`][motionblur.methods._estimate.exact] of the same scene at the same ``aa`` (the
analytic method's: against the exact limit, `limit`). A method that can measure its own error does
so (accumulation compares the halves of its samples, `accumulation`); every other method and
option set is estimated by a pilot (`pilot_estimate`), with no fitted factor:

- **the pilot**: the method on the scene seen by a smaller camera (`pilot_pixels`: a sixth of
  the frame's pixels, at least `PILOT_PIXELS` (64x48) and at most `PILOT_MAX_PIXELS` (128x96),
  the field of view unchanged) at the full frame's time structure: the motion volume
  is cut at the full frame's pieces, the analytic method's chord tolerance (pixels) is scaled
  with the image, so that both cut the shutter where the full frame does;
- **its reference**: accumulation at the pilot's size, grown from `REFERENCE_FIRST` samples
  (keeping those drawn) until its own estimate is at most `REFERENCE_SHARE` of the method's
  pilot RMSE, else (and under a rolling shutter)
  [`exact`][motionblur.methods._estimate.exact]: a reference a quarter as far off adds at most
  3% to the estimate, at a fraction of the exact integral's cost. The analytic method's pilot
  is held to its own segments each cut into `ANALYTIC_SPLIT` (`refined`, 4 Gauss points): a
  vertex's distance from its chord, and with it the error of every sample, falls by the
  square of the split, with the same sign, so the difference is ``1 - 1 / split**2`` of the
  pilot's error and is taken up by that (Richardson's step); and none of its segments is
  longer than `ANALYTIC_LONGEST`, so that the quadrature of a long piece whose shading swings
  (which no segment rule cuts where the motion is straight) is resolved too, nor, where an
  object deforms, than `ANALYTIC_DEFORMING_LONGEST`, so that a depth crossing within the
  time a turning triangle covers a sample (taken as linear in depth there) is too. Its estimate is
  its RMSE against the exact limit (`limit`), not against ``exact``, which is itself about a
  quarter as far off as the analytic default;
- **the frame's size**: a frame larger than the pilot gets a second pilot at a quarter of the
  pixels; an error along edges shrinks with the pixel size (MSE ``a + b / s``), one over areas
  does not, and the two pilots say how much of each (`_extrapolated`);
- **the analytic method's frame size**: its error is in its time structure, the same in every
  sample at any size (the pilot cuts the shutter where the frame does), but it is
  heavy-tailed: a sample an edge crosses nearly along itself is off by the chord's distance
  over the edge's slow normal speed (up to a piece's length of the shutter), so a frame of more
  samples holds larger single errors, and its RMSE grows with its pixel count until the rare
  large ones are common. No much smaller pilot predicts where a frame's few large errors
  fall, so a frame of at most `ANALYTIC_OWN_PIXELS` (1920x1080) is its own pilot: the
  estimate is then its measured error against the reference, and the frame is the one
  ``render`` made (passed in), so that the estimate costs the reference alone, about twice
  the frame's time. A larger frame (1440p, 4K) has for its pilot the largest image of the
  same field of view within `ANALYTIC_OWN_PIXELS` (`analytic_pilot_size`: 1920x1080 for
  both), and the pilot's estimate is the frame's, not carried to the frame's pixel count: a
  pilot of a quarter of the frame's pixels or more holds its own rare large errors about as
  often per pixel as the frame does (on tuning scenes it read 0.78x-1.17x of 4K and 1440p
  frames, and carrying its tail did not help; `ANALYTIC_OWN_PIXELS`), and with its
  reference it costs about what the 4K render does, where the frame's own reference would
  cost twice that, and the memory of a second 4K frame.

The rules were chosen on the tuning scenes of
[`motionblur.evaluation.random_scenes`][motionblur.evaluation.random_scenes] only (but the
analytic method's `ANALYTIC_LONGEST` and `ANALYTIC_OWN_PIXELS`, added for misses diagnosed on
measuring scenes, then measured on fresh ones; `ANALYTIC_DEFORMING_LONGEST` is for a kind of
miss first seen on a measuring scene, found and chosen on tuning scenes); the calibration on
the measuring scenes is in the docs (validation.md).
"""

from __future__ import annotations

import inspect
import math
import time

import numpy as np

from ..raster import Camera, Frame, over_background
from ..render import ESTIMATOR, METHODS
from ..scene import Scene
from ._accumulate import HalfSums, add_stratified
from .analytic import refined
from .motion_volume import piece_bounds, pieces_frame

__all__ = [
    "exact",
    "EXACT_OPTIONS",
    "pilot_estimate",
    "PILOT_PIXELS",
    "PILOT_SHARE",
    "PILOT_MAX_PIXELS",
    "pilot_pixels",
    "PILOT_FACTOR",
    "REFERENCE_FIRST",
    "REFERENCE_MAX",
    "REFERENCE_SHARE",
    "ANALYTIC_SPLIT",
    "ANALYTIC_LONGEST",
    "ANALYTIC_DEFORMING_LONGEST",
    "ANALYTIC_OWN_PIXELS",
    "analytic_pilot_size",
    "LIMIT_OPTIONS",
    "limit",
    "pilot_errors",
    "pilot_scene",
]

#: The analytic method's options for the exact time integral (chord tolerance in pixels, Gauss
#: points per piece): its distance from the true integral is stated in the docs (validation.md).
EXACT_OPTIONS = {"tolerance": 0.002, "gauss": 4}
#: Fewest pixels of the pilot render (the image is scaled down to about `pilot_pixels`, never
#: up); a frame larger than the pilot gets a second, coarse pilot of a quarter of its pixels.
PILOT_PIXELS = 64 * 48
#: The pilot's share of the frame's pixels, between `PILOT_PIXELS` and `PILOT_MAX_PIXELS`
#: (`pilot_pixels`): a pilot of 4% of a 320x240 frame's pixels read its error at 0.29x-3.8x on
#: tuning seeds 0-59 (181 frames, one under 0.5x), one of 16% at 0.76x-2.15x; an error held by
#: a few edges depends on where they fall on a small pilot's pixels.
PILOT_SHARE = 1.0 / 6.0
#: Most pixels of the pilot render (128x96 at 4:3): its cost, with its reference, grows with them.
PILOT_MAX_PIXELS = 128 * 96
#: The pilot's reference for every method but ``analytic``: accumulation at the pilot's size
#: with this many samples first (two halves of 8, the fewest whose estimate `auto` trusts), grown
#: while its own (halves) estimate is over `REFERENCE_SHARE` of the method's pilot RMSE: to the
#: least odd multiple of its samples (which keeps those drawn) that reaches the count its error
#: asks for at 1/N; where that count is over `REFERENCE_MAX`,
#: [`exact`][motionblur.methods._estimate.exact] at the pilot's size instead.
REFERENCE_FIRST = 16
#: The most samples the pilot's accumulated reference's error may ask for (`REFERENCE_FIRST`);
#: the odd multiple it grows to may pass it (at most 3x: 432 samples grow to 1296).
REFERENCE_MAX = 1024
#: The pilot reference's largest own error, as a share of the method's pilot RMSE (it adds at
#: most 3% to the estimate in quadrature).
REFERENCE_SHARE = 0.25
#: The analytic method's pilot reference: the pilot's own segments (its chord tolerance scaled
#: with the image, or its ``segments``) each cut into this many equal ones, at 4 Gauss points
#: (`refined`): a vertex's distance from its chord falls by the square, and so does the
#: reference's error next to the pilot's (the pilot's RMSE against it is taken up by
#: ``split**2 / (split**2 - 1)``). 2 costs about what the pilot does; 4 moved the tuning
#: estimates by no more than the scenes' spread, at twice the cost.
ANALYTIC_SPLIT = 2
#: ... and no segment of the reference longer than this share of the shutter: the analytic
#: method's other error is its Gauss quadrature (at most 4 points a piece) over a long visible
#: piece of one triangle whose shading swings across it, which a straight motion (one segment)
#: does not cut at all.
ANALYTIC_LONGEST = 0.125
#: ... or than this one where a moving object deforms (vertex keyframes): the analytic method
#: takes a triangle's depth at a sample as linear over the time it covers the sample, and a
#: deforming triangle turns within a segment (the vertices move straight, so the segment rule
#: keeps the keyframes' segments whole), so where two surfaces cross in depth (an object
#: through the floor) the crossing is off by up to a few thousandths of the shutter. A
#: covering span that no cut of the reference falls in keeps that error exactly (spans are
#: cut only at segment boundaries), so the reference must cut spans shorter than the frame's
#: segments: the error left in an uncut span falls as the square of its length. It costs more
#: only where the frame's segments are longer than this (a deforming mesh whose normals the
#: segment rule cuts for is cut finer already): up to about 5x the frame's render there, ~2x elsewhere.
ANALYTIC_DEFORMING_LONGEST = 1 / 32
#: The largest frame (pixels) the analytic method's pilot is the frame itself for (the frame
#: ``render`` made, so that only its reference is rendered, about twice the frame's time): its
#: error is heavy-tailed (one to three pixels may hold most of a frame's MSE), where they fall
#: no much smaller pilot predicts (on tuning scenes at 192x144 and 320x240, pilots of 3072 to 19200
#: pixels, carried to the frame's pixels or not, missed 0.5x-2x on 7-20% of frames, down to
#: 0.2x; at 640x480, pilots of 3072 to 76800 pixels read 0.1-0.2x of a frame whose own read
#: was 1.1x; at 960x540 the frame's own read 1.03x-1.14x on tuning seeds, where the 160x120
#: pilot carried had read 0.26x-3.1x on measuring seeds). A larger frame's pilot is the largest
#: image of its field of view within these pixels (`analytic_pilot_size`), its estimate taken
#: as the frame's: on tuning seeds 301-307 at 3840x2160 and 2560x1440 the 1920x1080 pilot read
#: 0.78x-1.17x on the 7 frames with an error of at least 1e-6 (0.97x-1.78x on the 5 with less),
#: and carrying its tail to the frame's pixels (`n**beta`, half the trend) moved the low one
#: to 0.80x and raised the rest (to 2.44x where one pilot pixel held 37% of its MSE). At 4K it
#: costs about what the render does; at 1440p the frame's own pilot (0.97x-1.12x on its 4
#: frames) would cost about a sixth more. A user who renders many
#: frames and needs no estimate passes ``error_estimate=False``.
ANALYTIC_OWN_PIXELS = 1920 * 1080
#: The exact limit the analytic estimate is against (`limit`): the analytic method at a chord
#: tolerance of 2e-4 px and 4 Gauss points, each segment cut into 4 (whatever the segment cap)
#: and none longer than 1/64 of the shutter; cutting each into 8, or none longer than 1/128,
#: moves it by under a tenth of the analytic default's error on the tuning scenes (docs:
#: validation.md).
LIMIT_OPTIONS = {"tolerance": 0.0002, "gauss": 4, "split": 4, "longest": 1 / 64}
#: Measured error over pilot RMSE, by method (chosen on the tuning scenes; none is needed).
PILOT_FACTOR: dict[str, float] = {}
_DEFAULT_FACTOR = 1.0


def exact(scene: Scene, aa: int = 1) -> Frame:
    """The exact time integral of ``scene``: the analytic method at `EXACT_OPTIONS`,
    composited over the scene's background. ``aa`` 1, 2 or 4 samples per pixel along each axis.
    Returns a [`Frame`][motionblur.methods._estimate.Frame] of the camera's size (``rgba`` (H,W,4) float32 premultiplied linear
    RGBA); its ``stats["error_estimate"]`` is 0: it is the reference every estimate is against."""
    frame = METHODS["analytic"].fn(scene, aa=aa, **EXACT_OPTIONS)
    frame = over_background(frame, scene.background)
    frame.stats["error_estimate"] = 0.0
    frame.stats["error_estimate_how"] = "exact: the reference itself"
    return frame


def limit(scene: Scene, aa: int = 1) -> Frame:
    """The exact time integral's limit, as far as it is measured here: the analytic method at
    `LIMIT_OPTIONS` (`refined`), composited over the scene's background; ``aa`` as in
    [`exact`][motionblur.methods._estimate.exact]. Returns a Frame (``rgba`` (H,W,4) float32
    premultiplied linear RGBA). The analytic method's estimate is its RMSE against this; it
    costs about 16x ``exact`` (used to calibrate, not by ``render``)."""
    frame = refined(scene, aa, **LIMIT_OPTIONS)
    return over_background(frame, scene.background)


def pilot_pixels(width: int, height: int) -> int:
    """The pilot's pixels for a frame of ``width`` x ``height``: `PILOT_SHARE` of the frame's,
    at least `PILOT_PIXELS` and at most `PILOT_MAX_PIXELS` (never more than the frame's)."""
    return int(min(width * height, PILOT_MAX_PIXELS, max(PILOT_PIXELS, round(width * height * PILOT_SHARE))))


def pilot_scene(
    scene: Scene, pixels: int = PILOT_PIXELS, size: tuple[int, int] | None = None
) -> tuple[Scene, float]:
    """``(scene seen by a smaller camera, scale)``: the camera's image scaled by ``scale`` <= 1
    so that it has about ``pixels`` pixels, or is ``size`` (width, height) when given (the
    field of view unchanged; ``scale`` the pilot's width over the frame's)."""
    cam = scene.camera
    if size is not None:
        w, h = int(size[0]), int(size[1])
        if not (2 <= w <= cam.width and 2 <= h <= cam.height):
            raise ValueError(f"size: expected 2x2 to the frame's {cam.width}x{cam.height}, got {w}x{h}")
        if (w, h) == (cam.width, cam.height):
            return scene, 1.0
    else:
        scale = min(1.0, math.sqrt(pixels / (cam.width * cam.height)))
        if scale >= 1.0:
            return scene, 1.0
        w, h = max(2, round(cam.width * scale)), max(2, round(cam.height * scale))
    small = Camera(cam.pose, cam.yfov, w, h, cam.znear, cam.zfar)
    return scene.with_(camera=small), w / cam.width


def analytic_pilot_size(width: int, height: int, own_pixels: int = ANALYTIC_OWN_PIXELS) -> tuple[int, int]:
    """``(width, height)`` of the analytic method's pilot for a frame of ``width`` x ``height``:
    the frame itself up to ``own_pixels`` pixels, else the largest image of the same field of
    view of at most ``own_pixels`` (the frame's sides scaled by one factor, each rounded down:
    1920x1080 for 3840x2160 and for 2560x1440 at the default)."""
    if own_pixels < 4:
        raise ValueError(f"own_pixels: expected at least 4 (a 2x2 pilot), got {own_pixels}")
    if width * height <= own_pixels:
        return width, height
    scale = math.sqrt(own_pixels / (width * height))
    w = max(2, math.floor(width * scale + 1e-9))  # 0.5 * 3840 is 1920, not 1919.9999
    h = max(2, math.floor(height * scale + 1e-9))
    while w * h > own_pixels:  # the 1e-9 above, or the 2-pixel floor of a thin frame
        if w > 2 and (h <= 2 or w * height > h * width):
            w -= 1
        else:
            h -= 1
    return w, h


def _aa(method: str, options: dict) -> int:
    if "aa" in options:
        return int(options["aa"])
    p = inspect.signature(METHODS[method].fn).parameters.get("aa")
    return int(p.default) if p is not None and p.default is not p.empty else 1


def _pilot_options(method: str, options: dict, scale: float) -> dict:
    """``options`` for the pilot: the analytic method's chord tolerance (pixels; its default
    when not given) scaled with the image, so that the pilot cuts the shutter where the frame does."""
    out = dict(options)
    if method == "analytic":
        default = inspect.signature(METHODS[method].fn).parameters["tolerance"].default
        out["tolerance"] = float(out.get("tolerance", default)) * scale
    return out


def is_exact(method: str, options: dict) -> bool:
    """Whether ``method`` with ``options`` is [`exact`][motionblur.methods._estimate.exact] itself."""
    return (
        method == "analytic"
        and all(options.get(k) == v for k, v in EXACT_OPTIONS.items())
        and not (set(options) - {"aa", *EXACT_OPTIONS})
    )


def _pilot_frame(scene: Scene, small: Scene, scale: float, method: str, options: dict) -> Frame:
    """``method`` with ``options`` rendered on ``small`` (the pilot camera); the motion volume
    is cut at the full frame's pieces (its limit on a turn in place is in pixels)."""
    if method != "motion_volume":
        return METHODS[method].fn(small, **_pilot_options(method, options, scale))
    opts = {
        k: p.default
        for k, p in list(inspect.signature(METHODS[method].fn).parameters.items())[1:]
        if p.default is not p.empty
    }
    opts.update(options)
    if opts["filter"] is None and isinstance(scene.shutter, str):
        opts["filter"] = scene.shutter
    bounds = piece_bounds(scene, opts["filter"], opts["spin"], opts.pop("pieces"))
    return pieces_frame(small, bounds, opts)


def _reference(small: Scene, options: dict, method: str, aa: int, rgba: np.ndarray) -> np.ndarray:
    """The pilot's reference RGBA (float64, over the background): see `REFERENCE_FIRST`; the
    analytic method's is its pilot's segments (``options``, the pilot's) each cut into
    `ANALYTIC_SPLIT` at 4 Gauss points, none longer than `ANALYTIC_LONGEST` (than
    `ANALYTIC_DEFORMING_LONGEST` where a moving object deforms)."""
    if method != "analytic":
        # under a rolling shutter accumulation has no halves: the exact frame, which models it
        ref = None if small.rolling > 0.0 else _accumulated_reference(small, aa, rgba)
        return exact(small, aa).rgba.astype(np.float64) if ref is None else ref
    cuts = {k: options[k] for k in ("tolerance", "segments") if k in options}
    deforms = any(o.is_moving and o.motion.is_deforming for o in small.objects)
    longest = ANALYTIC_DEFORMING_LONGEST if deforms else ANALYTIC_LONGEST
    ref = refined(small, aa, gauss=4, split=ANALYTIC_SPLIT, longest=longest, **cuts)
    return over_background(ref, small.background).rgba.astype(np.float64)


def _accumulated_reference(small: Scene, aa: int, rgba: np.ndarray) -> np.ndarray | None:
    """Accumulation on ``small`` grown from `REFERENCE_FIRST` samples until its own estimate is
    at most `REFERENCE_SHARE` of the RMSE of ``rgba`` against it (RGBA float64, over the
    background), or None when the count its error asks for is over `REFERENCE_MAX`."""
    sums, n, drawn = HalfSums(small, aa), REFERENCE_FIRST, 0
    while True:
        add_stratified(sums, small, n, drawn)
        acc = sums.frame()
        ref = over_background(acc, small.background).rgba.astype(np.float64)
        share = REFERENCE_SHARE * _rmse(rgba, ref)
        est = sums.reading  # the halves' own reading: at aa 4 above the estimate near resonance
        if est <= share:
            return ref
        wanted = n * est / share if share > 0.0 else math.inf
        if wanted > REFERENCE_MAX:
            return None
        drawn, n = n, n * _odd_at_least(wanted / n)


def _odd_at_least(x: float) -> int:
    """The least odd integer of at least ``max(x, 3)``."""
    k = max(3, math.ceil(x))
    return k + 1 - k % 2


def pilot_errors(
    scene: Scene,
    method: str,
    options: dict,
    pixels: int = PILOT_PIXELS,
    rgba: np.ndarray | None = None,
    size: tuple[int, int] | None = None,
    per_pixel: bool = False,
) -> dict:
    """The pilot at about ``pixels`` pixels: ``{"rmse", "unblurred", "mass", "scale", "size"}``,
    the RMSE of ``method`` and of the sharp mid-shutter frame against the pilot's reference (see
    `REFERENCE_FIRST`) at that size, ``mass`` the method's alpha mass over the reference's less
    1 (`alpha_mass_error`), ``scale`` the pilot's width over the frame's; with
    ``per_pixel`` also ``"pixel_mse"`` (h,w) float64, the method's squared error per pixel (mean
    over RGBA; a study of where the error lies, not used by the estimate).
    ``rgba``: the analytic frame itself (H,W,4, over the background), when the pilot is the
    frame (``pixels`` at least the frame's): used instead of rendering it again. ``size``:
    the pilot's (width, height) instead of ``pixels`` (`pilot_scene`)."""
    small, scale = pilot_scene(scene, pixels, size)
    aa = _aa(method, options)
    if rgba is not None and method == "analytic" and scale >= 1.0:
        if rgba.shape != (scene.camera.height, scene.camera.width, 4):
            raise ValueError(f"rgba: expected the frame's ({scene.camera.height}, {scene.camera.width}, 4)")
    else:
        frame = _pilot_frame(scene, small, scale, method, options)
        rgba = over_background(frame, small.background).rgba
    ref = _reference(small, _pilot_options(method, options, scale), method, aa, rgba)
    # the unblurred frame as accumulation's one sample renders it: where the scene's shutter has
    # half its weight (mid-shutter under the box; under a weighted shutter the box's middle can
    # be far from it and read a blur worse than none as better)
    sharp = METHODS["accumulation"].fn(small, samples=1, aa=aa)
    out = {
        "rmse": _rmse(rgba, ref),
        "unblurred": _rmse(over_background(sharp, small.background).rgba, ref),
        "mass": alpha_mass_error(rgba, ref),
        "scale": scale,
        "size": f"{small.camera.width}x{small.camera.height}",
    }
    if per_pixel:
        out["pixel_mse"] = np.mean(np.square(rgba.astype(np.float64) - ref), axis=-1)
    return out


def _extrapolated(fine: dict, coarse: dict) -> float:
    """The frame's RMSE from the pilots at two sizes: MSE ``a + b / s`` (``s`` the pilot's
    scale: an error over areas stays, one along edges shrinks with the pixel size), fitted to
    the two with ``a``, ``b`` >= 0 and taken at ``s`` = 1 (between the fine pilot's RMSE, all
    area, and that times sqrt(its scale), all edges); the estimate is the geometric mean of that
    and the fine pilot's RMSE."""
    m1, m0, s1, s0 = fine["rmse"] ** 2, coarse["rmse"] ** 2, fine["scale"], coarse["scale"]
    if s1 >= 1.0 or s0 >= s1:
        return fine["rmse"]
    b = min(max((m0 - m1) / (1.0 / s0 - 1.0 / s1), 0.0), m1 * s1)
    fitted = math.sqrt(m1 - b / s1 + b)
    # half the trend (in log): a 32x24 pilot is too coarse for its slope to be taken whole
    return math.sqrt(fine["rmse"] * fitted)


def pilot_estimate(
    scene: Scene,
    method: str,
    options: dict,
    frame: Frame | None = None,
    *,
    own_pixels: int = ANALYTIC_OWN_PIXELS,
) -> dict:
    """``{"error_estimate", "error_estimate_how", "estimate_ms", "unblurred_estimate"}`` of
    ``method`` with ``options`` on ``scene`` from a pilot render (see the module docs);
    ``unblurred_estimate`` is the same measure of the unblurred frame (accumulation's one sample:
    the sharp frame where the shutter's weight reaches half, mid-shutter under the box), so that a blur
    worse than none is seen ([`PoorBlurWarning`][motionblur.PoorBlurWarning]). ``frame``: the
    frame ``render`` made (over the background, no lens), which an analytic frame that is its
    own pilot uses instead of rendering itself again. ``own_pixels``: the analytic method's
    largest frame that is its own pilot (`analytic_pilot_size`; ``render`` uses
    `ANALYTIC_OWN_PIXELS`)."""
    t0 = time.perf_counter()
    if is_exact(method, options):
        return {
            "error_estimate": 0.0,
            "error_estimate_how": "exact: the reference itself",
            "estimate_ms": 0.0,
        }
    if method == "analytic":
        return _analytic_estimate(scene, options, frame, t0, own_pixels)
    pixels = pilot_pixels(scene.camera.width, scene.camera.height)
    p = pilot_errors(scene, method, options, pixels)
    est, how = p["rmse"], f"pilot: the method against the exact integral at {p['size']}"
    if p["scale"] < 1.0 and est > 0.0:
        coarse = pilot_errors(scene, method, options, pixels // 4)
        est = _extrapolated(p, coarse)
        how += f" and {coarse['size']}, extrapolated to the frame's size"
    return _estimate_stats(PILOT_FACTOR.get(method, _DEFAULT_FACTOR) * est, how, p, t0)


def _analytic_estimate(scene: Scene, options: dict, frame: Frame | None, t0: float, own_pixels: int) -> dict:
    """`pilot_estimate` of the analytic method: the frame itself (``frame`` when given) up to
    ``own_pixels``, else the largest pilot of the same field of view within them
    (`analytic_pilot_size`), against its refined segments and taken to the limit."""
    cam = scene.camera
    size = analytic_pilot_size(cam.width, cam.height, own_pixels)
    own = size == (cam.width, cam.height)
    rgba = frame.rgba if frame is not None and own else None
    p = pilot_errors(scene, "analytic", options, rgba=rgba, size=size)
    est = p["rmse"] * (ANALYTIC_SPLIT**2 / (ANALYTIC_SPLIT**2 - 1))
    how = f"pilot: the method against its segments cut in {ANALYTIC_SPLIT} at {p['size']}, taken to the exact limit"
    return _estimate_stats(PILOT_FACTOR.get("analytic", _DEFAULT_FACTOR) * est, how, p, t0)


def _estimate_stats(est: float, how: str, pilot: dict, t0: float) -> dict:
    return {
        "error_estimate": est,
        "error_estimate_how": how,
        "estimate_ms": (time.perf_counter() - t0) * 1e3,
        "unblurred_estimate": pilot["unblurred"],
        "alpha_mass_estimate": pilot["mass"],
    }


def alpha_mass_error(rgba: np.ndarray, ref: np.ndarray) -> float:
    """The alpha mass of ``rgba`` (H,W,4) over that of ``ref`` (H,W,4), less 1 (+0.5: half as
    much coverage again as the exact frame's), the reference's mass taken as at least 1% of the
    pixels (so that a nearly empty frame does not divide by nearly 0)."""
    exact = float(np.sum(ref[..., 3], dtype=np.float64))
    ours = float(np.sum(rgba[..., 3], dtype=np.float64))
    return (ours - exact) / max(exact, 0.01 * ref.shape[0] * ref.shape[1])


def _rmse(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.square(a.astype(np.float64) - b))))


ESTIMATOR[:] = [pilot_estimate]
