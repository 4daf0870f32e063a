"""What the image-space methods share: the sharp frame they blur, the time it is taken at, and
the shutter they can honour.

An image-space method renders the scene once, sharp, at the centroid ``t_c`` of the shutter
filter (0.5 for a box shutter), so that a blur centred on each pixel covers the whole shutter,
and then blurs that frame's pixels with a box (uniform) weight along each pixel's motion. Such a
blur honours a box shutter only (or custom weights that are all equal):
`require_box_shutter` raises for any other, naming ``shutter``, instead of blurring it as
a box.
"""

from __future__ import annotations

import numpy as np

from .._validate import as_samples
from ..raster import Draw, Frame, rasterize
from ..scene import Scene, Trapezoid

__all__ = ["shutter_centroid", "sharp_frame", "require_box_shutter", "check_aa"]


def require_box_shutter(scene: Scene, method: str) -> None:
    """Raise ValueError naming ``shutter`` unless the scene's shutter is a box (the name, or
    custom weights all equal): ``method`` blurs with a uniform weight over the shutter."""
    sh = scene.shutter
    if isinstance(sh, Trapezoid):
        if sh.open == 0.0 and sh.close == 0.0:
            return
        what = f"shutter curve {sh!r}"
    elif isinstance(sh, str):
        if sh == "box":
            return
        what = repr(sh)
    else:
        w = np.asarray(sh, dtype=np.float64)
        if np.all(w == w[0]):
            return
        what = f"custom weights {np.array2string(w, precision=3, threshold=8)}"
    raise ValueError(
        f"shutter: {method} blurs each pixel with a box (uniform) shutter and cannot honour the "
        f"scene's {what}; use accumulation or blur_shell (any shutter) or motion_volume (named filters)"
    )


def check_aa(aa) -> int:
    """``aa`` as 1, 2 or 4 (spatial samples per pixel along each axis), else ValueError."""
    return as_samples(aa, "aa")


def shutter_centroid(scene: Scene) -> float:
    """The mean time of the scene's shutter filter, ``1 - integral_0^1 W(t) dt`` (W its CDF)."""
    t = np.linspace(0.0, 1.0, 1025)
    w = scene.shutter_cdf(t)
    return float(np.clip(1.0 - np.sum((w[1:] + w[:-1]) * 0.5) / 1024.0, 0.0, 1.0))


def _aa(aa) -> int:
    return as_samples(aa, "aa")


def sharp_frame(scene: Scene, t: float, aa: int = 1, velocity: str | None = "shutter") -> Frame:
    """The scene rasterized at shutter time ``t`` by ``scene.camera_at(t)``, ids the object
    indices. The velocity buffer of each moving object holds (``velocity="shutter"``) its world
    motion over the whole shutter seen by that camera (``previous_vertices = x(t) - (x(1) -
    x(0))``), or (``"since_open"``) its apparent motion since the shutter opened, the camera's
    own motion folded in (``previous_vertices = P(t) P(0)^-1 x(0)``, P the camera pose), or
    (None) nothing. One rasterizer call, each object with its own shading mode, so that its
    depth test and its transparency are per sample whatever the modes."""
    cam = scene.camera_at(t)
    fold = scene.camera_pose_at(t) @ np.linalg.inv(scene.camera_pose_at(0.0))
    draws: list[Draw] = []
    for k, o in enumerate(scene.objects):
        v = o.world_vertices(t)
        prev = None
        if velocity == "shutter" and o.is_moving:
            prev = v - (o.world_vertices(1.0) - o.world_vertices(0.0))
        elif velocity == "since_open" and o.is_moving:
            prev = o.world_vertices(0.0) @ fold[:3, :3].T + fold[:3, 3]
        draws.append(Draw(v, o.mesh.faces, o.rgba, object_id=k, previous_vertices=prev, shading=o.shading))
    if not draws:
        h, w = cam.height, cam.width
        return Frame(
            np.zeros((h, w, 4), np.float32),
            np.full((h, w), np.inf, np.float32),
            np.full((h, w), -1, np.int32),
            np.zeros((h, w, 2), np.float32),
        )
    return rasterize(cam, draws, samples=aa, shading="flat", lights=scene.lights, ambient=scene.ambient)
