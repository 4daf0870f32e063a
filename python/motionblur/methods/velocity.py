"""The per-object velocity-buffer post-process of game engines and Blender EEVEE (method
``velocity``): McGuire et al. 2012's reconstruction filter with Guertin et al. 2014's
improvements, on the rasterizer's velocity and depth buffers.

The scene is rasterized once, sharp, at the centroid of the shutter (0.5 for a box shutter),
with every moving object's screen motion over the whole shutter in the velocity buffer (per
vertex, so a deforming or turning object has its own velocity at every pixel), and
:func:`motionblur.image.reconstruction_blur` gathers each pixel from the pixels whose motion
reaches it: the tile max and neighbour max velocities say how far to look, the depth buffer
splits the taps into foreground (blurred over the pixel) and background (filling what the
foreground leaves). It is what users pick instead of motion volumes; the report measures it
beside Kraus's ``opaque_image`` and Chapman's ``camera_velocity``.

Limits (the method's): one sharp frame, so a surface hidden at mid-shutter is never shown
(the background behind a moving object is filled from its neighbours), motion is taken as
straight and uniform over the shutter, and the shutter is a box.
"""

from __future__ import annotations

import numpy as np

from .. import image
from .._validate import as_float, as_int
from ..raster import Frame
from ..render import register
from ..scene import Scene
from ._sharp import check_aa, require_box_shutter, sharp_frame, shutter_centroid

__all__ = ["velocity"]


@register(
    "velocity",
    sweep=[{"samples": n} for n in (8, 16, 32)],
    applies=lambda scene: bool(scene.moving_objects) and not scene.camera_moves,
    needs="moving objects seen by a still camera",
)
def velocity(scene: Scene, samples: int = 16, aa: int = 1, tile=None, soft_depth: float = 0.02) -> Frame:
    """The velocity-buffer post-process (McGuire 2012 / Guertin 2014, module docs).

    Options: ``samples`` gather taps per pixel, even, in [2, 256]; ``aa`` 1, 2 or 4 spatial
    samples per pixel along each axis for the sharp frame; ``tile`` tile size in pixels
    (default: half the longest velocity, at least 8, so no motion is shortened); ``soft_depth``
    depth difference relative to depth over which a tap turns from foreground to background.
    A moving camera is not folded in (use ``camera_velocity``); a shutter other than a box
    raises ValueError naming ``shutter``. ``stats``: ``t`` (time of the sharp frame),
    ``samples``, ``tile``, ``max_velocity`` (pixels over the shutter).
    """
    samples = as_int(samples, "samples", minimum=2, maximum=image.MAX_TAPS)
    if samples % 2:
        raise ValueError(f"samples: must be even (taps come in pairs), got {samples}")
    aa = check_aa(aa)
    if tile is not None:
        tile = as_int(tile, "tile", minimum=1, maximum=1 << 16)
    soft_depth = as_float(soft_depth, "soft_depth")
    if not soft_depth > 0:
        raise ValueError(f"soft_depth: must be > 0, got {soft_depth}")
    require_box_shutter(scene, "velocity")
    if scene.camera_moves:
        raise ValueError(
            "scene: the velocity method blurs the objects' own motion seen by a still camera; "
            "this camera moves (use camera_velocity, accumulation or motion_volume)"
        )
    tc = shutter_centroid(scene)
    frame = sharp_frame(scene, tc, aa, velocity="shutter")
    vel = np.ascontiguousarray(frame.velocity, dtype=np.float32)
    vmax = float(np.sqrt((vel.astype(np.float64) ** 2).sum(axis=-1)).max())
    if tile is None:
        tile = max(8, int(np.ceil(0.5 * vmax)))
    rgba = image.reconstruction_blur(frame.rgba, frame.depth, vel, samples, tile, soft_depth)
    out = Frame(rgba, frame.depth, frame.ids, frame.velocity)
    out.stats.update(t=tc, samples=samples, tile=tile, max_velocity=vmax)
    return out
