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

A motion one volume cannot follow (an object that turns, a path that bends or changes speed,
a long path seen in perspective) is cut into pieces of the shutter, each drawn as its own frame
of volumes, and the frames are summed weighted by the filter's weight of each piece (see
`motionblur.methods._volume_pieces`); beyond 64 pieces the method raises ValueError.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass, field

import numpy as np

from .. import _core
from .._validate import as_bool, as_choice, as_int, as_samples, as_segments
from ..geometry import ContourTable
from ..geometry import motion_volume as build_volume
from ..geometry import spin_volume as build_spin
from ..raster import Camera, Draw, Frame
from ..render import register
from ..renderer import current_renderer
from ..scene import Object, Scene, shutter_cdf
from ._layers import (
    Layer,
    aligned_window,
    composite,
    paste,
    raster_layer,
    resolve,
    static_layer,
    supersampled,
    window_projection,
)
from ._volume_colors import UNLIT, averaged_colors, place, scattered, to_pixels, uniform
from ._volume_pieces import MAX_PIECES, check_equal, piece_scene, plan

__all__ = [
    "motion_volume",
    "apparent_keyframes",
    "apparent_motion",
    "camera_folds",
    "spin_of",
    "piece_bounds",
    "pieces_frame",
]

FILTERS: tuple[str, ...] = tuple(_core.FILTERS)

#: Still camera: draw the volumes in one rasterizer call over the kept static layer (the
#: rasterizer's ``background``), resolved by the rasterizer. False: the static objects are
#: redrawn with the volumes at sample resolution and resolved apart (the tests and
#: ``benches/bench_raster.py`` compare the two).
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


def apparent_motion(scene: Scene, obj: Object, segments: int, folds=None):
    """The keyframe engine's rigid keyframes (``_core._Keyframes``) of ``obj`` at the times
    ``i / S`` as the camera at the reference time sees them: ``P(t_r) @ inv(P(t)) @ O(t)``
    (paper section 3.1). With a still camera these are the object's own keyframes resampled
    (interpolated from their parts, not split again); a moving camera makes new matrices,
    split once. ``folds``: optional `camera_folds` of the same ``segments``."""
    if not scene.camera_moves and obj.is_moving:
        return obj.motion._keys.resampled(segments)
    times = np.linspace(0.0, 1.0, segments + 1)
    own = np.broadcast_to(obj.transform_at(0.0), (len(times), 4, 4))
    if scene.camera_moves:
        if obj.is_moving:
            own = obj.motion.transforms_at(times)
        if folds is None:
            folds = camera_folds(scene, segments)
        own = folds @ own
    return _core._Keyframes(times, np.ascontiguousarray(own), None, "motion")


def apparent_keyframes(scene: Scene, obj: Object, segments: int, folds=None) -> np.ndarray:
    """(S+1,4,4) float64 placements of ``obj`` at the times ``i / S`` as the camera at the
    reference time sees them: the matrices of `apparent_motion`."""
    if not scene.camera_moves:
        if obj.is_moving:
            return obj.motion.transforms_at(np.linspace(0.0, 1.0, segments + 1))
        return np.array(np.broadcast_to(obj.transform_at(0.0), (segments + 1, 4, 4)))
    return apparent_motion(scene, obj, segments, folds).transforms()


#: Steps the folded motion is sampled at to find a spin (each step must turn less than SPIN_MAX_STEP).
SPIN_STEPS = 32
SPIN_MAX_STEP = 2.5
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


@dataclass
class _Volumes:
    """A frame's draws, made by `_volume_draws`: ``draws`` (drawn as, Draw) of the objects
    with apparent motion (their volumes, or the object itself when it only moves with the
    camera), ``still`` (index, Object) of the objects drawn sharp into the static layer,
    ``movers`` (index, Object) of those drawn with their apparent motion and ``pending`` (draw
    index, index, Object, volume) of the volumes waiting for per-pixel colours."""

    draws: list = field(default_factory=list)
    still: list = field(default_factory=list)
    movers: list = field(default_factory=list)
    pending: list = field(default_factory=list)


def _checked_options(scene: Scene, filter, aa, contour_line, exact_static, spin, colors, color_renders):
    """1. ``_single``'s options checked: (filter, aa, contour_line, exact_static, color_renders)."""
    if filter is None:
        if not isinstance(scene.shutter, str):
            raise ValueError(
                "shutter: motion_volume's coverage model integrates the named filters only, not "
                "custom shutter weights or a Trapezoid; pass filter='box', 'ramp', 'triangle' or 'gaussian' to "
                "choose one, or use accumulation or blur_shell, which integrate the weights"
            )
        filter = scene.shutter
    as_choice(filter, "filter", FILTERS, type_error=False)
    aa = as_samples(aa, "aa")
    contour_line = as_bool(contour_line, "contour_line")
    exact_static = as_bool(exact_static, "exact_static")
    if not ((isinstance(spin, str) and spin == "auto") or isinstance(spin, (bool, np.bool_))):
        raise ValueError(f"spin: expected 'auto', True or False, got {spin!r}")
    as_choice(colors, "colors", ("pixel", "averaged", "contour"), type_error=False)
    color_renders = as_int(color_renders, "color_renders", minimum=1, maximum=64)
    return filter, aa, contour_line, exact_static, color_renders


def _volume_draws(scene: Scene, segments, filter, eye, contour_line, spin, colors, table_for, window, stats):
    """2. Every object sorted: sharp into the static layer, or drawn with its apparent motion
    (its motion volume, a spin volume, or itself where only the camera moves it)."""
    out = _Volumes()
    tr = scene.reference_t
    folds = camera_folds(scene, segments)
    spin_folds = None
    for k, obj in enumerate(scene.objects):
        if obj.is_moving and obj.motion.is_deforming:
            raise ValueError(
                f"scene: object {k} ({obj.name or 'unnamed'}) deforms; motion_volume sweeps one rigid "
                "contour and needs rigid motion: use opaque_image (velocity masks over the static "
                "scene), velocity (per-pixel velocity buffer), blur_shell (deforming silhouettes) or "
                "accumulation"
            )
        if not obj.is_moving and not scene.camera_moves:
            out.still.append((k, obj))  # no apparent motion, nothing to fold
            continue
        apparent = apparent_motion(scene, obj, segments, folds)
        keys = apparent.transforms()
        turns = spin is True and _rotates(scene, obj)
        if _still(keys) and not turns:
            if not scene.camera_moves:
                out.still.append((k, obj))
                continue
            deforming = obj.motion is not None and obj.motion.is_deforming
            v = obj.world_vertices(tr) if deforming else place(obj, keys[-1])
            out.draws.append((obj, Draw(v, obj.mesh.faces, obj.rgba, object_id=k)))
            out.movers.append((k, obj))
            continue
        vol = None
        if turns:
            if spin_folds is None and scene.camera_moves:
                spin_folds = camera_folds(scene, SPIN_STEPS)
            sp = spin_of(apparent_keyframes(scene, obj, SPIN_STEPS, spin_folds), obj.mesh.vertices)
            if sp is not None:
                spin_filter = filter if tuple(window) == (0.0, 1.0) else "box"
                vol = _spin_volume(obj, keys[0], sp, spin_filter, eye if contour_line else None)
                stats["spins"] += 1
        drawn_as = obj
        if vol is None:
            table = table_for(obj.mesh)
            vol = build_volume(
                obj.mesh, apparent, segments=1, filter=filter, colors=obj.rgba, camera_position=eye,
                contour_line=contour_line, visible_only=contour_line, contour_table=table, window=window,
            )  # fmt: skip
            if table is not None:
                stats["contour_error"] = max(stats.get("contour_error", 0.0), vol.contour_error)
            if colors == "pixel":
                out.pending.append((len(out.draws), k, obj, vol))
            elif colors == "averaged" and not uniform(obj):
                drawn_as = _averaged(scene, k, obj, keys, segments, vol, stats)
        out.movers.append((k, obj))
        out.draws.append((drawn_as, Draw._checked(vol.vertices, vol.faces, vol.rgba, vol.normals, k, True)))
        stats["volumes"] += 1
        stats["volume_triangles"] += len(vol.faces)
    return out, folds


def _single(
    scene: Scene,
    segments: int = 1,
    filter: str | None = None,
    aa: int = 1,
    contour_line: bool = True,
    exact_static: bool = True,
    spin="auto",
    colors: str = "pixel",
    color_renders: int = 2,
    contour_table=False,
    window=(0.0, 1.0),
):
    """One motion volume per moving object over the whole shutter of ``scene`` (the paper's
    method; the options as [`motion_volume`][motionblur.motion_volume]'s). ``window``: the part of the original shutter
    ``scene``'s stands for (a piece, see [`motion_volume`][motionblur.motion_volume]): the coverage alphas weigh its
    time by the filter over that part (a spin volume takes a box weight within it).

    Its steps: 1. the options checked; 2. the objects sorted into draws (`_volume_draws`);
    3. which volumes get per-pixel colours; 4. the frame: one full frame with a moving camera
    (`_moving_camera_frame`), else the volumes' window over the kept static layer
    (`_still_camera_frame`)."""
    segments = as_segments(segments)
    filter, aa, contour_line, exact_static, color_renders = _checked_options(
        scene, filter, aa, contour_line, exact_static, spin, colors, color_renders
    )
    table_for = _contour_tables(contour_table)
    tr = scene.reference_t
    cam = supersampled(scene.camera_at(tr), aa)
    eye = cam.pose[:3, 3]  # the perspective of the coverage alphas, with or without contour_line
    stats = {
        "volumes": 0,
        "volume_triangles": 0,
        "spins": 0,
        "averaged": 0,
        "segments": segments,
        "filter": filter,
    }
    vols, folds = _volume_draws(
        scene, segments, filter, eye, contour_line, spin, colors, table_for, window, stats
    )
    # 3. per-pixel colours, unless every mover has one flat colour; a spin volume in the frame
    # makes them fall back to averaged vertex colours (as the docstring says)
    scatter = bool(vols.pending) and not all(uniform(o) for _, o in vols.movers)
    if scatter and stats["spins"]:
        scatter = False
        for i, k, obj, vol in vols.pending:
            if not uniform(obj):
                keys = apparent_keyframes(scene, obj, segments, folds)
                vols.draws[i] = (_averaged(scene, k, obj, keys, segments, vol, stats), vols.draws[i][1])
    if scene.camera_moves:
        return _moving_camera_frame(scene, cam, aa, vols, scatter, color_renders, stats)
    return _still_camera_frame(scene, cam, aa, vols, scatter, color_renders, exact_static, stats)


def _moving_camera_frame(
    scene: Scene, cam: Camera, aa: int, vols: _Volumes, scatter, color_renders, stats
) -> Frame:
    """4a. Every object that moves on screen has a volume: one full frame."""
    pcam = scene.camera_at(scene.reference_t)  # the colours' camera: one sample a pixel
    averaged = None
    if scatter:
        win = (0, 0, pcam.width, pcam.height)
        averaged = _scatter(scene, pcam, vols.movers, vols.pending, vols.draws, win, color_renders)
        stats["averaged"] += len(vols.pending)
    draws = vols.draws
    layer = raster_layer(cam, scene, draws) if draws else Layer.empty(cam.height, cam.width)
    frame = resolve(layer, aa)
    if averaged is not None:
        frame.rgba = _colored(frame.rgba, averaged, None)
    frame.stats.update(stats)
    return frame


def _still_camera_frame(
    scene: Scene, cam: Camera, aa: int, vols: _Volumes, scatter, color_renders, exact_static, stats
) -> Frame:
    """4b. Still camera: the static layer is kept across frames; the volumes are rasterized
    inside the pixel window they cover and composited over it by depth."""
    draws, still = vols.draws, vols.still
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
    pwin = tuple(v // aa for v in win)
    averaged = None
    if scatter:
        pcam = scene.camera_at(scene.reference_t)  # the colours' camera: one sample a pixel
        averaged = _scatter(scene, pcam, vols.movers, vols.pending, draws, pwin, color_renders)
        stats["averaged"] += len(vols.pending)
    if averaged is not None and not empty and static.opaque:
        layer = _over_static_per_sample(scene, cam, aa, draws, win, proj, base, averaged)
        frame = paste(static, win, layer, aa)
    elif (averaged is not None and empty) or (
        ONE_PASS and len({o.shading for o, _ in draws}) == 1 and (empty or (exact_static and static.opaque))
    ):
        # One rasterizer call, which resolves the aa x aa samples of each pixel itself. The
        # opaque static layer (read in place at the window) pre-loads it, colour and depth per
        # sample: only the volumes are drawn, depth-tested and composited over it exactly. With
        # averaged colours nothing is behind the volumes here: A times the colour per pixel.
        wcam = cam.resized((x1 - x0) // aa, (y1 - y0) // aa)
        under = None if empty else static.layer
        layer = raster_layer(
            wcam, scene, draws, projection=proj, background=under, background_origin=(x0, y0), samples=aa
        )  # fmt: skip
        if averaged is not None:
            layer.rgba = _colored(layer.rgba, averaged, None)
        frame = paste(static, pwin, layer, 1)
    else:
        wcam = cam.resized(x1 - x0, y1 - y0)
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


def _over_static_per_sample(scene: Scene, cam: Camera, aa: int, draws, win, proj, base: Layer, averaged):
    """The volumes alone, per sample, over no colour but the static scene's depth (which hides
    them): their coverage A per sample; each sample is A times the averaged colour of its pixel
    over the static sample (the samples are resolved when pasted)."""
    x0, y0, x1, y1 = win
    scam = cam.resized(x1 - x0, y1 - y0)
    depth = np.ascontiguousarray(base.depth)
    under = Layer(np.zeros((*depth.shape, 4), np.float32), depth, np.ascontiguousarray(base.ids))
    layer = raster_layer(scam, scene, draws, projection=proj, background=under)
    per_sample = np.repeat(np.repeat(averaged, aa, axis=0), aa, axis=1) if aa > 1 else averaged
    layer.rgba = _colored(layer.rgba, per_sample, base.rgba)
    return layer


@register(
    "motion_volume",
    # every filter and segment count; and the paper's surface colours, with its ramp and with box
    sweep=[{"segments": s, "filter": f} for f in FILTERS for s in (1, 2, 4, 8)]
    + [{"segments": 1, "filter": f, "colors": "contour"} for f in ("ramp", "box")]
    + [{"segments": 1, "filter": "box", "colors": "averaged"}]
    + [{"segments": 1, "filter": "box", "color_renders": k} for k in (1, 3, 4)],
    applies=_rigid,
    needs="rigid motion only (no deforming object)",
)
def motion_volume(
    scene: Scene,
    segments: int = 1,
    filter: str | None = None,
    aa: int = 1,
    contour_line: bool = True,
    exact_static: bool = True,
    spin="auto",
    colors: str = "pixel",
    color_renders: int = 2,
    contour_table=False,
    pieces="auto",
):
    """Motion-volume rendering: each moving object becomes its motion volume, drawn transparent.

    Options: ``pieces`` ``"auto"`` (default) or an int P >= 1: the shutter is cut into pieces,
    each short enough for one volume (see `motionblur.methods._volume_pieces`: per piece an
    object turns at most 0.35 rad, less when it turns in place, its centroid stays within 0.03
    object radii of the chord followed at constant speed and crosses at most 0.6 rad of the
    view), every piece is rendered as its own frame of volumes
    and the frames are summed, weighted by the shutter filter's weight of each piece (the
    time-averaged image is linear in time; the coverage alphas of a piece's volumes weigh its
    time by the filter, a spin volume's by a box). ``"auto"`` takes the fewest pieces that hold (one for a straight, slow enough
    translation: the paper's method) and raises ValueError naming ``pieces`` past 64; an int
    takes P equal pieces and raises ValueError naming ``pieces`` when one of them breaks the
    limits (never a silently wrong frame: use ``"auto"``, or the ``analytic`` or
    ``accumulation`` methods). With more than one piece the ``ramp`` filter (the paper's
    look, one volume over the shutter) raises ValueError.
    ``segments`` S >= 1 joining segments per piece (its folded motion sampled at S + 1 times);
    ``filter`` ``"ramp"`` (the paper's), ``"box"``, ``"triangle"`` or ``"gaussian"`` (default:
    the scene's shutter filter; a scene with custom shutter weights raises ValueError naming
    ``shutter`` unless a filter is given, the weights are never replaced silently); ``aa`` 1, 2 or 4 spatial
    samples per pixel along each axis; ``contour_line`` (default True) sweeps only the
    camera-visible contour edges (section 4.1; the same image with back faces culled, fewer
    triangles) instead of all of them (the camera at the reference time gives the perspective
    of the coverage alphas either way; a spin volume gets the camera only with the contour
    line); ``exact_static`` (default True) redraws the static objects inside the volumes'
    window with them, one rasterizer pass with exact transparency;
    False composites the volumes over the kept static layer per sample by depth instead (exact
    unless a volume passes through a static surface); ``spin`` (paper section 4.3, objects that spin but
    barely move) ``"auto"`` (default), True or False: with True every moving object whose
    folded motion turns about one fixed axis (see `spin_of`: 32 steps, each step's axis
    within 3 degrees of the mean) is drawn as [`motionblur.spin_volume`][motionblur.spin_volume] (contour from the
    axis, alpha from the rotational speed; ``segments`` then does not apply, one ring per
    pi/12; its rotation does not count against the pieces' limits). It is the paper's
    approximation: measured against the exact integral it gave +27% coverage for a box spun
    about the view axis and +40% seen side-on (worse than no blur), so ``"auto"`` and False never
    draw one: a spinning object is cut into pieces like any turning one. ``colors`` ``"pixel"``
    (default), ``"averaged"`` or
    ``"contour"``: the paper's volume (``"contour"``) carries the object's own surface colours
    (joining surfaces take theirs from the contour edges, section 4.1, which the paper itself
    names a weakness: a shaded sphere's streak shows its rim's shading, not the average of its
    surface). The other two give a translation volume (not a spin volume) the time-averaged
    colour the camera sees, drawn unlit (see `motionblur.methods._volume_colors`):
    ``"averaged"`` per volume vertex, from one sharp render at mid-shutter box-blurred along the
    centroid's image path (one extra pass); ``"pixel"`` per pixel, from ``color_renders`` K >= 1
    sharp renders of the moving objects at the middles of K equal pieces of the shutter, each
    pixel splatted along its own 3D point's image path (K extra passes): the volume gives each
    pixel its coverage alpha A (its geometry, the coverage model and the depth test against the
    static scene) and the splatted image its colour C, the pixel is A C over the static scene
    (where the splatted alpha is below 1e-3 the volume's vertex colours, sampled from the same
    image, stand in). Scenes whose moving objects all have one flat colour skip it (nothing to
    average); with a spin volume in the frame ``"pixel"`` falls back to ``"averaged"``.
    ``contour_table`` (paper section 4.4) False (default); True or an int K: each moving
    object's mesh gets a [`motionblur.ContourTable`][motionblur.ContourTable] of K (True: 128) stochastic directions,
    built at its first frame and kept (the last 8 meshes), and its volume sweeps the face split
    and contour stored for the direction nearest its motion instead of computing them; or
    ContourTables (one, or a list), used for the objects whose mesh they were built for.
    Deforming objects raise ValueError (use accumulation or blur shells). Returns a Frame;
    ``stats`` counts the pieces, the volume triangles, the spins and the volumes with averaged
    colours (summed over the pieces), and with tables has ``contour_error``, the largest angle
    (radians) between an object's motion and the stored direction it swept.
    """
    if filter is None and isinstance(scene.shutter, str):
        filter = scene.shutter
    options = dict(
        segments=segments, filter=filter, aa=aa, contour_line=contour_line, exact_static=exact_static,
        spin=spin, colors=colors, color_renders=color_renders, contour_table=contour_table,
    )  # fmt: skip
    return pieces_frame(scene, piece_bounds(scene, filter, spin, pieces), options)


def piece_bounds(scene: Scene, filter, spin, pieces) -> np.ndarray:
    """Boundaries (P+1,) of the pieces [`motion_volume`][motionblur.motion_volume] cuts ``scene``'s shutter
    into (``filter``: the resolved filter, None for custom weights). The error estimate's pilot
    renders a smaller camera at the full frame's boundaries (the turn-in-place limit is in pixels)."""
    if not (isinstance(pieces, str) and pieces == "auto"):
        if isinstance(pieces, str):
            raise ValueError(f"pieces: expected 'auto' or an int >= 1, got {pieces!r}")
        pieces = as_int(pieces, "pieces", minimum=1, maximum=MAX_PIECES)
    moves = scene.camera_moves or any(o.is_moving for o in scene.objects)
    if filter is None or not _rigid(scene) or not moves:
        return np.array([0.0, 1.0])  # _single raises (custom weights, deforming objects) or no motion
    as_choice(filter, "filter", FILTERS, type_error=False)
    spun = _spun(scene) if spin is True else frozenset()
    return plan(scene, spun) if pieces == "auto" else check_equal(scene, pieces, spun)


def pieces_frame(scene: Scene, bounds: np.ndarray, options: dict) -> Frame:
    """The motion-volume frame of ``scene`` cut at ``bounds`` (see `piece_bounds`), ``options``
    [`motion_volume`][motionblur.motion_volume]'s with the filter resolved."""
    filter = options["filter"]
    if len(bounds) == 2:
        frame = _single(scene, **options)
        frame.stats["pieces"] = 1
        return frame
    if filter == "ramp":
        raise ValueError(
            f"filter: 'ramp' (the paper's look) is one volume over the shutter, and this motion needs "
            f"{len(bounds) - 1} pieces of it (it turns, bends or crosses the view too much for one "
            "volume); pass filter='box', 'triangle' or 'gaussian', or use render(scene, 'analytic') "
            "or render(scene, 'accumulation')"
        )
    weights = np.diff(shutter_cdf(filter, bounds))
    frames = []
    for a, b, w in zip(bounds[:-1], bounds[1:], weights):
        if w > 0.0:
            piece = piece_scene(scene, float(a), float(b))
            frames.append((w, _single(piece, **options, window=(float(a), float(b)))))
    return _summed(frames, len(bounds) - 1, filter)


def _spun(scene: Scene) -> frozenset:
    """Indices of the objects ``spin=True`` draws as spin volumes (see `spin_of`)."""
    folds = camera_folds(scene, SPIN_STEPS) if scene.camera_moves else None
    out = set()
    for k, obj in enumerate(scene.objects):
        if (obj.is_moving or scene.camera_moves) and _rotates(scene, obj):
            keys = apparent_keyframes(scene, obj, SPIN_STEPS, folds)
            if spin_of(keys, obj.mesh.vertices) is not None:
                out.add(k)
    return frozenset(out)


def _summed(frames, pieces: int, filter: str) -> Frame:
    """The pieces' frames ``(weight, Frame)`` summed: RGBA weighted, depth and ids of the nearest."""
    rgba = np.zeros_like(frames[0][1].rgba, dtype=np.float64)
    for w, f in frames:
        rgba += w * f.rgba
    depth = np.stack([f.depth for _, f in frames])
    near = np.argmin(depth, axis=0)[None]
    ids = np.take_along_axis(np.stack([f.ids for _, f in frames]), near, axis=0)[0]
    out = Frame(rgba.astype(np.float32), np.take_along_axis(depth, near, axis=0)[0], ids, None)
    stats = {"pieces": pieces, "filter": filter}
    for _, f in frames:
        for k, v in f.stats.items():
            if k in ("volumes", "volume_triangles", "spins", "averaged"):
                stats[k] = stats.get(k, 0) + v
            elif k == "contour_error":
                stats[k] = max(stats.get(k, 0.0), v)
            elif k not in stats and k != "window":
                stats[k] = v
    out.stats.update(stats)
    return out


#: Directions of the tables ``contour_table=True`` builds, and the meshes whose tables are kept.
CONTOUR_DIRECTIONS = 128


def _contour_tables(option):
    """``contour_table`` -> a function from an object's mesh to its ContourTable or None."""
    if option is False or option is None:
        return lambda mesh: None
    if isinstance(option, ContourTable):
        option = [option]
    if isinstance(option, (list, tuple)):
        if not all(isinstance(t, ContourTable) for t in option):
            raise TypeError("contour_table: expected True, False, an int or ContourTables")
        return lambda mesh: next((t for t in option if t.mesh is mesh), None)
    k = CONTOUR_DIRECTIONS if option is True else as_int(option, "contour_table", minimum=1, maximum=65536)

    def table_for(mesh):
        kept = current_renderer().contour_tables  # each table holds its mesh: the id stays its
        key = (id(mesh), k)
        hit = kept.get(key, lambda table: table.mesh is mesh)
        if hit is None:
            hit = ContourTable(mesh, directions=k)
            kept.put(key, hit)
        return hit

    return table_for


def _window(cam: Camera, vertex_sets):
    """Pixel rectangle of ``cam`` holding every vertex of ``vertex_sets``; the whole image when a
    vertex is behind the camera; None when there is nothing."""
    if not vertex_sets:
        return None
    lo, hi = np.array([np.inf, np.inf]), np.array([-np.inf, -np.inf])
    world_to_pixels = to_pixels(cam)
    for v in vertex_sets:
        b = _core._pixel_bounds(world_to_pixels, np.ascontiguousarray(v, dtype=np.float64))
        if b is None:
            return 0, 0, cam.width, cam.height
        lo = np.minimum(lo, b[:2])
        hi = np.maximum(hi, b[2:])
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


def _rotates(scene: Scene, obj: Object) -> bool:
    """Whether the object's or the camera's keyframes turn (cheap: a pure translation never
    spins, and the 32-step spin test is skipped for it)."""
    mats = []
    if obj.is_moving:
        mats.append(obj.motion.transforms[:, :3, :3])
    if scene.camera_moves:
        mats.append(scene.camera_motion.transforms[:, :3, :3])
    return any(np.abs(m - m[0]).max() > 1e-9 for m in mats)


def _averaged(scene: Scene, k: int, obj: Object, keys: np.ndarray, segments: int, vol, stats) -> object:
    """``colors="averaged"``: the volume's vertex colours set to `averaged_colors`; returns
    what the volume is drawn as (unlit when the colours were set)."""
    mid = keys[segments // 2] if segments % 2 == 0 else apparent_keyframes(scene, obj, 2)[1]
    rgb = averaged_colors(scene, k, obj, keys, mid, vol)
    if rgb is None:
        return obj
    vol.rgba = np.concatenate([rgb, vol.rgba[:, 3:]], axis=1)
    stats["averaged"] += 1
    return UNLIT  # the colours are shaded already


def _scatter(scene: Scene, pcam: Camera, movers, pending, draws, pwin, pieces: int) -> np.ndarray:
    """``colors="pixel"``: the movers' time-averaged image in the pixel window ``pwin`` of
    ``pcam`` (`scattered`); every pending volume is redrawn unlit with its vertex colours
    sampled from it (the stand-in where the per-pixel colour is not trusted)."""
    folds: dict[int, np.ndarray | None] = {}

    def keys_of(obj, n):
        if n not in folds:
            folds[n] = camera_folds(scene, n)
        return apparent_keyframes(scene, obj, n, folds[n])

    img = scattered(scene, pcam, movers, keys_of, pwin, pieces)
    world_to_window = to_pixels(pcam, pwin[0], pwin[1])
    for i, _, _, vol in pending:
        # each vertex's colour: its pixel's (nearest), where the splatted alpha is enough
        vol.rgba = _core._sample_colors(
            img,
            world_to_window,
            np.ascontiguousarray(vol.vertices, dtype=np.float64),
            np.ascontiguousarray(vol.rgba, dtype=np.float32),
        )
        # the volume's Draw (validated when made) with these colours: >= 0, the same alphas
        d = copy.copy(draws[i][1])
        d.rgba = vol.rgba.view()
        d.rgba.flags.writeable = False
        draws[i] = (UNLIT, d)
    return img


def _colored(rgba: np.ndarray, averaged: np.ndarray, static_rgba) -> np.ndarray:
    """Per pixel, the volumes' coverage alpha A (``rgba`` drawn over nothing) times the averaged
    colour where its alpha is at least MIN_ALPHA (``rgba``'s own colour elsewhere), over
    ``static_rgba`` (None: nothing)."""
    if static_rgba is not None:
        static_rgba = np.ascontiguousarray(static_rgba, dtype=np.float32)
    return _core._colored(
        np.ascontiguousarray(rgba, dtype=np.float32),
        np.ascontiguousarray(averaged, dtype=np.float32),
        static_rgba,
    )
