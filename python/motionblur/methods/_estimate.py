"""The error estimate every frame carries: its RMSE against the exact time integral.

``render()`` puts ``stats["error_estimate"]`` on every frame: the estimated RMSE of the frame
(premultiplied linear RGBA, composited over the scene's background, all four channels) against
:func:`exact` of the same scene at the same ``aa``. A method that can measure its own error does
so (accumulation compares the halves of its samples, :mod:`.accumulation`); for every other
method and option set, :func:`pilot_estimate` renders the scene again at a low resolution
(about :data:`PILOT_PIXELS` pixels) with the method and with :func:`exact`, and scales their RMSE
by the method's :data:`PILOT_FACTOR`. The factors were chosen on the tuning scenes of
:mod:`motionblur.evaluation.random_scenes` only; the calibration on the measuring scenes is in
the README.
"""

from __future__ import annotations

import inspect
import math
import time

import numpy as np

from ..raster import Camera, Frame, over_background
from ..render import ESTIMATOR, METHODS
from ..scene import Scene

__all__ = ["exact", "EXACT_OPTIONS", "pilot_estimate", "PILOT_PIXELS", "PILOT_FACTOR", "pilot_scene"]

#: The analytic method's options for the exact time integral (chord tolerance in pixels, Gauss
#: points per piece): its distance from the true integral is stated in the README.
EXACT_OPTIONS = {"tolerance": 0.002, "gauss": 4}
#: Pixels of the pilot render (the image is scaled down to about this many, never up).
PILOT_PIXELS = 64 * 48
#: Measured error over pilot RMSE, by method (chosen on the tuning scenes).
PILOT_FACTOR: dict[str, float] = {}
_DEFAULT_FACTOR = 1.0


def exact(scene: Scene, aa: int = 1) -> Frame:
    """The exact time integral of ``scene``: the analytic method at :data:`EXACT_OPTIONS`,
    composited over the scene's background. ``aa`` 1, 2 or 4 samples per pixel along each axis.
    Returns a :class:`Frame` of the camera's size (``rgba`` (H,W,4) float32 premultiplied linear
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
    """Whether ``method`` with ``options`` is :func:`exact` itself."""
    return (
        method == "analytic"
        and all(options.get(k) == v for k, v in EXACT_OPTIONS.items())
        and not (set(options) - {"aa", *EXACT_OPTIONS})
    )


def pilot_estimate(scene: Scene, method: str, options: dict) -> dict:
    """``{"error_estimate", "error_estimate_how", "estimate_ms"}`` of ``method`` with ``options``
    on ``scene`` from a pilot render (see the module docs)."""
    t0 = time.perf_counter()
    if is_exact(method, options):
        return {
            "error_estimate": 0.0,
            "error_estimate_how": "exact: the reference itself",
            "estimate_ms": 0.0,
        }
    small, scale = pilot_scene(scene)
    frame = over_background(
        METHODS[method].fn(small, **_pilot_options(method, options, scale)), small.background
    )
    ref = exact(small, _aa(method, options))
    err = float(np.sqrt(np.mean(np.square(frame.rgba.astype(np.float64) - ref.rgba))))
    factor = PILOT_FACTOR.get(method, _DEFAULT_FACTOR)
    return {
        "error_estimate": factor * err,
        "error_estimate_how": f"pilot: the method and the exact integral at {small.camera.width}x{small.camera.height}",
        "estimate_ms": (time.perf_counter() - t0) * 1e3,
    }


ESTIMATOR[:] = [pilot_estimate]
