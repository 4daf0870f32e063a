"""Image-space motion blur of one rasterized frame: Kraus's opaque motion blur per moving object
(``opaque_image``) and Chapman's camera motion blur (``camera_velocity``).

Both render the scene once, sharp, at the centroid ``t_c`` of the shutter filter
(``1 - integral of W(t) dt``; 0.5 for a box shutter), so that a blur centred on each pixel covers
the whole shutter, and then blur the frame's pixels:

* ``opaque_image`` (Kraus 2013, section 4.1): the frame carries each object's screen motion over
  the shutter in its velocity buffer. For every moving object, farthest first, the mask is its
  pixels in the id buffer, the direction and the length are the mean of its velocity there, and
  :func:`motionblur.image.opaque_motion_blur` of the masked layer is composited *over* the frame.
  Applies to scenes with moving objects and a still camera. Limits (the paper's): a static object
  in front of a moving one is painted over, and the background behind the object is never
  disoccluded (the blurred object stays opaque where it was).
* ``camera_velocity`` (Chapman 2011): the velocity of every pixel follows from the frame's depth
  and the camera at the shutter's start (:func:`motionblur.image.camera_velocity`; the sky moves
  only with the camera's rotation) and :func:`motionblur.image.velocity_blur` blurs along it.
  Pixels of moving objects take their rasterized velocity with the camera's motion folded in, so
  an object the camera follows stays sharp. Applies to scenes whose camera moves.
"""

from __future__ import annotations

import numpy as np

from .. import image
from .._validate import as_int
from ..raster import Draw, Frame, rasterize
from ..render import register
from ..scene import Scene

__all__ = ["opaque_image", "camera_velocity", "shutter_centroid"]


def shutter_centroid(scene: Scene) -> float:
    """The mean time of the scene's shutter filter, ``1 - integral_0^1 W(t) dt`` (W its CDF)."""
    t = np.linspace(0.0, 1.0, 1025)
    w = scene.shutter_cdf(t)
    return float(np.clip(1.0 - np.sum((w[1:] + w[:-1]) * 0.5) / 1024.0, 0.0, 1.0))


def _aa(aa) -> int:
    aa = as_int(aa, "aa")
    if aa not in (1, 2, 4):
        raise ValueError(f"aa: must be 1, 2 or 4, got {aa}")
    return aa


def sharp_frame(scene: Scene, t: float, aa: int = 1, velocity: str | None = "shutter") -> Frame:
    """The scene rasterized at shutter time ``t`` by ``scene.camera_at(t)``, ids the object
    indices. The velocity buffer of each moving object holds (``velocity="shutter"``) its world
    motion over the whole shutter seen by that camera (``previous_vertices = x(t) - (x(1) -
    x(0))``), or (``"since_open"``) its apparent motion since the shutter opened, the camera's
    own motion folded in (``previous_vertices = P(t) P(0)^-1 x(0)``, P the camera pose), or
    (None) nothing. One rasterizer call per shading mode, merged per pixel by depth."""
    cam = scene.camera_at(t)
    fold = scene.camera_pose_at(t) @ np.linalg.inv(scene.camera_pose_at(0.0))
    groups: dict[str, list[Draw]] = {}
    for k, o in enumerate(scene.objects):
        v = o.world_vertices(t)
        prev = None
        if velocity == "shutter" and o.is_moving:
            prev = v - (o.world_vertices(1.0) - o.world_vertices(0.0))
        elif velocity == "since_open" and o.is_moving:
            prev = o.world_vertices(0.0) @ fold[:3, :3].T + fold[:3, 3]
        draw = Draw(v, o.mesh.faces, o.rgba, object_id=k, previous_vertices=prev)
        groups.setdefault(o.shading, []).append(draw)
    out = None
    for shading, draws in groups.items():
        f = rasterize(cam, draws, samples=aa, shading=shading, lights=scene.lights, ambient=scene.ambient)
        if out is None:
            out = f
            continue
        front = f.depth < out.depth
        near = np.where(front[..., None], f.rgba, out.rgba)
        far = np.where(front[..., None], out.rgba, f.rgba)
        out = Frame(
            near + (1.0 - near[..., 3:4]) * far,
            np.minimum(f.depth, out.depth),
            np.where(front, f.ids, out.ids),
            np.where(front[..., None], f.velocity, out.velocity),
        )
    if out is None:
        h, w = cam.height, cam.width
        out = Frame(
            np.zeros((h, w, 4), np.float32),
            np.full((h, w), np.inf, np.float32),
            np.full((h, w), -1, np.int32),
            np.zeros((h, w, 2), np.float32),
        )
    return out


@register(
    "opaque_image",
    sweep=[{"aa": a} for a in (1, 2, 4)],
    applies=lambda scene: bool(scene.moving_objects) and not scene.camera_moves,
    needs="moving objects seen by a still camera",
)
def opaque_image(scene: Scene, aa: int = 1) -> Frame:
    """Kraus's image-based opaque motion blur of every moving object (module docs).

    Options: ``aa`` 1, 2 or 4 spatial samples per pixel along each axis for the sharp frame.
    ``stats``: ``t`` (the time of the sharp frame), ``blurred`` (objects blurred) and per object
    ``lengths`` (pixels).
    """
    aa = _aa(aa)
    tc = shutter_centroid(scene)
    frame = sharp_frame(scene, tc, aa, velocity="shutter")
    rgba = frame.rgba
    order = []
    for k, o in enumerate(scene.objects):
        mask = frame.ids == k
        if not o.is_moving or not mask.any():
            continue
        v = frame.velocity[mask].astype(np.float64).mean(axis=0)
        order.append((float(np.mean(frame.depth[mask])), k, v, mask))
    lengths = {}
    for _, k, v, mask in sorted(order, key=lambda e: -e[0]):
        length = float(np.hypot(v[0], v[1]))
        lengths[k] = length
        if length < 1.0:
            continue
        layer = rgba * mask[..., None]
        rgba = image.opaque_motion_blur(layer, (v[0], v[1]), length, mode="over", base=rgba)
    out = Frame(rgba, frame.depth, frame.ids, frame.velocity)
    out.stats.update(t=tc, blurred=len(lengths), lengths=lengths)
    return out


@register(
    "camera_velocity",
    sweep=[{"samples": n} for n in (4, 8, 16, 32)],
    applies=lambda scene: scene.camera_moves,
    needs="a moving camera (Scene(camera_motion=...))",
)
def camera_velocity(scene: Scene, samples: int = 16, aa: int = 1) -> Frame:
    """Chapman's camera motion blur from the frame's depth and the camera's motion (module docs).

    Options: ``samples`` N in [1, 1024] blur taps per pixel; ``aa`` 1, 2 or 4 spatial samples per
    pixel along each axis for the sharp frame. The velocity from the camera at ``t_c`` back to the
    camera at the shutter's start is scaled by ``1 / t_c`` to span the whole shutter. Pixels of
    moving objects take the rasterizer's velocity of the object with the camera's motion folded
    in instead (Chapman's static-scene velocity would blur an object the camera follows).
    ``stats``: ``t``, ``samples``.
    """
    samples = as_int(samples, "samples", minimum=1, maximum=image.MAX_SAMPLES)
    aa = _aa(aa)
    tc = shutter_centroid(scene)
    frame = sharp_frame(scene, tc, aa, velocity="since_open")
    rgba = frame.rgba
    if scene.camera_moves and tc > 0.0:
        cam, start = scene.camera_at(tc), scene.camera_at(0.0)
        vel = image.camera_velocity(frame.depth, cam, start)
        moving = np.isin(frame.ids, [k for k, o in enumerate(scene.objects) if o.is_moving])
        vel = np.where(moving[..., None], frame.velocity, vel) * np.float32(1.0 / tc)
        rgba = image.velocity_blur(rgba, vel, samples)
    out = Frame(rgba, frame.depth, frame.ids, frame.velocity)
    out.stats.update(t=tc, samples=samples)
    return out
