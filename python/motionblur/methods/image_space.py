"""Image-space motion blur of one rasterized frame: Kraus's opaque motion blur per moving object
(``opaque_image``), Chapman's camera motion blur (``camera_velocity``) and the per-pixel
velocity-buffer post-process of game engines and Blender EEVEE (``velocity``).

Both render the scene once, sharp, at the centroid ``t_c`` of the shutter filter
(``1 - integral of W(t) dt``; 0.5 for a box shutter), so that a blur centred on each pixel covers
the whole shutter, and then blur the frame's pixels:

* ``opaque_image`` (Kraus 2013, section 4.1): the frame carries each object's screen motion over
  the shutter in its velocity buffer. For every moving object, farthest first, the mask is its
  pixels in the id buffer, the direction and the length are the mean of its velocity there, and
  [`motionblur.image.opaque_motion_blur`][motionblur.image.opaque_motion_blur] of the masked layer is composited *over* what is
  behind the object and *under* what is in front of it by depth (section 4.1's "under").
  Applies to scenes with moving objects and a still camera. Limit (the paper's): the background
  behind the object is never disoccluded (the blurred object stays opaque where it was, and the
  glow keeps the streak near it opaque), so a motion longer than the object is over-covered.
* ``camera_velocity`` (Chapman 2011): the velocity of every pixel follows from the frame's depth
  and the camera at the shutter's start ([`motionblur.image.camera_velocity`][motionblur.image.camera_velocity]; the sky moves
  only with the camera's rotation) and [`motionblur.image.velocity_blur`][motionblur.image.velocity_blur] blurs along it.
  Pixels of moving objects take their rasterized velocity with the camera's motion folded in, so
  an object the camera follows stays sharp. Applies to scenes whose camera moves.
* ``velocity`` (McGuire et al. 2012's reconstruction filter with Guertin et al. 2014's
  improvements): the velocity buffer holds every moving object's screen motion over the whole
  shutter per vertex, so a deforming or turning object has its own velocity at every pixel, and
  [`motionblur.image.reconstruction_blur`][motionblur.image.reconstruction_blur] gathers each pixel from the pixels whose motion
  reaches it (tile max and neighbour max say how far to look, the depth buffer splits the taps
  into foreground blurred over the pixel and background filling what it leaves). It is what
  users pick instead of motion volumes. Limits: one sharp frame, so a surface hidden at
  mid-shutter is never shown; motion taken as straight and uniform; a still camera.
"""

from __future__ import annotations

import numpy as np

from .. import _core, image
from .._validate import as_bool, as_choice, as_float, as_int
from ..raster import Frame
from ..render import register
from ..scene import Scene
from ._sharp import check_aa, require_box_shutter, sharp_frame, shutter_centroid

__all__ = ["opaque_image", "camera_velocity", "velocity", "shutter_centroid"]


#: ``opaque_image(groups=True)``: a moving object's pixels are split into masks by the direction
#: of their velocity (this many sectors) and its length (bins this factor apart), each mask
#: blurred along its own mean velocity.
VELOCITY_SECTORS = 16
VELOCITY_RATIO = 1.5


@register(
    "opaque_image",
    sweep=[{"aa": a} for a in _core.SAMPLES] + [{"glow": "opaque", "groups": False}],
    applies=lambda scene: bool(scene.moving_objects) and not scene.camera_moves,
    needs="moving objects seen by a still camera",
)
def opaque_image(
    scene: Scene, aa: int = 1, layers: bool = True, glow: str = "coverage", groups: bool = True
) -> Frame:
    """Kraus's image-based motion blur of every moving object (module docs).

    Options: ``aa`` 1, 2 or 4 spatial samples per pixel along each axis for the sharp frame;
    ``glow`` ``"coverage"`` (default) or ``"opaque"``: the opacity of a blurred mask. Kraus's
    opaque blur (``"opaque"``, his eq. 10: the largest triangle-filtered opacity along the blur)
    never lowers an opacity, so nothing behind the object need be known, and the object stays
    opaque where it was: a motion longer than the object is over-covered (on the deforming scenes
    no better than the sharp frame). ``"coverage"`` takes the box-blurred opacity itself, the
    time-averaged coverage of a uniformly moving mask (the physically correct glow his section 6
    asks for), over the static objects rendered without the moving ones (his section 4.1's
    alternative of rendering the moving objects apart: one more rasterizer pass of the static
    objects), so what the object uncovers shows. ``groups`` (default True): each object is split
    into masks by its pixels' velocity (16 direction sectors, lengths in bins 1.5x apart), each
    blurred along its own mean velocity (section 4.1's several masks; a turning or deforming
    object has no one direction); False: one mask per object, along the mean of its pixels'
    velocities. ``layers`` (default True): Kraus's "under" as well as "over" (section 4.1): the
    static pixels nearer than the blurred object (its depth the mean depth of the mask pixels
    the box gathers there) stay in front of it; False composites every object over everything.
    Objects are blurred farthest first. A shutter other than a box raises ValueError naming
    ``shutter``. ``stats``: ``t`` (the time of the sharp frame), ``blurred`` (objects blurred),
    per object ``lengths`` (pixels, its mean velocity), ``masks`` (velocity masks blurred),
    ``front_pixels`` (pixels composited in front).
    """
    aa = check_aa(aa)
    layers = as_bool(layers, "layers")
    groups = as_bool(groups, "groups")
    as_choice(glow, "glow", ("coverage", "opaque"), type_error=False)
    require_box_shutter(scene, "opaque_image")
    tc = shutter_centroid(scene)
    frame = sharp_frame(scene, tc, aa, velocity="shutter")
    order = []  # (depth, object, mean velocity (2,), mask)
    for k, o in enumerate(scene.objects):
        mask = frame.ids == k
        if not o.is_moving or not mask.any():
            continue
        v = frame.velocity[mask].astype(np.float64).mean(axis=0)
        order.append((float(np.mean(frame.depth[mask])), k, v, mask))
    order.sort(key=lambda e: -e[0])
    lengths = {k: float(np.hypot(v[0], v[1])) for _, k, v, _ in order}
    if glow == "coverage":
        rgba, masks, front_pixels = _coverage_blur(scene, frame, tc, aa, order, layers, groups)
    else:
        rgba, masks, front_pixels = _opaque_blur(frame, order, layers, groups)
    out = Frame(rgba, frame.depth, frame.ids, frame.velocity)
    out.stats.update(t=tc, blurred=len(order), lengths=lengths, masks=masks, front_pixels=front_pixels)
    return out


def _velocity_masks(frame: Frame, mask: np.ndarray, mean, groups: bool):
    """[(window (y0, y1, x0, x1), its mask, velocity (2,))]: the pixels of ``mask`` in each
    velocity group (``groups``) with the group's mean velocity, or all of them with ``mean``."""
    ys, xs = np.nonzero(mask)
    v = frame.velocity[ys, xs].astype(np.float64)
    if groups:
        sector = np.floor((np.arctan2(v[:, 1], v[:, 0]) + np.pi) / (2 * np.pi) * VELOCITY_SECTORS)
        size = np.floor(np.log(np.maximum(np.hypot(v[:, 0], v[:, 1]), 1.0)) / np.log(VELOCITY_RATIO))
        key = (sector.astype(np.int64) % VELOCITY_SECTORS) * (1 << 20) + size.astype(np.int64)
        keys, inverse = np.unique(key, return_inverse=True)
        parts = [np.flatnonzero(inverse == i) for i in range(len(keys))]
    else:
        parts = [np.arange(len(ys))]
    out = []
    for sel in parts:
        vel = v[sel].mean(axis=0) if groups else np.asarray(mean, np.float64)
        py, px = ys[sel], xs[sel]
        r = int(np.ceil(0.5 * float(np.hypot(vel[0], vel[1])))) + 2
        h, w = mask.shape
        y0, y1 = max(0, int(py.min()) - r), min(h, int(py.max()) + r + 1)
        x0, x1 = max(0, int(px.min()) - r), min(w, int(px.max()) + r + 1)
        m = np.zeros((y1 - y0, x1 - x0), bool)
        m[py - y0, px - x0] = True
        out.append(((y0, y1, x0, x1), m, vel))
    return out


def _opaque_blur(frame: Frame, order, layers: bool, groups: bool):
    """Kraus's opaque motion blur of each velocity mask, composited over the frame itself (the
    object stays where it was under its blur) and, with ``layers``, under what is in front."""
    rgba = frame.rgba
    masks = front_pixels = 0
    for _, k, v, mask in order:
        for (y0, y1, x0, x1), m, vel in _velocity_masks(frame, mask, v, groups):
            length = float(np.hypot(vel[0], vel[1]))
            if length < 1.0:
                continue
            masks += 1
            full = np.zeros(mask.shape, bool)
            full[y0:y1, x0:x1] = m
            layer = rgba * full[..., None]
            if not layers:
                rgba = image.opaque_motion_blur(layer, (vel[0], vel[1]), length, mode="over", base=rgba)
                continue
            front = _front_of(frame, full, k, (vel[0], vel[1]), length)
            front_pixels += int(front.sum())
            near = rgba * front[..., None]
            blurred = image.opaque_motion_blur(layer, (vel[0], vel[1]), length, mode="over", base=rgba - near)
            rgba = near + (1.0 - near[..., 3:4]) * blurred  # the front layer over (Kraus's "under")
    return rgba, masks, front_pixels


def _coverage_blur(scene: Scene, frame: Frame, tc: float, aa: int, order, layers: bool, groups: bool):
    """Each moving object's velocity masks box-blurred, opacity included (the coverage glow),
    summed (a turning object's masks sweep into each other: opacity capped at 1), and
    composited farthest first over the static objects rendered alone; with ``layers`` a static
    pixel nearer than the object's blurred depth there stays in front of it."""
    statics = scene.with_(objects=[o for o in scene.objects if not o.is_moving])
    back = sharp_frame(statics, tc, aa, velocity=None)
    rgba = back.rgba.copy()
    masks = front_pixels = 0
    for _, _, v, mask in order:
        blurred = np.zeros_like(rgba)
        depth = np.zeros((*mask.shape, 4), np.float32)  # (z m, 0, 0, m) blurred alike
        z = np.where(mask, frame.depth, 0.0).astype(np.float32)
        for (y0, y1, x0, x1), m, vel in _velocity_masks(frame, mask, v, groups):
            layer = np.ascontiguousarray(frame.rgba[y0:y1, x0:x1] * m[..., None])
            zm = m.astype(np.float32)
            zl = np.ascontiguousarray(np.stack([z[y0:y1, x0:x1] * zm, 0 * zm, 0 * zm, zm], axis=-1))
            length = float(np.hypot(vel[0], vel[1]))
            if length >= 1.0:
                masks += 1
                layer = image.box_blur(layer, (vel[0], vel[1]), length)
                zl = image.box_blur(zl, (vel[0], vel[1]), length)
            blurred[y0:y1, x0:x1] += layer
            depth[y0:y1, x0:x1] += zl
        a = blurred[..., 3:4]
        blurred *= np.where(a > 1.0, 1.0 / np.maximum(a, 1e-30), 1.0).astype(np.float32)
        over = blurred + (1.0 - blurred[..., 3:4]) * rgba
        if not layers:
            rgba = over
            continue
        reach = depth[..., 3] > 1e-6
        zbar = np.where(reach, depth[..., 0] / np.maximum(depth[..., 3], 1e-30), np.inf)
        front = reach & (back.depth < zbar)
        front_pixels += int(front.sum())
        under = rgba + (1.0 - rgba[..., 3:4]) * blurred
        rgba = np.where(front[..., None], under, over).astype(np.float32)
    return rgba, masks, front_pixels


def _front_of(frame: Frame, mask: np.ndarray, k: int, direction, length: float) -> np.ndarray:
    """(H,W) bool: the pixels of other objects nearer than object ``k``'s blurred image there,
    whose depth is the mean depth of the ``mask`` pixels a box of ``length`` along
    ``direction`` gathers (the same box the blur uses)."""
    z = np.where(mask, frame.depth, 0.0).astype(np.float32)
    m = mask.astype(np.float32)
    layer = np.ascontiguousarray(np.stack([z, z, z, m], axis=-1))
    b = image.box_blur(layer, direction, length)
    reach = b[..., 3] > 1e-6
    zbar = np.where(reach, b[..., 0] / np.maximum(b[..., 3], 1e-30), np.inf)
    return reach & (frame.ids >= 0) & (frame.ids != k) & (frame.depth < zbar)


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
    camera at the shutter's start is scaled by ``1 / t_c`` to span the whole shutter and clamped
    to ``MAX_VELOCITY`` pixels (as [`motionblur.image.camera_motion_blur`][motionblur.image.camera_motion_blur]). Pixels of
    moving objects take the rasterizer's velocity of the object with the camera's motion folded
    in instead (Chapman's static-scene velocity would blur an object the camera follows).
    ``stats``: ``t``, ``samples``.
    """
    samples = as_int(samples, "samples", minimum=1, maximum=image.MAX_SAMPLES)
    aa = check_aa(aa)
    require_box_shutter(scene, "camera_velocity")
    tc = shutter_centroid(scene)
    frame = sharp_frame(scene, tc, aa, velocity="since_open")
    rgba = frame.rgba
    if scene.camera_moves and tc > 0.0:
        cam, start = scene.camera_at(tc), scene.camera_at(0.0)
        vel = image.camera_velocity(frame.depth, cam, start)
        moving = np.isin(frame.ids, [k for k, o in enumerate(scene.objects) if o.is_moving])
        vel = np.where(moving[..., None], frame.velocity, vel) * np.float32(1.0 / tc)
        # as camera_motion_blur: a streak past MAX_VELOCITY pixels crosses the image anyway (a
        # very narrow field of view, a point near the previous camera plane)
        vel = np.clip(vel, -image.MAX_VELOCITY, image.MAX_VELOCITY, out=vel)
        rgba = image.velocity_blur(rgba, vel, samples)
    out = Frame(rgba, frame.depth, frame.ids, frame.velocity)
    out.stats.update(t=tc, samples=samples)
    return out


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
