"""A forecast of accumulation's error from the scene's geometry alone, before anything renders:
the screen sweep. ``auto`` reads it to choose how many samples its first render draws; the
render's own halves then certify the frame (a forecast never does).

With one sample a pixel, a pixel an outline passes over changes its colour once during the
shutter, and N stratified time samples place that step to within half a stratum: its error is
about the contrast over N sqrt(12). The pixels that step are those the moving outlines sweep,
about an object's outline on screen times the distance its surface travels there. So the error
of N samples scales as `sweep_scale` / N, where

    sweep_scale**2 = sum over moving objects of perimeter x path x contrast**2 / pixels,

``perimeter`` twice the sides of the screen bounding box at mid-shutter of the object's `POINTS`
surface points (pixels, clipped to the image) plus one, ``path`` the mean screen distance those
points travel over `TIMES` shutter times (pixels, the points seen at some time), ``contrast``
the RMS over RGBA of the premultiplied difference the object's colour at `SHADE` makes over the
background (with a colour a vertex, the RMS over the vertices too). Under camera motion every object moves. It runs in the compiled core
(``src/motion/sweep.rs``) in microseconds.
"""

from __future__ import annotations

import numpy as np

from .. import _core
from ..scene import Scene

__all__ = ["sweep_scale", "sweep_path", "TIMES", "POINTS", "SHADE"]

#: Shutter times the surface points are followed at (evenly spaced, both ends included).
TIMES: int = int(_core.SWEEP_TIMES)
#: Surface points followed per object (at most four a face).
POINTS: int = int(_core.SWEEP_POINTS)
#: The shading factor of an object's colour in its contrast (a typical lambert shade).
SHADE: float = float(_core.SWEEP_SHADE)


def sweep_scale(scene: Scene) -> float:
    """The scene's screen sweep (see the module docs), about ``sqrt(12)`` x the RMSE of one
    accumulation sample a pixel before `auto.FIRST_FIT` maps it to an error; 0.0 when nothing
    that moves is seen."""
    return _sweep(scene)[0]


def sweep_path(scene: Scene) -> float:
    """The mean screen path (pixels over the shutter) of the moving outlines, each object's
    ``path`` weighted by its share of `sweep_scale` squared: how far the outlines the error
    comes from travel; 0.0 when nothing that moves is seen."""
    return _sweep(scene)[1]


def _sweep(scene: Scene) -> tuple[float, float]:
    """(scale, path) of the compiled core's `motionblur._core._sweep` for ``scene``."""
    objects = scene.objects if scene.camera_moves else [o for o in scene.objects if o.is_moving]
    cam = scene.camera
    motion = scene.camera_motion
    options = {
        "objects": [
            {
                "mesh": o.mesh._core,
                "motion": None if o.motion is None else o.motion._keys,
                "rgba": np.ascontiguousarray(o.rgba, np.float64).reshape(-1, 4),
            }
            for o in objects
        ],
        "width": cam.width,
        "height": cam.height,
        "projection": cam.projection,
        "pose": cam.pose,
        "camera_motion": None if motion is None else motion._keys,
        "background": np.asarray(scene.background, np.float64),
    }
    scale, path = _core._sweep(options)
    return float(scale), float(path)
