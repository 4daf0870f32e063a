"""Analytic motion blur (method ``analytic``): for every sample, the exact set of shutter times
during which each moving triangle covers it, visibility resolved over time, colour integrated
with the shutter filter at Gauss points.

The shutter is cut into segments within which every vertex moves linearly in clip space (see
`segment_times` for the rule); objects that do not move (with a still camera) are
rasterized once into the static layer kept across frames, which the moving triangles are
depth-tested and composited against. With a moving camera every object is drawn analytically.
"""

from __future__ import annotations

import numpy as np

from .. import _core
from .._validate import as_float, as_int
from ..analytic import MovingDraw, rasterize_motion
from ..ground_truth import _renders_exposure
from ..raster import Frame
from ..render import register
from ..scene import Camera, Object, Scene
from ._layers import static_layer, supersampled
from ._segments import MAX_SEGMENTS, MIN_PIECE, NORMAL_TOLERANCE, segment_times

__all__ = ["analytic", "refined", "segment_times", "MAX_SEGMENTS", "MIN_PIECE", "NORMAL_TOLERANCE"]


def _transform(m: np.ndarray, p: np.ndarray, out: np.ndarray) -> np.ndarray:
    """(V,4) points ``p`` (or (V,3): w = 1) transformed by the 4x4 matrix ``m`` into ``out``
    (V,4), each component summed as ``(x m0 + z m2) + (y m1 + w m3)`` (numpy's einsum order
    for four terms, which this straddle has always used: its bits), in the core
    (`motionblur._core._transform_points`, threads, the GIL released)."""
    c = np.ascontiguousarray
    _core._transform_points(c(m, np.float64), c(p, np.float64), out)
    return out


def straddled(scene: Scene, obj: Object, times: np.ndarray) -> np.ndarray:
    """(K+1,V,3) world positions at the boundaries ``times``, moved so that the motion linear in
    clip space between them straddles the true path instead of cutting inside its curves.

    Within a segment the true clip-space path of a vertex bows away from the chord by ``s``
    (its sagitta, measured at the segment's middle). Every boundary is moved by half the mean
    bow of the segments beside it, towards the bow, so the piecewise-linear path lies half
    outside and half inside the true one: its largest distance halves and the covered area
    errors on either side cancel. Straight motion (translation, vertex keyframes between their
    times, a still camera) is left exactly as it is.

    Computed one boundary at a time, the transforms in the core (`_transform`: the arithmetic
    the numpy passes had, element for element), the result written over the unmoved positions:
    besides them only the bows are held."""
    pos = np.stack([obj.world_vertices(t) for t in times])
    if len(times) < 2:
        return pos
    k, v = len(times) - 1, pos.shape[1]
    mids = 0.5 * (times[1:] + times[:-1])
    vp = np.stack([scene.camera_at(t).view_projection for t in times])
    vpm = np.stack([scene.camera_at(t).view_projection for t in mids])
    bow = np.empty((k, v, 4))  # chord middle to the true middle
    clip = (np.empty((v, 4)), np.empty((v, 4)))  # the clip positions at boundaries i and i + 1
    chord = np.empty((v, 4))
    big_bow = big_clip = 0.0
    _transform(vp[0], pos[0], clip[0])
    for i in range(k):
        c0, c1 = clip[i % 2], clip[(i + 1) % 2]
        _transform(vp[i + 1], pos[i + 1], c1)
        _transform(vpm[i], obj.world_vertices(mids[i]), bow[i])
        np.add(c1, c0, out=chord)
        chord *= 0.5
        bow[i] -= chord
        big_bow = max(big_bow, float(np.abs(bow[i]).max()))
        big_clip = max(big_clip, float(np.abs(c0).max()), float(np.abs(c1).max()))
    if not big_bow > 1e-12 * (1.0 + big_clip):
        return pos
    inv = np.linalg.inv(vp)
    shift, half, moved = clip[0], clip[1], chord
    for i in range(k + 1):
        # 0 plus half the bow after, plus half the bow before, halved between two; halved, plus
        # the boundary's clip position
        shift.fill(0.0)
        if i < k:
            np.multiply(bow[i], 0.5, out=half)
            shift += half
        if i > 0:
            np.multiply(bow[i - 1], 0.5, out=half)
            shift += half
        if 0 < i < k:
            shift *= 0.5
        shift *= 0.5
        shift += _transform(vp[i], pos[i], half)
        _transform(inv[i], shift, moved)
        np.divide(moved[:, :3], moved[:, 3:4], out=pos[i])
    return pos


def on_sample_grid(points: np.ndarray, camera: Camera, aa: int) -> np.ndarray:
    """(V,3) float64 world points moved, at their clip depth, onto the rasterizer's fixed-point
    screen grid (1/256 of a sample of ``camera`` at ``aa`` samples a pixel side), where the
    rasterizer snaps them (`motionblur._core._on_sample_grid`, the rasterizer's own snap): a
    still surface's edges then fall where accumulation's do, so no sample within that snap of
    an edge is inside for one and outside for the other (a whole pixel's difference that no
    number of time samples removes). Points behind the camera or outside the rasterizer's range
    are left as they are."""
    c = np.ascontiguousarray
    return _core._on_sample_grid(
        c(points, np.float64), c(camera.view, np.float64), c(camera.projection, np.float64),
        camera.width, camera.height, aa,
    )  # fmt: skip


def _draw(scene: Scene, obj: Object, k: int, times: np.ndarray, aa: int = 1) -> MovingDraw:
    pos = straddled(scene, obj, times)
    if not obj.is_moving and not scene.camera_moves:  # still on screen: the rasterizer's edges
        pos[:] = on_sample_grid(pos[0], scene.camera, aa)
    normals = None
    if obj.shading == "lambert" and not (obj.motion is not None and obj.motion.is_deforming):
        n0 = obj.mesh.vertex_normals()
        # each boundary's float64 normals rounded to float32 as they are made (astype's rounding)
        normals = np.empty((len(times), *n0.shape), np.float32)
        for i, t in enumerate(times):
            m = obj.transform_at(t)[:3, :3]
            normals[i] = n0 @ (m / np.cbrt(np.linalg.det(m))).T
    return MovingDraw(pos, obj.mesh.faces, obj.rgba, normals, object_id=k, shading=obj.shading)


@_renders_exposure
@register(
    "analytic",
    sweep=[{"gauss": "auto"}, {"gauss": 1}, {"gauss": 2}, {"aa": 1}, {"tolerance": 0.25}],
    applies=lambda scene: True,
)
def analytic(
    scene: Scene, aa: int = 1, gauss="auto", tolerance: float = 0.01, segments=None, exposure: bool = False
) -> Frame:
    """Analytic motion blur: the exact covered time of every sample, visibility over time.

    Options: ``aa`` 1, 2 or 4 samples per pixel along each axis; ``gauss`` points in time per
    visible piece and triangle (1 to 4, or ``"auto"``: 1 to 4, the most of two rules: by the
    piece's length, 1 below 1/32 of the shutter, 2 below 1/4, else 3; and by how far apart a
    lambert triangle's unit vertex normals are, 2 beyond 0.1, 3 beyond 0.5 and 4 beyond 1.0, since a sample
    sweeps the whole triangle within a short piece; a piece is cut where the triangle of a
    surface covering the sample changes, and where a light grazes a lambert surface, the kink
    of ``max(0, n . l)``); ``tolerance`` pixels, the
    chord rule of `segment_times`; ``segments`` an int to cut the shutter into that many
    equal segments instead (plus every keyframe time); ``exposure`` True: also the exposure
    channel, in ``stats["exposure"]`` (see
    [`exposure`][motionblur.ground_truth.exposure]). Depth, ids and velocity describe the
    surface in front at the scene's reference time (with a rolling shutter, ``Scene(rolling=)``,
    each row's: its window's instant at that fraction of it; the rolling shutter is exact). ``stats``: the kernel's (``prims``,
    ``intervals``, ``pieces``, ``splits``, ``ms_*``) plus ``segments``. Memory per thread is
    bounded by `motionblur.analytic.TILE_BUDGET_BYTES`.
    """
    return _analytic(scene, aa, gauss, tolerance, segments, exposure)


def refined(
    scene: Scene,
    aa: int = 1,
    gauss=4,
    tolerance: float = 0.01,
    segments=None,
    split: int = 4,
    longest: float = 1.0,
) -> Frame:
    """The analytic frame with every segment (of `segment_times` at ``tolerance`` pixels, or the
    ``segments`` equal ones) cut into ``split`` equal ones, and then each longer than
    ``longest`` (a share of the shutter) into as few equal ones as are not, not capped at
    `MAX_SEGMENTS`: within each, a vertex's distance from its chord falls by ``split**2``
    (where the rule stopped at its cap the pieces are cut all the same), and no visible piece is
    longer than ``longest``, which the Gauss quadrature of a triangle whose shading swings
    across it needs even where the motion is straight. The reference of the analytic method's
    error estimate (`motionblur.methods._estimate`); ``aa`` and ``gauss`` as in `analytic`.
    Returns a Frame (``rgba`` (H,W,4) float32 premultiplied, not over the background)."""
    n = as_int(split, "split", minimum=1, maximum=64)
    most = as_float(longest, "longest")
    if not 1.0 / 1024 <= most <= 1.0:
        raise ValueError(f"longest: must be in [1/1024, 1], got {most}")
    return _analytic(scene, aa, gauss, tolerance, segments, False, split=n, longest=most)


def _analytic(
    scene: Scene, aa, gauss, tolerance, segments, exposure, split: int = 1, longest: float = 1.0
) -> Frame:
    """`analytic`'s body; ``split`` and ``longest`` cut the rule's segments further (`refined`)."""
    aa = as_int(aa, "aa")
    if aa not in (1, 2, 4):
        raise ValueError(f"aa: must be 1, 2 or 4, got {aa}")
    cam = supersampled(scene.camera, aa)
    everything = list(enumerate(scene.objects))
    if scene.camera_moves or any(o.is_transparent for o in scene.objects if not o.is_moving):
        # A still transparent surface cannot be one entry a sample of the static layer: a moving
        # surface behind it, or a still one of another shading mode, would be lost. Every object
        # then goes through the kernel, which sorts them all (a still one has the same positions
        # at every boundary).
        moving, still = everything, []
    else:
        moving = [(k, o) for k, o in everything if o.is_moving]
        still = [(k, o) for k, o in everything if not o.is_moving]
    static = static_layer(scene, cam, still, aa) if (still or not moving) else None
    if not isinstance(exposure, (bool, np.bool_)):
        raise TypeError(f"exposure: expected a bool, got {type(exposure).__name__}")
    if not moving and not exposure:
        f = Frame(
            static.rgba.copy(), static.depth.copy(), static.ids.copy(), np.zeros((*static.ids.shape, 2))
        )
        f.stats.update({"segments": 0})
        return f
    if not moving:  # the exposure of the static layer alone, through the same kernel
        times = np.array([0.0, 1.0])
    elif segments is None:
        times = segment_times(scene, [o for _, o in moving], scene.camera, tolerance)
    else:
        n = as_int(segments, "segments", minimum=1, maximum=MAX_SEGMENTS)
        cuts = set(np.linspace(0.0, 1.0, n + 1).tolist())
        motions = [o.motion for _, o in moving if o.motion is not None]
        if scene.camera_motion is not None:
            motions.append(scene.camera_motion)
        for m in motions:
            cuts.update(float(t) for t in m.times if 0.0 < t < 1.0)
        times = np.array(sorted(cuts))
    if split > 1 and moving:
        u = np.arange(split) / split
        times = np.append((times[:-1, None] + np.diff(times)[:, None] * u).ravel(), 1.0)
    if longest < 1.0 and moving:
        parts = np.maximum(1, np.ceil(np.diff(times) / longest - 1e-9)).astype(int)
        pieces = [a + (b - a) * np.arange(k) / k for a, b, k in zip(times[:-1], times[1:], parts)]
        times = np.append(np.concatenate(pieces), 1.0)
    draws = [_draw(scene, o, k, times, aa) for k, o in moving]
    cams = [scene.camera_at(t) for t in times] if scene.camera_moves else scene.camera
    background = None
    if static is not None:
        L = static.layer
        background = (L.rgba, L.depth, L.ids)
    lights = [(li.direction, li.intensity) for li in scene.lights]
    frame = rasterize_motion(
        cams, draws, times, samples=aa, shutter=scene.shutter, lights=lights,
        ambient=scene.ambient, gauss=gauss, reference_time=scene.reference_t, background=background,
        exposure=len(scene.objects) if exposure else None, rolling=scene.rolling,
        rolling_direction=scene.rolling_direction,
    )  # fmt: skip
    frame.stats["segments"] = len(times) - 1
    return frame
