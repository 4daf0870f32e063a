"""The ``opaque_image`` method as its numpy steps (the method before its coverage glow moved
into one call of the core, ``_core._coverage_blur``): the oracle of
tests/methods/test_image_space_fast_paths.py, which asks for the same bits. Unchanged helpers
are the method's own (`motionblur.methods.image_space`)."""

from __future__ import annotations

import numpy as np

from motionblur import _core, image
from motionblur._validate import as_bool, as_choice
from motionblur.methods._layers import Static
from motionblur.methods._sharp import check_aa, require_box_shutter, sharp_frame, shutter_centroid
from motionblur.methods.image_space import (
    VELOCITY_RATIO,
    VELOCITY_SECTORS,
    _front_of,
    _full_mask,
    _reach,
    _sharp,
    _sharp_over,
    _static_part,
)
from motionblur.raster import Frame
from motionblur.scene import Scene


def _masked_window_rgba(frame: Frame, pasted, window, m: np.ndarray) -> np.ndarray:
    """The sharp frame's colour over ``window`` (y0, y1, x0, x1) times the mask ``m`` there, a
    new array: ``frame.rgba`` with the ``pasted`` window of `_sharp_over` (or None) laid over it,
    each pixel multiplied where it lies (no copy of the window first)."""
    y0, y1, x0, x1 = window
    out = frame.rgba[y0:y1, x0:x1] * m[..., None]
    if pasted is not None:
        (py0, py1, px0, px1), part = pasted
        a0, a1, b0, b1 = max(y0, py0), min(y1, py1), max(x0, px0), min(x1, px1)
        if a0 < a1 and b0 < b1:
            np.multiply(
                part[a0 - py0 : a1 - py0, b0 - px0 : b1 - px0],
                m[a0 - y0 : a1 - y0, b0 - x0 : b1 - x0, None],
                out=out[a0 - y0 : a1 - y0, b0 - x0 : b1 - x0],
            )
    return out


def opaque_image(
    scene: Scene, aa: int = 1, layers: bool = True, glow: str = "coverage", groups: bool = True
) -> Frame:
    """The method as it was: its numpy steps (module docs)."""
    aa = check_aa(aa)
    layers = as_bool(layers, "layers")
    groups = as_bool(groups, "groups")
    as_choice(glow, "glow", ("coverage", "opaque"), type_error=False)
    require_box_shutter(scene, "opaque_image")
    tc = shutter_centroid(scene)
    static = _static_part(scene, aa)
    if glow == "coverage" and static is not None:  # (its colour read by windows: no full copy)
        frame, pasted = _sharp_over(scene, tc, aa, "shutter", static)
    else:
        frame, pasted = _sharp(scene, tc, aa, "shutter", static), None
    order = []  # (depth, object, mean velocity (2,), (its pixels' window, mask there))
    for k, (y0, y1, x0, x1) in _moving_windows(scene, frame.ids):
        mask = frame.ids[y0:y1, x0:x1] == k
        vs = frame.velocity[y0:y1, x0:x1][mask].astype(np.float64)  # (its pixels in row order)
        v = vs.mean(axis=0)
        order.append((float(np.mean(frame.depth[y0:y1, x0:x1][mask])), k, v, ((y0, y1, x0, x1), mask, vs)))
    order.sort(key=lambda e: -e[0])
    lengths = {k: float(np.hypot(v[0], v[1])) for _, k, v, _ in order}
    if glow == "coverage":
        rgba, masks, front_pixels = _coverage_blur(
            scene, (frame, pasted), tc, aa, order, layers, groups, static
        )
    else:
        order = [(z, k, v, _full_mask(frame.ids.shape, win, m)) for z, k, v, (win, m, _) in order]
        rgba, masks, front_pixels = _opaque_blur(frame, order, layers, groups)
    out = Frame(rgba, frame.depth, frame.ids, frame.velocity)
    out.stats.update(t=tc, blurred=len(order), lengths=lengths, masks=masks, front_pixels=front_pixels)
    return out


def _moving_windows(scene: Scene, ids: np.ndarray):
    """[(k, (y0, y1, x0, x1))]: each moving object ``k`` seen in the frame, with the rows and
    columns that hold its pixels (``ids == k``), in object order."""
    out = []
    for k, o in enumerate(scene.objects):
        if not o.is_moving:
            continue
        mask = ids == k
        rows = np.flatnonzero(mask.any(axis=1))
        if len(rows) == 0:
            continue
        y0, y1 = int(rows[0]), int(rows[-1]) + 1
        cols = np.flatnonzero(mask[y0:y1].any(axis=0))
        out.append((k, (y0, y1, int(cols[0]), int(cols[-1]) + 1)))
    return out


def _velocity_masks(frame: Frame, mask, mean, groups: bool):
    """[(window (y0, y1, x0, x1), its mask, velocity (2,))]: the pixels of ``mask`` (an (H,W)
    bool, or (window, mask there, the velocities of its pixels in row order (N, 2) float64)) in
    each velocity group (``groups``) with the group's mean velocity, or all of them with
    ``mean``; windows in frame pixels."""
    if isinstance(mask, tuple):
        (oy, oy1, ox, ox1), mask, v = mask
    else:
        (oy, oy1, ox, ox1), v = (0, *mask.shape[:1], 0, *mask.shape[1:]), None
    ys, xs = np.nonzero(mask)
    if v is None:
        v = frame.velocity[oy:oy1, ox:ox1][mask].astype(np.float64)
    ys, xs = ys + oy, xs + ox
    whole = [None]  # (every pixel, the object's own window and mask)
    if groups:
        sector = np.floor((np.arctan2(v[:, 1], v[:, 0]) + np.pi) / (2 * np.pi) * VELOCITY_SECTORS)
        size = np.floor(np.log(np.maximum(np.hypot(v[:, 0], v[:, 1]), 1.0)) / np.log(VELOCITY_RATIO))
        key = (sector.astype(np.int64) % VELOCITY_SECTORS) * (1 << 20) + size.astype(np.int64)
        if len(key) and key.min() == key.max():
            parts = whole  # one group (a translation): no sort
        else:
            keys, inverse = np.unique(key, return_inverse=True)
            # each group's pixels in row order, as np.flatnonzero(inverse == i) gives them
            rank = np.argsort(inverse, kind="stable")
            parts = np.split(rank, np.cumsum(np.bincount(inverse, minlength=len(keys)))[:-1])
    else:
        parts = whole
    out = []
    h, w = frame.ids.shape
    for sel in parts:
        if sel is None:
            vel = v.mean(axis=0) if groups else np.asarray(mean, np.float64)
            py, px = ys, xs
        else:
            vel = v[sel].mean(axis=0) if groups else np.asarray(mean, np.float64)
            py, px = ys[sel], xs[sel]
        ry, rx = _reach(vel)
        y0, y1 = max(0, int(py.min()) - ry), min(h, int(py.max()) + ry + 1)
        x0, x1 = max(0, int(px.min()) - rx), min(w, int(px.max()) + rx + 1)
        m = np.zeros((y1 - y0, x1 - x0), bool)
        if sel is None:  # the mask itself in the window (which holds every pixel of it)
            a0, a1, b0, b1 = max(oy, y0), min(oy1, y1), max(ox, x0), min(ox1, x1)
            m[a0 - y0 : a1 - y0, b0 - x0 : b1 - x0] = mask[a0 - oy : a1 - oy, b0 - ox : b1 - ox]
        else:
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


def _coverage_blur(
    scene: Scene, sharp, tc: float, aa: int, order, layers: bool, groups: bool, static: Static | None
):
    """Each moving object's velocity masks box-blurred, opacity included (the coverage glow),
    summed (a turning object's masks sweep into each other: opacity capped at 1), and
    composited farthest first over the static objects rendered alone (the kept ``static``
    layer when there is one); with ``layers`` a static pixel nearer than the object's blurred
    depth there stays in front of it. Only the window each object's blurred masks cover is
    computed: elsewhere nothing reaches and the static pixels are kept as they are. ``sharp``:
    (the sharp frame, the window pasted over its colour or None: `_sharp_over`)."""
    frame, pasted = sharp
    if static is None:
        statics = scene.with_(objects=[o for o in scene.objects if not o.is_moving])
        back = sharp_frame(statics, tc, aa, velocity=None)
        back_rgba, back_depth = back.rgba, back.depth
    else:  # the same pixels (ids aside, which are not read)
        back_rgba, back_depth = static.rgba, static.depth
    rgba = back_rgba.copy()
    back_depth = np.ascontiguousarray(back_depth, np.float32)
    masks = front_pixels = 0
    for _, _, v, mask in order:
        parts = _velocity_masks(frame, mask, v, groups)
        wy0, wx0 = min(p[0][0] for p in parts), min(p[0][2] for p in parts)
        wy1, wx1 = max(p[0][1] for p in parts), max(p[0][3] for p in parts)
        sub = rgba[wy0:wy1, wx0:wx1]
        blurred = np.zeros_like(sub)
        depth = np.zeros((*sub.shape[:2], 4), np.float32)  # (z m, 0, 0, m) blurred alike
        (oy0, oy1, ox0, ox1), m0, _ = mask
        z = np.zeros(sub.shape[:2], np.float32)
        zs = z[oy0 - wy0 : oy1 - wy0, ox0 - wx0 : ox1 - wx0]
        zs[...] = np.where(m0, frame.depth[oy0:oy1, ox0:ox1], 0.0)
        for (y0, y1, x0, x1), m, vel in parts:
            layer = np.ascontiguousarray(_masked_window_rgba(frame, pasted, (y0, y1, x0, x1), m))
            zm = m.astype(np.float32)
            zw = z[y0 - wy0 : y1 - wy0, x0 - wx0 : x1 - wx0]
            zl = np.zeros((*zm.shape, 4), np.float32)  # (z m, 0, 0, m)
            zl[..., 0], zl[..., 3] = zw * zm, zm
            length = float(np.hypot(vel[0], vel[1]))
            if length >= 1.0:
                masks += 1
                layer = image.box_blur(layer, (vel[0], vel[1]), length)
                zl = image.box_blur(zl, (vel[0], vel[1]), length)
            blurred[y0 - wy0 : y1 - wy0, x0 - wx0 : x1 - wx0] += layer
            depth[y0 - wy0 : y1 - wy0, x0 - wx0 : x1 - wx0] += zl
        # the blurred colour (opacity capped at 1) over the static pixels and, with layers, the
        # static pixels nearer than the blurred depth there in front instead: one pass
        over, front = _core._coverage_composite(
            rgba, back_depth, (wy0, wy1, wx0, wx1), blurred, np.ascontiguousarray(depth), layers
        )
        front_pixels += front
        sub[...] = over  # (a view of rgba)
    return rgba, masks, front_pixels
