"""The error estimate every frame carries: its RMSE against the exact time integral.

``render()`` puts ``stats["error_estimate"]`` on every frame: the estimated RMSE of the frame
(premultiplied linear RGBA, composited over the scene's background, all four channels) against
[`exact`][motionblur.methods._estimate.exact] of the same scene at the same ``aa``. A method that can measure its own error does
so (accumulation compares the halves of its samples, `accumulation`); for every other
method and option set, `pilot_estimate` renders the scene again at a low resolution
(about `PILOT_PIXELS` pixels) with the method and with [`exact`][motionblur.methods._estimate.exact], and scales their RMSE
by the method's `PILOT_FACTOR`. The factors were chosen on the tuning scenes of
[`motionblur.evaluation.random_scenes`][motionblur.evaluation.random_scenes] only; the calibration on the measuring scenes is in
the docs (validation.md).
"""

from __future__ import annotations

import inspect
import math
import time

import numpy as np

from ..raster import Camera, Frame, over_background
from ..render import ESTIMATOR, METHODS
from ..scene import Scene

__all__ = [
    "exact",
    "EXACT_OPTIONS",
    "pilot_estimate",
    "PILOT_PIXELS",
    "PILOT_FACTOR",
    "pilot_scene",
]

#: The analytic method's options for the exact time integral (chord tolerance in pixels, Gauss
#: points per piece): its distance from the true integral is stated in the docs (validation.md).
EXACT_OPTIONS = {"tolerance": 0.002, "gauss": 4}
#: Pixels of the pilot render (the image is scaled down to about this many, never up).
PILOT_PIXELS = 64 * 48
#: Measured error over pilot RMSE, by method (chosen on the tuning scenes).
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
    """``options`` for the pilot: pixel lengths scaled with the image."""
    out = dict(options)
    if method == "analytic" and "tolerance" in out:
        out["tolerance"] = float(out["tolerance"]) * scale
    return out


def is_exact(method: str, options: dict) -> bool:
    """Whether ``method`` with ``options`` is [`exact`][motionblur.methods._estimate.exact] itself."""
    return (
        method == "analytic"
        and all(options.get(k) == v for k, v in EXACT_OPTIONS.items())
        and not (set(options) - {"aa", *EXACT_OPTIONS})
    )


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
    small, scale = pilot_scene(scene)
    aa = _aa(method, options)
    frame = METHODS[method].fn(small, **_pilot_options(method, options, scale))
    ref = exact(small, aa).rgba.astype(np.float64)
    sharp = METHODS["accumulation"].fn(small.with_(shutter="box"), samples=1, aa=aa)
    factor = PILOT_FACTOR.get(method, _DEFAULT_FACTOR)
    size = f"{small.camera.width}x{small.camera.height}"
    return {
        "error_estimate": factor * _rmse(over_background(frame, small.background).rgba, ref),
        "error_estimate_how": f"pilot: the method and the exact integral at {size}",
        "estimate_ms": (time.perf_counter() - t0) * 1e3,
        "unblurred_estimate": _rmse(over_background(sharp, small.background).rgba, ref),
    }


def _rmse(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.square(a.astype(np.float64) - b))))


ESTIMATOR[:] = [pilot_estimate]
