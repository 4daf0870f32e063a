"""Rendering methods, one module each; importing this package registers all of them.

Adding a method is adding a module here that decorates its function with
[`motionblur.render.register`][motionblur.render.register], and importing it below. The modules whose names start with
an underscore hold what the methods share, and a method imports them, never another method:
``_layers`` (rasterizing into layers, compositing, supersampling, the static layer kept across
frames), ``_painter`` (objects drawn at any shutter time, per-mesh constants),
``_volume_colors`` (the colours of motion volumes), ``_sharp`` (the sharp frame the image-space
methods blur), ``_accumulate`` (the accumulation kernel call and its two halves of samples) and
``_estimate`` (the exact reference [`exact`][motionblur.methods.exact] and every frame's error estimate).
"""

from __future__ import annotations

from . import (  # each registers its methods
    accumulation,
    analytic,
    auto,  # the planner: it calls the others through the registry, at render time
    blur_shell,
    image_space,
    motion_volume,
)
from ._estimate import exact  # noqa: F401  (motionblur.exact)
from ._layers import clear_static_cache

__all__ = [
    "accumulation",
    "analytic",
    "auto",
    "blur_shell",
    "image_space",
    "motion_volume",
    "clear_static_cache",
]
