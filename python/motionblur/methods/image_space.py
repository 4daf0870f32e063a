"""Image-space motion blur of one rasterized frame: Kraus's opaque motion blur per moving object
(``opaque_image``), Chapman's camera motion blur (``camera_velocity``) and the per-pixel
velocity-buffer post-process of game engines and Blender EEVEE (``velocity``).

Both render the scene once, sharp, at the centroid ``t_c`` of the shutter filter
(``1 - integral of W(t) dt``; 0.5 for a box shutter), so that a blur centred on each pixel covers
the whole shutter, and then blur the frame's pixels. With a still camera, one shading mode and
opaque static objects, the static objects' layer is kept across frames (the one ``accumulation``
keeps) and only the moving objects are drawn over it: the same pixels as drawing everything, at
the cost of the moving triangles. The blurs skip what does not move: ``velocity``'s gather
counts the taps no moving surface can reach without reading them, ``opaque_image`` composites
only the windows its blurred masks cover, and ``camera_velocity`` blurs along each pixel's
velocity as the core computes it, with no velocity image in between:

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
from ..raster import Draw, Frame
from ..raster import _lights as raster_lights
from ..render import register
from ..scene import Scene
from ._layers import Layer, Static, static_layer, supersampled, window_projection
from ._sharp import check_aa, require_box_shutter, sharp_frame, shutter_centroid

__all__ = ["opaque_image", "camera_velocity", "velocity", "shutter_centroid"]


#: ``opaque_image(groups=True)``: a moving object's pixels are split into masks by the direction
#: of their velocity (this many sectors) and its length (bins this factor apart), each mask
#: blurred along its own mean velocity.
VELOCITY_SECTORS = 16
VELOCITY_RATIO = 1.5


def _static_part(scene: Scene, aa: int) -> Static | None:
    """The still camera's static layer (kept across frames, as ``accumulation`` keeps it), when
    drawing the moving objects over it gives the bits of `sharp_frame`: opaque static objects
    (a sample of the layer hides what is behind it); None otherwise."""
    if scene.camera_moves:
        return None
    statics = [(k, o) for k, o in enumerate(scene.objects) if not o.is_moving]
    if any(o.is_transparent for _, o in statics):
        return None
    return static_layer(scene, supersampled(scene.camera, aa), statics, aa)


def _sharp(scene: Scene, t: float, aa: int, velocity: str | None, static: Static | None) -> Frame:
    """`sharp_frame` (same arguments), the moving objects drawn over the ``static`` layer of
    `_static_part` when there is one: the rasterizer runs on the window of pixels their
    vertices project to (the camera's projection narrowed to it, the layer read from the
    window's first sample) and the static pixels are copied around it, the bits of drawing
    everything (tests/methods/test_image_space_fast_paths.py). ``stats["drawn"]``: (y0, y1, x0,
    x1) the pixels drawn (the whole image when drawn whole), None when nothing was; elsewhere
    every velocity is 0."""
    if static is None or velocity == "since_open":
        frame = sharp_frame(scene, t, aa, velocity=velocity)
        frame.stats["drawn"] = (0, frame.rgba.shape[0], 0, frame.rgba.shape[1])
        return frame
    frame, pasted = _sharp_over(scene, t, aa, velocity, static)
    rgba = static.rgba.copy()
    if pasted is not None:
        (y0, y1, x0, x1), part = pasted
        rgba[y0:y1, x0:x1] = part
    out = Frame(rgba, frame.depth, frame.ids, frame.velocity)
    out.stats["drawn"] = None if pasted is None else pasted[0]
    return out


def _sharp_over(scene: Scene, t: float, aa: int, velocity: str | None, static: Static):
    """`_sharp` over the ``static`` layer, its colour left apart: (a Frame whose ``rgba`` is
    the static layer's own array, not to be written, with the depth, ids and velocity of the
    sharp frame; ``((y0, y1, x0, x1), rgba there)``, the window the moving objects were drawn
    in, or None). The sharp frame's colour is the static colour with that window pasted in:
    `_coverage_blur` reads it so, without making the whole image."""
    cam = scene.camera_at(t)
    draws, points = [], []
    for k, o in enumerate(scene.objects):
        if not o.is_moving:
            continue
        v, prev = o.world_vertices(t), None  # the previous vertices exactly as sharp_frame's
        if velocity == "shutter":
            prev = v - (o.world_vertices(1.0) - o.world_vertices(0.0))
        draws.append(Draw(v, o.mesh.faces, o.rgba, object_id=k, previous_vertices=prev, shading=o.shading))
        points.append(_drawn_vertices(o.mesh, v))
    depth, ids = static.depth.copy(), static.ids.copy()
    vel = np.zeros((*ids.shape, 2), np.float32)
    win = _window(cam, np.concatenate(points) if points else np.zeros((0, 3)))
    pasted = None
    if win is not None:
        x0, y0, x1, y1 = win
        layer = static.layer
        c = np.ascontiguousarray
        options = {
            "view": cam.view, "projection": window_projection(cam.projection, cam.width, cam.height, win),
            "width": x1 - x0, "height": y1 - y0, "samples": aa, "blend": "exact",
            "shading": scene.objects[0].shading, "lights": raster_lights(scene.lights),
            "ambient": tuple(map(float, scene.ambient)), "origin": (x0 * aa, y0 * aa),
        }  # fmt: skip
        part = _core._rasterize(draws, options, Layer(c(layer.rgba), c(layer.depth), c(layer.ids)))
        depth[y0:y1, x0:x1], ids[y0:y1, x0:x1] = part[1:3]
        pasted = ((y0, y1, x0, x1), part[0])
        if part[3] is not None:  # (no velocity buffer when no draw has previous vertices)
            vel[y0:y1, x0:x1] = part[3]
    return Frame(static.rgba, depth, ids, vel), pasted


def _drawn_vertices(mesh, v: np.ndarray) -> np.ndarray:
    """The rows of ``v`` (a mesh's vertices placed in the world) that its faces use: all of them
    when the mesh has no unreferenced vertex (its stats, counted once and kept), as `_window`
    needs only their set (no sort of the faces each frame: 7 ms for 70,000 faces)."""
    if len(mesh.faces) == 0:
        return v[:0]
    if mesh.stats["unreferenced_vertices"] == 0:
        return v
    return v[np.unique(mesh.faces)]


def _window(cam, points: np.ndarray):
    """(x0, y0, x1, y1): the pixels of ``cam`` that triangles of ``points`` (N,3) world can
    cover (their projected box, 2 pixels more), the whole image when one is not in front of the
    near plane; None when there are none or the box misses the image."""
    if len(points) == 0:
        return None
    w, h = cam.width, cam.height
    clip = points @ cam.view_projection[:3, :3].T + cam.view_projection[:3, 3]
    cw = points @ cam.view_projection[3, :3] + cam.view_projection[3, 3]
    if not np.all(cw > cam.znear):
        return (0, 0, w, h)
    px = (clip[:, 0] / cw + 1.0) * 0.5 * w
    py = (1.0 - clip[:, 1] / cw) * 0.5 * h
    x0, x1 = max(0, int(np.floor(px.min())) - 2), min(w, int(np.ceil(px.max())) + 2)
    y0, y1 = max(0, int(np.floor(py.min())) - 2), min(h, int(np.ceil(py.max())) + 2)
    return (x0, y0, x1, y1) if x0 < x1 and y0 < y1 else None


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
    static = _static_part(scene, aa)
    drawn = None  # (the window the moving objects were drawn in over the static layer)
    if glow == "coverage" and static is not None:  # (its colour read by windows: no full copy)
        frame, pasted = _sharp_over(scene, tc, aa, "shutter", static)
        drawn = (0, 0, 0, 0) if pasted is None else pasted[0]
    else:
        frame, pasted = _sharp(scene, tc, aa, "shutter", static), None
    order = []  # (depth, object, mean velocity (2,), (its pixels' window, mask there))
    c = np.ascontiguousarray
    ids, vel, depth = c(frame.ids, np.int32), c(frame.velocity, np.float32), c(frame.depth, np.float32)
    for k, win in _moving_windows(scene, frame.ids, drawn):
        # ids[win] == k, velocity[win][mask] as float64 and depth[win][mask] (its pixels in row
        # order) and the mean velocity, numpy's vs.mean(axis=0), in one pass of the core
        mask, vs, zs, v = _core._object_pixels(ids, vel, depth, win, k)
        order.append((float(np.mean(zs)), k, np.array(v, np.float64), (win, mask, vs)))
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


def _moving_windows(scene: Scene, ids: np.ndarray, within=None):
    """[(k, (y0, y1, x0, x1))]: each moving object ``k`` seen in the frame, with the rows and
    columns that hold its pixels (``ids == k``), in object order. ``within`` (y0, y1, x0, x1):
    a window that holds every moving object's pixels (the one `_sharp_over` drew them in; None:
    the whole frame), the only pixels read."""
    out = []
    wy0, _, wx0, _ = within = within or (0, *ids.shape[:1], 0, *ids.shape[1:])
    ids = ids[within[0] : within[1], within[2] : within[3]]
    for k, o in enumerate(scene.objects):
        if not o.is_moving:
            continue
        mask = ids == k
        rows = np.flatnonzero(mask.any(axis=1))
        if len(rows) == 0:
            continue
        y0, y1 = int(rows[0]), int(rows[-1]) + 1
        cols = np.flatnonzero(mask[y0:y1].any(axis=0))
        out.append((k, (wy0 + y0, wy0 + y1, wx0 + int(cols[0]), wx0 + int(cols[-1]) + 1)))
    return out


def _full_mask(shape, window, mask: np.ndarray) -> np.ndarray:
    """(H,W) bool: ``mask`` placed at ``window`` (y0, y1, x0, x1) of a frame of ``shape``."""
    full = np.zeros(shape, bool)
    y0, y1, x0, x1 = window
    full[y0:y1, x0:x1] = mask
    return full


def _velocity_groups(frame: Frame, mask, mean, groups: bool):
    """(labels, [(window (y0, y1, x0, x1), velocity (2,), pixels)]): the pixels of ``mask`` (an
    (H,W) bool, or (window, mask there, the velocities of its pixels in row order (N, 2)
    float64)) in each velocity group (``groups``) with the group's mean velocity, or all of them
    with ``mean``; windows in frame pixels, each holding its group's pixels and the reach of its
    blur. ``labels``: None for one group (every pixel of the mask), else the index of each
    pixel's group in the mask's window (int32, -1 outside the mask); ``pixels``: None for one
    group, else the (rows, columns) of the group's pixels in the frame."""
    if isinstance(mask, tuple):
        (oy, oy1, ox, ox1), mask, v = mask
    else:
        (oy, oy1, ox, ox1), v = (0, *mask.shape[:1], 0, *mask.shape[1:]), None
    if v is None:
        v = frame.velocity[oy:oy1, ox:ox1][mask].astype(np.float64)
    parts, inverse = [None], None  # (every pixel, the object's own window and mask)
    # (the core says when every pixel certainly has one key, whose computation it skips)
    if groups and not _core._one_velocity_group(np.ascontiguousarray(v), VELOCITY_SECTORS, VELOCITY_RATIO):
        sector = np.floor((np.arctan2(v[:, 1], v[:, 0]) + np.pi) / (2 * np.pi) * VELOCITY_SECTORS)
        size = np.floor(np.log(np.maximum(np.hypot(v[:, 0], v[:, 1]), 1.0)) / np.log(VELOCITY_RATIO))
        sector, size = sector.astype(np.int64) % VELOCITY_SECTORS, size.astype(np.int64)
        key = sector * (1 << 20) + size
        if not (len(key) and key.min() == key.max()):  # (one group, a translation: no sort)
            if size.min() >= 0 and size.max() < 64:
                # np.unique(key, return_inverse=True) without its sort: the keys' order is that
                # of sector * 64 + size, a small range counted in bins
                counts = np.bincount(sector * 64 + size, minlength=VELOCITY_SECTORS * 64)
                present = np.flatnonzero(counts)
                index = np.zeros(len(counts), np.intp)
                index[present] = np.arange(len(present))
                inverse = index[sector * 64 + size]
            else:
                inverse = np.unique(key, return_inverse=True)[1]
            # each group's pixels in row order, as np.flatnonzero(inverse == i) gives them
            rank = np.argsort(inverse, kind="stable")
            parts = np.split(rank, np.cumsum(np.bincount(inverse))[:-1])
    out = []
    h, w = frame.ids.shape
    if inverse is None:
        rows, cols = np.flatnonzero(mask.any(axis=1)), np.flatnonzero(mask.any(axis=0))
        box = (oy + int(rows[0]), oy + int(rows[-1]), ox + int(cols[0]), ox + int(cols[-1]))
        # (one group: every pixel, whose mean is the object's own, ``mean``)
        parts = [(box, np.asarray(mean, np.float64), None)]
        labels = None
    else:
        ys, xs = np.nonzero(mask)
        ys, xs = ys + oy, xs + ox
        pixels = [(ys[sel], xs[sel]) for sel in parts]
        parts = [
            ((int(py.min()), int(py.max()), int(px.min()), int(px.max())), v[sel].mean(axis=0), (py, px))
            for sel, (py, px) in zip(parts, pixels)
        ]  # fmt: skip
        labels = np.full(mask.shape, -1, np.int32)
        labels[mask] = inverse
    for (py0, py1, px0, px1), vel, pixels in parts:
        ry, rx = _reach(vel)
        y0, y1 = max(0, py0 - ry), min(h, py1 + ry + 1)
        x0, x1 = max(0, px0 - rx), min(w, px1 + rx + 1)
        out.append(((y0, y1, x0, x1), vel, pixels))
    return labels, out


def _velocity_masks(frame: Frame, mask, mean, groups: bool):
    """[(window (y0, y1, x0, x1), its mask, velocity (2,))]: `_velocity_groups` with each
    group's mask over its window."""
    labels, parts = _velocity_groups(frame, mask, mean, groups)
    if isinstance(mask, tuple):
        (oy, oy1, ox, ox1), mask, _ = mask
    else:
        (oy, oy1, ox, ox1) = (0, *mask.shape[:1], 0, *mask.shape[1:])
    out = []
    for (y0, y1, x0, x1), vel, pixels in parts:
        m = np.zeros((y1 - y0, x1 - x0), bool)
        if pixels is None:  # the mask itself in the window (which holds every pixel of it)
            a0, a1, b0, b1 = max(oy, y0), min(oy1, y1), max(ox, x0), min(ox1, x1)
            m[a0 - y0 : a1 - y0, b0 - x0 : b1 - x0] = mask[a0 - oy : a1 - oy, b0 - ox : b1 - ox]
        else:
            py, px = pixels
            m[py - y0, px - x0] = True
        out.append(((y0, y1, x0, x1), m, vel))
    return out


def _reach(vel) -> tuple[int, int]:
    """(rows, columns) a box blur of length ``|vel|`` along ``vel`` (2,) spreads a mask by, at
    most, on each side. Along its major axis (the one the core filters along: y when ``|vy| >
    |vx|`` in float32, as ``image.box_blur`` receives it) ``ceil(|vel| / 2) + 2``, the reach
    the windows have always had: the window's first column (row) there sets where the sheared
    rows sample the layer, so it stays. Across it, the shear moves the taps by at most half the
    minor component, and the two interpolations (into the shear and back) by a row each: ``ceil(
    |minor| / 2) + 3``. A window any larger only adds pixels nothing reaches, which composite
    to the static pixels unchanged."""
    r = int(np.ceil(0.5 * float(np.hypot(vel[0], vel[1])))) + 2
    dx, dy = abs(float(np.float32(vel[0]))), abs(float(np.float32(vel[1])))
    if dy > dx:
        return r, min(r, int(np.ceil(0.5 * dx)) + 3)
    return min(r, int(np.ceil(0.5 * dy)) + 3), r


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
    c = np.ascontiguousarray
    back_rgba = c(back_rgba, np.float32)
    # (the first object's call fills the new frame: the static colour outside its windows)
    rgba = np.empty_like(back_rgba) if order else back_rgba.copy()
    fill = back_rgba
    back_depth, depth = c(back_depth, np.float32), c(frame.depth, np.float32)
    if pasted is not None:
        pasted = (pasted[0], c(pasted[1], np.float32))
    masks = front_pixels = 0
    for _, _, v, mask in order:
        window, m0, _ = mask
        labels, parts = _velocity_groups(frame, mask, v, groups)
        if labels is None:
            labels = m0.astype(np.int32) - 1  # (0: the one group)
        blurs = []
        for win, vel, _ in parts:
            length = float(np.hypot(vel[0], vel[1]))
            masks += length >= 1.0
            blurs.append((win, (float(vel[0]), float(vel[1])), length, length >= 1.0))
        # each group's masked colour and (z m, 0, 0, m) box-blurred, summed (opacity capped at
        # 1) and composited over rgba in place (the module docs of src/image/coverage_blur.rs)
        front_pixels += _core._coverage_blur(
            rgba, back_depth, c(frame.rgba, np.float32), pasted, depth, (window, labels), blurs, layers, fill
        )
        fill = None
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
    sweep=[{"samples": None}] + [{"samples": n} for n in (4, 8, 16, 32)],
    applies=lambda scene: scene.camera_moves,
    needs="a moving camera (Scene(camera_motion=...))",
)
def camera_velocity(scene: Scene, samples: int | None = None, aa: int = 1) -> Frame:
    """Chapman's camera motion blur from the frame's depth and the camera's motion (module docs).

    Options: ``samples`` None (default) or N in [1, 1024]: how each pixel is blurred along its
    velocity. None: the mean of the image along the pixel's whole streak (a line integral, read
    from running sums along curves that follow the velocity field, so a pixel costs the same
    whatever its streak's length; the continuous limit of the taps, without their ghost
    copies); pixels where the curves do not fit the field (moving objects, depth edges, a fan
    of directions, streaks under 16 pixels), or where too few fit for the curves to cost less
    than the taps, take the 16-tap blur instead (its bits). N: the centred N-tap
    blur of [`motionblur.image.velocity_blur`][motionblur.image.velocity_blur] at every pixel
    (the method's bits before the line integral, with ``samples=16``). ``aa`` 1, 2 or 4 spatial
    samples per pixel along each axis for the sharp frame. The velocity from the camera at
    ``t_c`` back to the camera at the shutter's start is scaled by ``1 / t_c`` to span the whole
    shutter and clamped to ``MAX_VELOCITY`` pixels (as
    [`motionblur.image.camera_motion_blur`][motionblur.image.camera_motion_blur]). Pixels of
    moving objects take the rasterizer's velocity of the object with the camera's motion folded
    in instead (Chapman's static-scene velocity would blur an object the camera follows).
    ``stats``: ``t``, ``samples`` (None for the line integral), ``line_pixels`` (pixels blurred
    as a line integral; 0 with taps).
    """
    if samples is not None:
        samples = as_int(samples, "samples", minimum=1, maximum=image.MAX_SAMPLES)
    aa = check_aa(aa)
    require_box_shutter(scene, "camera_velocity")
    tc = shutter_centroid(scene)
    frame = _sharp(scene, tc, aa, "since_open", _static_part(scene, aa))
    rgba, lines = frame.rgba, 0
    if scene.camera_moves and tc > 0.0:
        cam, start = scene.camera_at(tc), scene.camera_at(0.0)
        # one pass in the core: per pixel, the moving object's velocity or the camera's from the
        # depth (image.camera_velocity), times 1 / tc in float32, clamped as camera_motion_blur
        # clamps (a streak past MAX_VELOCITY pixels crosses the image anyway: a very narrow
        # field of view, a point near the previous camera plane), blurred along it
        c = np.ascontiguousarray
        moving = [o.is_moving for o in scene.objects]
        rgba, lines = _core._camera_frame_blur(
            c(rgba), c(frame.depth), c(frame.ids), c(frame.velocity), moving,
            {"camera": cam, "previous_camera": start, "scale": float(np.float32(1.0 / tc)), "samples": samples},
        )  # fmt: skip
    out = Frame(rgba, frame.depth, frame.ids, frame.velocity)
    out.stats.update(t=tc, samples=samples, line_pixels=lines)
    return out


def _max_speed(vel: np.ndarray, drawn) -> float:
    """The longest velocity of ``vel`` (H,W,2) float32 (`motionblur._core._max_speed`), read
    only in the window ``drawn`` (y0, y1, x0, x1) that `_sharp` drew in (``stats["drawn"]``;
    outside it every velocity is 0: the same value), 0 when it drew nothing (None)."""
    if drawn is None:
        return 0.0
    return _core._max_speed(np.ascontiguousarray(vel), tuple(drawn))


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
    static = _static_part(scene, aa)
    if static is None:
        frame = _sharp(scene, tc, aa, "shutter", None)
        drawn, pasted = frame.stats["drawn"], None
    else:
        # the sharp colour is only read here: the static layer's kept copy with the moving
        # objects' window pasted in (Static.pasted), not a new frame-sized copy
        frame, pasted = _sharp_over(scene, tc, aa, "shutter", static)
        drawn = None if pasted is None else pasted[0]
    vel = np.ascontiguousarray(frame.velocity, dtype=np.float32)
    vmax = _max_speed(vel, drawn)
    if tile is None:
        tile = max(8, int(np.ceil(0.5 * vmax)))
    # the frame is the rasterizer's (finite, depth > 0): the core checks it once more, and
    # reads the velocities only where it drew (every other is 0)
    c = np.ascontiguousarray
    moving = drawn if drawn is not None else (0, 0, 0, 0)
    args = (c(frame.depth), vel, samples, tile, soft_depth, moving)
    if pasted is None:
        rgba = _core._reconstruct(c(frame.rgba), *args)
    else:
        with static.pasted(*pasted) as sharp:
            rgba = _core._reconstruct(sharp, *args)
    out = Frame(rgba, frame.depth, frame.ids, frame.velocity)
    out.stats.update(t=tc, samples=samples, tile=tile, max_velocity=vmax)
    return out
