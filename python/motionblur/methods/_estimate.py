"""The error estimate every frame carries: its RMSE against the exact time integral.

``render()`` puts ``stats["error_estimate"]`` on every frame: the estimated RMSE of the frame
(premultiplied linear RGBA, composited over the scene's background, all four channels) against
[`exact`][motionblur.methods._estimate.exact] of the same scene at the same ``aa``. A method that can measure its own error does
so (accumulation compares the halves of its samples, `accumulation`); every other method and
option set is estimated by a pilot (`pilot_estimate`), with no fitted factor:

- **the pilot**: the method on the scene seen by a smaller camera (about `PILOT_PIXELS`
  pixels, the field of view unchanged) at the full frame's time structure: the motion volume
  is cut at the full frame's pieces, the analytic method's chord tolerance (pixels) is scaled
  with the image, so that both cut the shutter where the full frame does;
- **its reference**: accumulation at the pilot's size with the first of `REFERENCE_SAMPLES`
  whose own estimate is at most `REFERENCE_SHARE` of the method's pilot RMSE, else
  [`exact`][motionblur.methods._estimate.exact] (the analytic method's pilot is always held to
  ``exact`` with its tolerance scaled the same way): a reference a quarter as far off adds at
  most 3% to the estimate, at a fraction of the exact integral's cost;
- **the frame's size**: a frame larger than the pilot gets a second pilot at a quarter of the
  pixels; an error along edges shrinks with the pixel size (MSE ``a + b / s``), one over areas
  does not, and the two pilots say how much of each (`_extrapolated`; the analytic method's
  error is in its time structure and gets none);
- **the analytic method's floor**: where its pilot differs from the reference at all, its
  estimate is at least `ANALYTIC_FLOOR`, the reference's own distance from the limit: a
  difference smaller than that is not a measured error (the estimate is then a bound).

The rules were chosen on the tuning scenes of
[`motionblur.evaluation.random_scenes`][motionblur.evaluation.random_scenes] only; the
calibration on the measuring scenes is in the docs (validation.md).
"""

from __future__ import annotations

import inspect
import math
import time

import numpy as np

from ..raster import Camera, Frame, over_background
from ..render import ESTIMATOR, METHODS
from ..scene import Scene
from .motion_volume import piece_bounds, pieces_frame

__all__ = [
    "exact",
    "EXACT_OPTIONS",
    "pilot_estimate",
    "PILOT_PIXELS",
    "PILOT_FACTOR",
    "REFERENCE_SAMPLES",
    "REFERENCE_SHARE",
    "ANALYTIC_FLOOR",
    "pilot_errors",
    "pilot_scene",
]

#: The analytic method's options for the exact time integral (chord tolerance in pixels, Gauss
#: points per piece): its distance from the true integral is stated in the docs (validation.md).
EXACT_OPTIONS = {"tolerance": 0.002, "gauss": 4}
#: Pixels of the pilot render (the image is scaled down to about this many, never up); a frame
#: larger than the pilot gets a second, coarse pilot of a quarter of these pixels.
PILOT_PIXELS = 64 * 48
#: The pilot's reference for every method but ``analytic``: accumulation with the first of these
#: sample counts whose own (halves) estimate is at most `REFERENCE_SHARE` of the method's pilot
#: RMSE (a count the last one's error says is too few, at 1/N, is skipped), else
#: [`exact`][motionblur.methods._estimate.exact] at the pilot's size.
REFERENCE_SAMPLES = (64, 256, 1024)
#: The pilot reference's largest own error, as a share of the method's pilot RMSE (it adds at
#: most 3% to the estimate in quadrature).
REFERENCE_SHARE = 0.25
#: The analytic method's smallest estimate (RMSE) where its frame differs from the reference at
#: all: [`exact`][motionblur.methods._estimate.exact]'s own distance from the limit (the
#: largest measured against accumulation with 2**14 samples on the tuning scenes, docs:
#: validation.md); below it a difference from the reference is not a measured error.
ANALYTIC_FLOOR = 3e-5
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


def pilot_scene(scene: Scene, pixels: int = PILOT_PIXELS) -> tuple[Scene, float]:
    """``(scene seen by a smaller camera, scale)``: the camera's image scaled by ``scale`` <= 1
    so that it has about ``pixels`` pixels (the field of view unchanged)."""
    cam = scene.camera
    scale = min(1.0, math.sqrt(pixels / (cam.width * cam.height)))
    if scale >= 1.0:
        return scene, 1.0
    w, h = max(2, round(cam.width * scale)), max(2, round(cam.height * scale))
    small = Camera(cam.pose, cam.yfov, w, h, cam.znear, cam.zfar)
    return scene.with_(camera=small), w / cam.width


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


def _reference(small: Scene, scale: float, method: str, aa: int, rgba: np.ndarray) -> np.ndarray:
    """The pilot's reference RGBA (float64, over the background): see `REFERENCE_SAMPLES`; the
    analytic method's is [`exact`][motionblur.methods._estimate.exact] with its chord tolerance scaled as the pilot's."""
    if method != "analytic":
        wanted = 0.0  # sample count the last reference's own error asks for (it falls as 1/N)
        for n in REFERENCE_SAMPLES:
            if n < wanted:
                continue
            acc = METHODS["accumulation"].fn(small, samples=n, aa=aa)
            ref = over_background(acc, small.background).rgba.astype(np.float64)
            share = REFERENCE_SHARE * _rmse(rgba, ref)
            if acc.stats["error_estimate"] <= share:
                return ref
            wanted = n * acc.stats["error_estimate"] / share if share > 0.0 else math.inf
        return exact(small, aa).rgba.astype(np.float64)
    opts = dict(EXACT_OPTIONS, tolerance=EXACT_OPTIONS["tolerance"] * scale)
    ref = over_background(METHODS["analytic"].fn(small, aa=aa, **opts), small.background)
    return ref.rgba.astype(np.float64)


def pilot_errors(scene: Scene, method: str, options: dict, pixels: int = PILOT_PIXELS) -> dict:
    """The pilot at about ``pixels`` pixels: ``{"rmse", "unblurred", "scale", "size"}``, the
    RMSE of ``method`` and of the sharp mid-shutter frame against the pilot's reference (see
    `REFERENCE_SAMPLES`) at that size, ``scale`` the pilot's width over the frame's."""
    small, scale = pilot_scene(scene, pixels)
    aa = _aa(method, options)
    frame = _pilot_frame(scene, small, scale, method, options)
    rgba = over_background(frame, small.background).rgba
    ref = _reference(small, scale, method, aa, rgba)
    sharp = METHODS["accumulation"].fn(small.with_(shutter="box"), samples=1, aa=aa)
    return {
        "rmse": _rmse(rgba, ref),
        "unblurred": _rmse(over_background(sharp, small.background).rgba, ref),
        "scale": scale,
        "size": f"{small.camera.width}x{small.camera.height}",
    }


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


def pilot_estimate(scene: Scene, method: str, options: dict) -> dict:
    """``{"error_estimate", "error_estimate_how", "estimate_ms", "unblurred_estimate"}`` of
    ``method`` with ``options`` on ``scene`` from a pilot render (see the module docs);
    ``unblurred_estimate`` is the same measure of the sharp frame at mid-shutter, so that a blur
    worse than none is seen ([`PoorBlurWarning`][motionblur.PoorBlurWarning])."""
    t0 = time.perf_counter()
    if is_exact(method, options):
        return {
            "error_estimate": 0.0,
            "error_estimate_how": "exact: the reference itself",
            "estimate_ms": 0.0,
        }
    p = pilot_errors(scene, method, options)
    est, how = p["rmse"], f"pilot: the method against the exact integral at {p['size']}"
    if p["scale"] < 1.0 and est > 0.0 and method != "analytic":
        coarse = pilot_errors(scene, method, options, PILOT_PIXELS // 4)
        est = _extrapolated(p, coarse)
        how += f" and {coarse['size']}, extrapolated to the frame's size"
    if method == "analytic" and est > 0.0:
        est = max(est, ANALYTIC_FLOOR)
    return {
        "error_estimate": PILOT_FACTOR.get(method, _DEFAULT_FACTOR) * est,
        "error_estimate_how": how,
        "estimate_ms": (time.perf_counter() - t0) * 1e3,
        "unblurred_estimate": p["unblurred"],
    }


def _rmse(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.square(a.astype(np.float64) - b))))


ESTIMATOR[:] = [pilot_estimate]
