"""Motion volumes (Wloka and Zeleznik 1996): one semi-transparent volume per moving object.

The frame is rendered once, with the camera at the scene's reference time ``t_r`` (the shutter
close by default, as in the paper). Camera motion is folded into each object's motion (paper
section 3.1): the object at time ``t`` is placed where the camera at ``t_r`` sees what the camera
at ``t`` saw, ``W(t) = P(t_r) P(t)^-1 O(t)`` with ``P`` the camera pose and ``O`` the object's
transform, so a camera pan blurs the whole still scene and a camera that follows an object
leaves it sharp. For ``segments`` S the folded motion is sampled at the S + 1 times ``i / S``
and the volume joins the contour rings of those placements. Objects without apparent motion are
drawn sharp and opaque; the volumes are drawn over them with exact (depth-sorted per sample)
transparency.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from .. import image
from .._validate import as_int
from ..geometry import motion_volume as build_volume
from ..geometry import spin_volume as build_spin
from ..raster import Camera, Draw, Frame
from ..render import (
    Layer,
    aligned_window,
    composite,
    paste,
    raster_layer,
    register,
    resolve,
    static_layer,
    supersampled,
    window_projection,
)
from ..scene import Object, Scene

__all__ = ["motion_volume", "apparent_keyframes", "camera_folds", "spin_of"]

FILTERS = ("ramp", "box", "triangle", "gaussian")

#: Still camera: draw the volumes in one rasterizer call over the kept static layer (the
#: rasterizer's ``background``), resolved by the rasterizer. False restores the previous path
#: (static objects redrawn with the volumes at sample resolution, resolved apart); the
#: benchmark and the tests compare the two.
ONE_PASS = True


def _rigid(scene: Scene) -> bool:
    return not any(o.is_moving and o.motion.is_deforming for o in scene.objects)


def camera_folds(scene: Scene, segments: int) -> np.ndarray | None:
    """(S+1,4,4) float64 ``P(t_r) @ inv(P(t))`` at the times ``i / S``, or None for a still
    camera (computed once per frame, shared by every object)."""
    if not scene.camera_moves:
        return None
    ref = scene.camera_pose_at(scene.reference_t)
    return np.stack(
        [ref @ np.linalg.inv(scene.camera_pose_at(t)) for t in np.linspace(0.0, 1.0, segments + 1)]
    )


def apparent_keyframes(scene: Scene, obj: Object, segments: int, folds=None) -> np.ndarray:
    """(S+1,4,4) float64 placements of ``obj`` at the times ``i / S`` as the camera at the
    reference time sees them: ``P(t_r) @ inv(P(t)) @ O(t)`` (paper section 3.1). ``folds``:
    optional :func:`camera_folds` of the same ``segments``."""
    times = np.linspace(0.0, 1.0, segments + 1)
    if not obj.is_moving:
        own = np.broadcast_to(obj.transform_at(0.0), (len(times), 4, 4))
    else:
        own = np.stack([obj.transform_at(t) for t in times])
    if not scene.camera_moves:
        return np.array(own)
    if folds is None:
        folds = camera_folds(scene, segments)
    return folds @ own


#: Steps the folded motion is sampled at to find a spin (each step must turn less than SPIN_MAX_STEP).
SPIN_STEPS = 32
SPIN_MAX_STEP = 2.5
#: auto spin: the arc the farthest vertex travels about the axis over the shutter, at least this
#: many times the path of the object's vertex centroid (``|angle| r >= SPIN_DOMINANCE * path``).
SPIN_DOMINANCE = 4.0
#: largest angle (radians) between a step's rotation axis and the mean axis for a "fixed" axis.
SPIN_AXIS_TOLERANCE = np.radians(3.0)


def _rotvec(m: np.ndarray) -> np.ndarray:
    """(3,) rotation vector (axis times angle, angle < pi) of the 3x3 rotation ``m``."""
    c = np.clip((np.trace(m) - 1.0) * 0.5, -1.0, 1.0)
    ang = np.arccos(c)
    w = np.array([m[2, 1] - m[1, 2], m[0, 2] - m[2, 0], m[1, 0] - m[0, 1]])
    s = np.linalg.norm(w)
    if s < 1e-15:
        return np.zeros(3)
    return w / s * ang


def spin_of(keys: np.ndarray, vertices: np.ndarray) -> dict | None:
    """The spin in the (n+1,4,4) placements ``keys`` of an object with local ``vertices`` (V,3),
    or None when they do not turn about one fixed axis.

    Each step's rotation ``R(i+1) R(i)^T`` is taken as a rotation vector; the axis is their
    mean direction and must hold every step within ``SPIN_AXIS_TOLERANCE`` (3 degrees), the
    scale must not change and no step may turn more than ``SPIN_MAX_STEP`` radians. The point on
    the axis (nearest the vertices' centroid) is the least-squares point that the placements
    move along a straight line at constant speed. Returns, in the object's LOCAL frame of the shutter-open placement ``keys[0]``:
    ``axis`` (unit), ``center`` (on the axis, nearest the vertices' centroid) and
    ``translation`` (of that point, open to close); and ``angle`` (radians, signed about the
    axis, may exceed 2 pi), ``radius`` (world units: the farthest vertex from the axis),
    ``centre_path`` (world path length of the vertex centroid over the steps) and
    ``dominance`` = ``|angle| radius / centre_path`` (inf when the centre does not move).
    """
    m3 = keys[:, :3, :3]
    scale = np.cbrt(np.linalg.det(m3))
    if np.abs(scale - scale[0]).max() > 1e-9 * abs(scale[0]) or scale[0] <= 0:
        return None
    rots = m3 / scale[:, None, None]
    steps = np.array([_rotvec(b @ a.T) for a, b in zip(rots[:-1], rots[1:])])
    norms = np.linalg.norm(steps, axis=1)
    if norms.max() > SPIN_MAX_STEP:
        return None
    total = steps.sum(axis=0)
    if np.linalg.norm(total) < 1e-9:
        return None
    axis = total / np.linalg.norm(total)
    moving = norms > 1e-12
    if (steps[moving] @ axis / norms[moving]).min() < np.cos(SPIN_AXIS_TOLERANCE):
        return None
    angle = float((steps @ axis).sum())
    # the axis point q (local) moving linearly by T (world): M_i q + t_i = M_0 q + t_0 + u_i T
    n = len(keys) - 1
    u = np.arange(1, n + 1) / n
    a_mat = np.concatenate([m3[1:] - m3[0], -u[:, None, None] * np.eye(3)], axis=2).reshape(-1, 6)
    b_vec = (keys[0, :3, 3] - keys[1:, :3, 3]).reshape(-1)
    q = np.linalg.lstsq(a_mat, b_vec, rcond=None)[0][:3]
    a_loc = rots[0].T @ axis
    centre = vertices.mean(axis=0)
    q = q + ((centre - q) @ a_loc) * a_loc
    trans = (m3[-1] - m3[0]) @ q + keys[-1, :3, 3] - keys[0, :3, 3]
    rel = vertices - q
    radius = float(np.linalg.norm(rel - np.outer(rel @ a_loc, a_loc), axis=1).max() * scale[0])
    cpath = m3 @ centre + keys[:, :3, 3]
    centre_path = float(np.linalg.norm(np.diff(cpath, axis=0), axis=1).sum())
    arc = abs(angle) * radius
    return {
        "axis": a_loc,
        "angle": angle,
        "center": q,
        "translation": np.linalg.solve(m3[0], trans),
        "radius": radius,
        "centre_path": centre_path,
        "dominance": arc / centre_path if centre_path > 0 else float("inf"),
    }


@register(
    "motion_volume",
    # every filter and segment count; and the paper's surface colours, with its ramp and with box
    sweep=[{"segments": s, "filter": f} for f in FILTERS for s in (1, 2, 4, 8)]
    + [{"segments": 1, "filter": f, "colors": "contour"} for f in ("ramp", "box")],
    applies=_rigid,
)
def motion_volume(
    scene: Scene,
    segments: int = 1,
    filter: str | None = None,
    aa: int = 1,
    contour_line: bool = True,
    exact_static: bool = True,
    spin="auto",
    colors: str = "averaged",
):
    """Motion-volume rendering: each moving object becomes its motion volume, drawn transparent.

    Options: ``segments`` S >= 1 joining segments (the folded motion sampled at S + 1 times);
    ``filter`` ``"ramp"`` (the paper's), ``"box"``, ``"triangle"`` or ``"gaussian"`` (default:
    the scene's shutter filter when it is a name, else ``"box"``); ``aa`` 1, 2 or 4 spatial
    samples per pixel along each axis; ``contour_line`` (default True) sweeps only the
    camera-visible contour edges (section 4.1; the same image with back faces culled, fewer
    triangles) instead of all of them (the camera at the reference time gives the perspective
    of the coverage alphas either way; a spin volume gets the camera only with the contour
    line); ``exact_static`` (default True) redraws the static objects inside the volumes'
    window with them, one rasterizer pass with exact transparency;
    False composites the volumes over the kept static layer per sample by depth instead (exact
    unless a volume passes through a static surface; with numpy compositing it was the slower
    of the two on the built-in scenes); ``spin`` (paper section 4.3, objects that spin but
    barely move) ``"auto"`` (default), True or False: with True every moving object whose
    folded motion turns about one fixed axis (see :func:`spin_of`: 32 steps, each step's axis
    within 3 degrees of the mean) is drawn as :func:`motionblur.spin_volume` (contour from the
    axis, alpha from the rotational speed; ``segments`` then does not apply, one ring per
    pi/12); with ``"auto"`` only those that spin in place: the arc the vertex farthest from the
    axis travels is at least 4 times the path of the object's vertex centroid
    (``|angle| r >= 4 path``: a propeller or wheel, not an object orbiting a far axis nor a
    camera pan); False never; ``colors`` ``"averaged"`` (default) or ``"contour"``: the
    paper's volume carries the object's own surface colours (joining surfaces take theirs from
    the contour edges, section 4.1, which the paper itself names a weakness: a shaded sphere's
    streak shows its rim's shading, not the average of its surface). With ``"averaged"`` every
    vertex of a translation volume (not a spin volume) takes the time-averaged colour the camera
    sees at its image instead: the object is rendered sharp at mid-shutter inside the volume's
    window (one extra pass, one sample a pixel), box-blurred along its centroid's image path and
    sampled at the vertices (exact for a translation seen orthographically), and the volume is
    drawn unlit with those shaded colours. Objects of one flat colour skip it (nothing to
    average). Deforming objects raise ValueError (use accumulation or blur shells). Returns a
    Frame; ``stats`` counts the volume triangles, the spins and the averaged volumes.
    """
    segments = as_int(segments, "segments", minimum=1, maximum=4096)
    if filter is None:
        filter = scene.shutter if isinstance(scene.shutter, str) else "box"
    if not isinstance(filter, str) or filter not in FILTERS:
        raise ValueError(f"filter: expected one of {', '.join(FILTERS)}, got {filter!r}")
    aa = as_int(aa, "aa")
    if aa not in (1, 2, 4):
        raise ValueError(f"aa: must be 1, 2 or 4, got {aa}")
    if not (spin == "auto" or isinstance(spin, (bool, np.bool_))):
        raise ValueError(f"spin: expected 'auto', True or False, got {spin!r}")
    if not isinstance(colors, str) or colors not in ("averaged", "contour"):
        raise ValueError(f"colors: expected 'averaged' or 'contour', got {colors!r}")
    tr = scene.reference_t
    cam = supersampled(scene.camera_at(tr), aa)
    eye = cam.pose[:3, 3]  # the perspective of the coverage alphas, with or without contour_line
    draws: list[tuple[Object, Draw]] = []
    still: list[tuple[int, Object]] = []
    stats = {
        "volumes": 0,
        "volume_triangles": 0,
        "spins": 0,
        "averaged": 0,
        "segments": segments,
        "filter": filter,
    }
    folds = camera_folds(scene, segments)
    spin_folds = None
    for k, obj in enumerate(scene.objects):
        if obj.is_moving and obj.motion.is_deforming:
            raise ValueError(
                f"scene: object {k} ({obj.name or 'unnamed'}) deforms; motion_volume needs rigid motion "
                "(use accumulation or blur_shell)"
            )
        if not obj.is_moving and not scene.camera_moves:
            still.append((k, obj))  # no apparent motion, nothing to fold
            continue
        keys = apparent_keyframes(scene, obj, segments, folds)
        turns = spin is not False and _rotates(scene, obj) and (spin is True or _may_spin(keys, obj))
        if _still(keys) and not turns:
            if not scene.camera_moves:
                still.append((k, obj))
                continue
            deforming = obj.motion is not None and obj.motion.is_deforming
            v = obj.world_vertices(tr) if deforming else _place(obj, keys[-1])
            draws.append((obj, Draw(v, obj.mesh.faces, obj.rgba, object_id=k)))
            continue
        vol = None
        if turns:
            if spin_folds is None and scene.camera_moves:
                spin_folds = camera_folds(scene, SPIN_STEPS)
            sp = spin_of(apparent_keyframes(scene, obj, SPIN_STEPS, spin_folds), obj.mesh.vertices)
            if sp is not None and (spin is True or sp["dominance"] >= SPIN_DOMINANCE):
                vol = _spin_volume(obj, keys[0], sp, filter, eye if contour_line else None)
                stats["spins"] += 1
        drawn_as = obj
        if vol is None:
            vol = build_volume(
                obj.mesh, keys, segments=1, filter=filter, colors=obj.rgba, camera_position=eye,
                contour_line=contour_line,
            )  # fmt: skip
            rgb = (
                _averaged_colors(scene, k, obj, keys, vol)
                if colors == "averaged" and not _uniform(obj)
                else None
            )
            if rgb is not None:
                vol.rgba = np.concatenate([rgb, vol.rgba[:, 3:]], axis=1)
                drawn_as = _UNLIT  # the colours are shaded already
                stats["averaged"] += 1
        draws.append(
            (
                drawn_as,
                Draw(vol.vertices, vol.faces, vol.rgba, normals=vol.normals, object_id=k, cull_back=True),
            )
        )
        stats["volumes"] += 1
        stats["volume_triangles"] += len(vol.faces)
    if scene.camera_moves:
        # every object that moves on screen has a volume: one full frame
        layer = raster_layer(cam, scene, draws) if draws else Layer.empty(cam.height, cam.width)
        frame = resolve(layer, aa)
        frame.stats.update(stats)
        return frame
    # Still camera: the static layer is kept across frames; the volumes are rasterized inside
    # the pixel window they cover and composited over it by depth.
    static = static_layer(scene, cam, still, aa)
    stats["static_cached"] = static.cached
    win = _window(cam, [d.vertices for _, d in draws])
    if win is None:
        frame = Frame(
            static.rgba.copy(), static.depth.copy(), static.ids.copy(), np.zeros((*static.ids.shape, 2))
        )
        frame.stats.update(stats)
        return frame
    win = aligned_window(win, aa, cam.width, cam.height)
    x0, y0, x1, y1 = win
    stats["window"] = win
    proj = window_projection(cam.projection, cam.width, cam.height, win)
    base = Layer(
        static.layer.rgba[y0:y1, x0:x1], static.layer.depth[y0:y1, x0:x1], static.layer.ids[y0:y1, x0:x1]
    )
    empty = not still or not np.isfinite(base.depth).any()
    one_call = ONE_PASS and len({o.shading for o, _ in draws}) == 1
    if one_call and (empty or (exact_static and static.opaque)):
        # One rasterizer call, which resolves the aa x aa samples of each pixel itself. The
        # opaque static layer (read in place at the window) pre-loads it, colour and depth per
        # sample: only the volumes are drawn, depth-tested and composited over it exactly.
        pcam = Camera(cam.pose, cam.yfov, (x1 - x0) // aa, (y1 - y0) // aa, cam.znear, cam.zfar)
        under = None if empty else static.layer
        layer = raster_layer(
            pcam, scene, draws, projection=proj, background=under, background_origin=(x0, y0), samples=aa
        )  # fmt: skip
        frame = paste(static, tuple(v // aa for v in win), layer, 1)
        frame.stats.update(stats)
        return frame
    wcam = Camera(cam.pose, cam.yfov, x1 - x0, y1 - y0, cam.znear, cam.zfar)
    if empty:
        layer = raster_layer(wcam, scene, draws, projection=proj)
    elif exact_static:
        # the static objects redrawn with the volumes in the window: exact transparency always
        statics = [(o, Draw(o.world_vertices(0.0), o.mesh.faces, o.rgba, object_id=k)) for k, o in still]
        layer = raster_layer(wcam, scene, statics + draws, projection=proj)
    else:
        layer = composite(raster_layer(wcam, scene, draws, projection=proj), base)
    frame = paste(static, win, layer, aa)
    frame.stats.update(stats)
    return frame


def _window(cam: Camera, vertex_sets):
    """Pixel rectangle of ``cam`` holding every vertex of ``vertex_sets``; the whole image when a
    vertex is behind the camera; None when there is nothing."""
    if not vertex_sets:
        return None
    lo, hi = np.array([np.inf, np.inf]), np.array([-np.inf, -np.inf])
    for v in vertex_sets:
        x, y, front = _pixels(cam.view_projection, v, cam.width, cam.height)
        if not front.all():
            return 0, 0, cam.width, cam.height
        lo = np.minimum(lo, [x.min(), y.min()])
        hi = np.maximum(hi, [x.max(), y.max()])
    x0, y0 = max(0, int(np.floor(lo[0])) - 1), max(0, int(np.floor(lo[1])) - 1)
    x1, y1 = min(cam.width, int(np.ceil(hi[0])) + 1), min(cam.height, int(np.ceil(hi[1])) + 1)
    if x0 >= x1 or y0 >= y1:
        return None
    return x0, y0, x1, y1


def _still(keys: np.ndarray) -> bool:
    """No apparent motion: every keyframe equals the last one up to rounding (a camera that
    follows its object folds to products like ``T P inv(T P)``, equal only to ~1e-15)."""
    scale = 1.0 + np.abs(keys[:, :3, 3]).max()
    return bool(np.abs(keys - keys[-1]).max() <= 1e-12 * scale)


def _spin_volume(obj: Object, open_pose: np.ndarray, sp: dict, filter: str, eye):
    """spin_volume built in the object's local frame (its mesh and adjacency reused), placed
    in the world by the shutter-open placement."""
    inv = np.linalg.inv(open_pose)
    cam_local = None if eye is None else inv[:3, :3] @ eye + inv[:3, 3]
    vol = build_spin(
        obj.mesh, sp["axis"], sp["angle"], sp["center"], sp["translation"],
        filter=filter, colors=obj.rgba, camera_position=cam_local,
    )  # fmt: skip
    m = open_pose[:3, :3]
    vol.vertices = vol.vertices @ m.T + open_pose[:3, 3]
    rot = m / np.cbrt(np.linalg.det(m))
    vol.normals = (vol.normals @ rot.T).astype(np.float32)
    return vol


def _may_spin(keys: np.ndarray, obj: Object) -> bool:
    """A cheap necessary test for the auto spin on the coarse placements ``keys``: a spin in
    place has its axis within R/3 of the centroid (R its farthest vertex), so its farthest arc
    is at most 4R/3 times the angle; with a margin, run the 32-step test only when
    ``angle * 2R >= SPIN_DOMINANCE * centroid chord path``."""
    m3 = keys[:, :3, :3]
    scale = np.cbrt(abs(np.linalg.det(m3[0])))
    rots = m3 / scale
    angle = sum(np.linalg.norm(_rotvec(b @ a.T)) for a, b in zip(rots[:-1], rots[1:]))
    if not keys.shape[0] > 1 or angle <= 0.0:
        return False
    v = obj.mesh.vertices
    c = v.mean(axis=0)
    radius = float(np.sqrt(((v - c) ** 2).sum(axis=1).max())) * scale
    path = m3 @ c + keys[:, :3, 3]
    chord = float(np.linalg.norm(np.diff(path, axis=0), axis=1).sum())
    return angle * 2.0 * radius >= SPIN_DOMINANCE * chord


def _rotates(scene: Scene, obj: Object) -> bool:
    """Whether the object's or the camera's keyframes turn (cheap: a pure translation never
    spins, and the 32-step spin test is skipped for it)."""
    mats = []
    if obj.is_moving:
        mats.append(obj.motion.transforms[:, :3, :3])
    if scene.camera_moves:
        mats.append(scene.camera_motion.transforms[:, :3, :3])
    return any(np.abs(m - m[0]).max() > 1e-9 for m in mats)


def _place(obj: Object, m: np.ndarray) -> np.ndarray:
    return obj.mesh.vertices @ m[:3, :3].T + m[:3, 3]


#: Stand-in for an object drawn unlit: colours already shaded (``raster_layer`` groups by it).
_UNLIT = SimpleNamespace(shading="flat")


def _uniform(obj: Object) -> bool:
    """Flat shading and one colour: the time-averaged colour is that colour."""
    c = obj.rgba
    return obj.shading == "flat" and (c.ndim == 1 or bool((c == c[0]).all()))


def _averaged_colors(scene: Scene, k: int, obj: Object, keys: np.ndarray, vol) -> np.ndarray | None:
    """Straight RGB (N,3) float32 for the N volume vertices: the time-averaged colour the camera
    sees at each one's image, or None (leave the volume's own colours).

    The object alone is rendered sharp (shaded, one sample a pixel) at its mid-shutter placement
    as the camera at the reference time sees it, inside the volume's pixel window, and box-blurred
    along the image path of its centroid from shutter open to close: for a translation seen
    orthographically that blurred layer is exactly the time average of the object's image (the
    window reaches beyond the view by the image path, at most one image size, so an object
    leaving the view still colours its streak). Each vertex takes the blurred colour over the blurred alpha at its image (bilinear); where that
    alpha is below 1e-3 (outside every position of the object) or the vertex is behind the camera
    it keeps its own colour."""
    cam = scene.camera_at(scene.reference_t)
    c = obj.mesh.vertices.mean(axis=0)
    ex, ey, ok = _pixels(
        cam.view_projection,
        np.array([m[:3, :3] @ c + m[:3, 3] for m in (keys[0], keys[-1])]),
        cam.width,
        cam.height,
    )
    if not ok.all():
        return None
    dx, dy = float(ex[1] - ex[0]), float(ey[1] - ey[0])
    # The volume's pixel box, cut to the view grown by the image path (what passes the view
    # during the shutter, also from outside it) and at most one image size beyond each side.
    x, y, front = _pixels(cam.view_projection, vol.vertices, cam.width, cam.height)
    if front.all():
        mx, my = min(abs(dx) + 1.0, cam.width), min(abs(dy) + 1.0, cam.height)
        x0 = int(max(np.floor(x.min()) - 1, -mx))
        y0 = int(max(np.floor(y.min()) - 1, -my))
        x1 = int(min(np.ceil(x.max()) + 1, cam.width + mx))
        y1 = int(min(np.ceil(y.max()) + 1, cam.height + my))
    else:
        x0, y0, x1, y1 = 0, 0, cam.width, cam.height
    if x1 <= x0 or y1 <= y0:
        return None
    win = (x0, y0, x1, y1)
    w, h = x1 - x0, y1 - y0
    proj = window_projection(cam.projection, cam.width, cam.height, win)
    wcam = Camera(cam.pose, cam.yfov, w, h, cam.znear, cam.zfar)
    n = len(keys) - 1
    mid = keys[n // 2] if n % 2 == 0 else apparent_keyframes(scene, obj, 2)[1]
    draw = Draw(_place(obj, mid), obj.mesh.faces, obj.rgba, object_id=k)
    sharp = raster_layer(wcam, scene, [(obj, draw)], projection=proj).rgba
    length = float(np.hypot(dx, dy))
    if length >= 1.0:
        sharp = image.box_blur(sharp, (dx, dy), length)
    px, py = x - x0 - 0.5, y - y0 - 0.5  # in the window (same pixel centres), centres at +0.5
    i0 = np.clip(np.floor(px), 0, max(w - 2, 0)).astype(np.int64)
    j0 = np.clip(np.floor(py), 0, max(h - 2, 0)).astype(np.int64)
    i1, j1 = np.minimum(i0 + 1, w - 1), np.minimum(j0 + 1, h - 1)
    fx = np.clip(px - i0, 0.0, 1.0)[:, None]
    fy = np.clip(py - j0, 0.0, 1.0)[:, None]
    b = sharp.astype(np.float64)
    s = (b[j0, i0] * (1 - fx) + b[j0, i1] * fx) * (1 - fy) + (b[j1, i0] * (1 - fx) + b[j1, i1] * fx) * fy
    keep = (s[:, 3] < 1e-3) | ~front
    return np.where(keep[:, None], vol.rgba[:, :3], s[:, :3] / np.maximum(s[:, 3:], 1e-3)).astype(np.float32)


def _pixels(vp: np.ndarray, p: np.ndarray, width: int, height: int):
    """Pixel coordinates ``x``, ``y`` (N,) of the points ``p`` (N,3) under the view-projection
    ``vp`` of a ``width`` x ``height`` image, and whether each is in front of the camera."""
    clip = p @ vp[:3, :3].T + vp[:3, 3]
    wc = p @ vp[3, :3] + vp[3, 3]
    front = wc > 1e-9
    wc = np.where(front, wc, 1.0)
    return (clip[:, 0] / wc + 1.0) * 0.5 * width, (1.0 - clip[:, 1] / wc) * 0.5 * height, front
