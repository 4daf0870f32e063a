"""Analytic motion blur (method ``analytic``): for every sample, the exact set of shutter times
during which each moving triangle covers it, visibility resolved over time, colour integrated
with the shutter filter at Gauss points.

The shutter is cut into segments within which every vertex moves linearly in clip space (see
:func:`segment_times` for the rule); objects that do not move (with a still camera) are
rasterized once into the static layer kept across frames, which the moving triangles are
depth-tested and composited against. With a moving camera every object is drawn analytically.
"""

from __future__ import annotations

import heapq

import numpy as np

from .._validate import as_float, as_int
from ..analytic import MovingDraw, rasterize_motion
from ..geometry import Mesh
from ..raster import Camera, Frame
from ..render import register
from ..scene import Object, Scene
from ._layers import static_layer, supersampled

__all__ = ["analytic", "segment_times", "MAX_SEGMENTS", "NORMAL_TOLERANCE"]

#: Most segments the automatic rule makes.
MAX_SEGMENTS = 256
#: Shortest piece the rule halves: halving a piece that never comes straight (a point on a
#: path with a kink, a NaN) would end in equal boundaries.
MIN_PIECE = 1.0 / 1024.0
#: Test points per deforming object in the segment rule.
_DEFORMING_POINTS = 256
#: Largest distance between a test vertex's unit normal at a piece's middle and the direction of
#: the mean of its normals at the piece's ends (about radians), for deforming lambert objects in
#: the segment rule: their normals are computed at every boundary and interpolated between, and
#: lambert shading moves by about this much wherever they bend.
NORMAL_TOLERANCE = 2e-4


def _test_points(obj: Object) -> tuple[np.ndarray | None, np.ndarray | None]:
    """(object-space points of a rigid object, vertex indices of a deforming one)."""
    if obj.motion is not None and obj.motion.is_deforming:
        nv = len(obj.mesh.vertices)
        return None, np.linspace(0, nv - 1, min(nv, _DEFORMING_POINTS)).astype(np.int64)
    v = obj.mesh.vertices
    a, b = v.min(axis=0), v.max(axis=0)
    corners = np.array([[x, y, z] for x in (a[0], b[0]) for y in (a[1], b[1]) for z in (a[2], b[2])])
    return corners, None


def _normal_probe(obj: Object, idx: np.ndarray | None):
    """(the mesh of the faces touching the test vertices ``idx``, its vertices' indices in the
    object's mesh, the test vertices' rows in it) of a deforming lambert object, else None: the
    test vertices' normals are those of this small mesh."""
    if idx is None or obj.shading != "lambert":
        return None
    f = np.asarray(obj.mesh.faces)
    sub = f[np.isin(f, idx).any(axis=1)]
    verts = np.unique(sub)
    local = Mesh(obj.mesh.vertices[verts], np.searchsorted(verts, sub))
    return local, verts, np.searchsorted(verts, idx)


def segment_times(scene: Scene, objects, camera: Camera, tolerance: float = 0.01) -> np.ndarray:
    """(K+1,) float64 segment boundaries from 0 to 1 for ``objects`` seen by ``camera``'s image.

    The rule: the shutter is first cut at every keyframe time of the objects' motions and of
    the camera's; each piece is then halved while, at its middle, some test point lies more
    than ``tolerance`` pixels from where motion linear in clip space between the piece's ends
    puts it, as far as it can be seen: a point off the image or nearer than the near plane is
    measured as if it were at the image's border and at the near plane (its triangles show
    only there; the distance in clip space, which is linear over a triangle, is what moves
    them). Test points are the corners of each rigid object's bounding box (the farthest
    points from any rotation axis) and up to 256 vertices of each deforming one. A deforming lambert object's piece is also halved while a test
    vertex's unit normal at the middle lies more than :data:`NORMAL_TOLERANCE` from the
    direction of the mean of its normals at the ends. At most :data:`MAX_SEGMENTS` segments, none
    halved below :data:`MIN_PIECE` of the shutter: the piece furthest over its tolerance is
    halved first, so a shutter that needs more than the cap ends with every piece about equally
    far off (not with its start refined and its end left whole)."""
    tol = as_float(tolerance, "tolerance")
    if not tol > 0:
        raise ValueError(f"tolerance: must be > 0 pixels, got {tol}")
    pts = [(o, *_test_points(o)) for o in objects]
    probes = [(o, _normal_probe(o, idx)) for o, _, idx in pts]
    probes = [(o, pr) for o, pr in probes if pr is not None]
    if not pts:
        return np.array([0.0, 1.0])
    w, h = camera.width, camera.height

    def clip(t: float) -> np.ndarray:
        vp = scene.camera_at(t).view_projection
        world = []
        for o, corners, idx in pts:
            if corners is not None:
                m = o.transform_at(t)
                world.append(corners @ m[:3, :3].T + m[:3, 3])
            else:
                world.append(o.world_vertices(t)[idx])
        p = np.concatenate(world)
        return p @ vp[:3, :3].T + vp[:3, 3], p @ vp[3, :3] + vp[3, 3]

    near = camera.znear

    def pixel_error(xyz_l, w_l, xyz_m, w_m) -> float:
        """The largest screen distance (pixels) between the test points at ``(xyz_m, w_m)`` (clip
        space) and at ``(xyz_l, w_l)``, as seen where it matters: the image distance of two
        points is ``|d_xy - p d_w| / w_l`` per axis (``d`` their difference, ``p`` the NDC
        position); a point off the image or nearer than the near plane is only seen through
        the visible part of its triangles, which lies within the image (``|p| <= 1``) beyond
        the near plane (``w >= znear``), so ``p`` is clamped to [-1, 1] and ``w_l`` to
        ``znear`` and above."""
        d, dw = xyz_l - xyz_m, w_l - w_m
        with np.errstate(divide="ignore", invalid="ignore"):
            px = np.clip(xyz_m[:, 0] / w_m, -1.0, 1.0)
            py = np.clip(xyz_m[:, 1] / w_m, -1.0, 1.0)
            px = np.where(np.isfinite(px), px, 0.0)
            py = np.where(np.isfinite(py), py, 0.0)
        wl = np.maximum(w_l, near)
        ex = np.abs(d[:, 0] - px * dw) / wl * (0.5 * w)
        ey = np.abs(d[:, 1] - py * dw) / wl * (0.5 * h)
        return float(np.hypot(ex, ey).max()) if len(ex) else 0.0

    cache: dict[float, tuple] = {}

    def at(t: float):
        if t not in cache:
            cache[t] = clip(t)
        return cache[t]

    normal_cache: dict[float, list] = {}

    def normals(t: float) -> list:
        if t not in normal_cache:
            normal_cache[t] = [
                local.with_vertices(o.world_vertices(t)[verts]).vertex_normals()[rows]
                for o, (local, verts, rows) in probes
            ]
        return normal_cache[t]

    def normals_off(a: float, b: float) -> float:
        """The largest normal deviation at the middle of [a, b] over NORMAL_TOLERANCE."""
        worst = 0.0
        for na, nb, nm in zip(normals(a), normals(b), normals(0.5 * (a + b))):
            mean = na + nb
            length = np.linalg.norm(mean, axis=1, keepdims=True)
            ok = (length[:, 0] > 1e-12) & (np.linalg.norm(nm, axis=1) > 0)
            mean = mean / np.where(length > 1e-12, length, 1.0)
            dev = np.linalg.norm(nm[ok] - mean[ok], axis=1)
            if dev.size:
                d = float(dev.max()) / NORMAL_TOLERANCE
                worst = max(worst, d if d == d else np.inf)
        return worst

    def off(a: float, b: float) -> float:
        """How far [a, b] is from straight, in tolerances (> 1: halve it)."""
        (ca, wa), (cb, wb), (cm, wm) = at(a), at(b), at(0.5 * (a + b))
        worst = pixel_error(0.5 * (ca + cb), 0.5 * (wa + wb), cm, wm) / tol
        worst = worst if worst == worst else np.inf
        if worst > 1.0:
            return worst
        return max(worst, normals_off(a, b))

    cuts = {0.0, 1.0}
    motions = [o.motion for o in objects if o.motion is not None]
    if scene.camera_motion is not None:
        motions.append(scene.camera_motion)
    for m in motions:
        cuts.update(float(t) for t in m.times if 0.0 < t < 1.0)
    todo = sorted(cuts)
    # Worst piece first (a heap of (-off, a, b)); pieces at the tolerance or at MIN_PIECE are done.
    heap: list[tuple[float, float, float]] = []
    done = set(todo)

    def push(a: float, b: float) -> None:
        if b - a > MIN_PIECE:
            e = off(a, b)
            if e > 1.0:
                heapq.heappush(heap, (-e, a, b))

    for a, b in zip(todo[:-1], todo[1:]):
        push(a, b)
    while heap and len(done) - 1 < MAX_SEGMENTS:
        _, a, b = heapq.heappop(heap)
        m = 0.5 * (a + b)
        done.add(m)
        push(a, m)
        push(m, b)
    return np.array(sorted(done))


def _homogeneous(p: np.ndarray) -> np.ndarray:
    return np.concatenate([p, np.ones((*p.shape[:-1], 1))], axis=-1)


def _transform(m: np.ndarray, p: np.ndarray) -> np.ndarray:
    """(K,V,4) points ``p`` each transformed by its (K,4,4) matrix ``m``: the sums in numpy's
    einsum order for four terms (even and odd terms first), in a tenth of its time."""
    t = [p[..., j : j + 1] * m[:, None, :, j] for j in range(4)]
    return (t[0] + t[2]) + (t[1] + t[3])


def straddled(scene: Scene, obj: Object, times: np.ndarray) -> np.ndarray:
    """(K+1,V,3) world positions at the boundaries ``times``, moved so that the motion linear in
    clip space between them straddles the true path instead of cutting inside its curves.

    Within a segment the true clip-space path of a vertex bows away from the chord by ``s``
    (its sagitta, measured at the segment's middle). Every boundary is moved by half the mean
    bow of the segments beside it, towards the bow, so the piecewise-linear path lies half
    outside and half inside the true one: its largest distance halves and the covered area
    errors on either side cancel. Straight motion (translation, vertex keyframes between their
    times, a still camera) is left exactly as it is."""
    pos = np.stack([obj.world_vertices(t) for t in times])
    if len(times) < 2:
        return pos
    mids = 0.5 * (times[1:] + times[:-1])
    vp = np.stack([scene.camera_at(t).view_projection for t in times])
    vpm = np.stack([scene.camera_at(t).view_projection for t in mids])
    clip = _transform(vp, _homogeneous(pos))
    mid = _transform(vpm, _homogeneous(np.stack([obj.world_vertices(t) for t in mids])))
    bow = mid - 0.5 * (clip[1:] + clip[:-1])  # (K,V,4): chord middle to the true middle
    if not np.abs(bow).max() > 1e-12 * (1.0 + np.abs(clip).max()):
        return pos
    shift = np.zeros_like(clip)
    shift[:-1] += 0.5 * bow
    shift[1:] += 0.5 * bow
    shift[1:-1] *= 0.5
    moved = _transform(np.linalg.inv(vp), clip + 0.5 * shift)
    return moved[..., :3] / moved[..., 3:4]


def _draw(scene: Scene, obj: Object, k: int, times: np.ndarray) -> MovingDraw:
    pos = straddled(scene, obj, times)
    normals = None
    if obj.shading == "lambert" and not (obj.motion is not None and obj.motion.is_deforming):
        n0 = obj.mesh.vertex_normals()
        rows = []
        for t in times:
            m = obj.transform_at(t)[:3, :3]
            rows.append(n0 @ (m / np.cbrt(np.linalg.det(m))).T)
        normals = np.stack(rows).astype(np.float32)
    return MovingDraw(pos, obj.mesh.faces, obj.rgba, normals, object_id=k, shading=obj.shading)


@register(
    "analytic",
    sweep=[{"gauss": "auto"}, {"gauss": 1}, {"gauss": 2}, {"aa": 1}, {"tolerance": 0.25}],
    applies=lambda scene: True,
)
def analytic(scene: Scene, aa: int = 1, gauss="auto", tolerance: float = 0.01, segments=None) -> Frame:
    """Analytic motion blur: the exact covered time of every sample, visibility over time.

    Options: ``aa`` 1, 2 or 4 samples per pixel along each axis; ``gauss`` points in time per
    visible piece and triangle (1 to 4, or ``"auto"``: 1 to 4, the most of two rules: by the
    piece's length, 1 below 1/32 of the shutter, 2 below 1/4, else 3; and by how far apart a
    lambert triangle's unit vertex normals are, 2 beyond 0.1, 3 beyond 0.5 and 4 beyond 1.0, since a sample
    sweeps the whole triangle within a short piece; a piece is cut where the triangle of a
    surface covering the sample changes, and where a light grazes a lambert surface, the kink
    of ``max(0, n . l)``); ``tolerance`` pixels, the
    chord rule of :func:`segment_times`; ``segments`` an int to cut the shutter into that many
    equal segments instead (plus every keyframe time). Depth, ids and velocity describe the
    surface in front at the scene's reference time. ``stats``: the kernel's (``prims``,
    ``intervals``, ``pieces``, ``splits``, ``ms_*``) plus ``segments``. Memory per thread is
    bounded by :data:`motionblur.analytic.TILE_BUDGET_BYTES`.
    """
    aa = as_int(aa, "aa")
    if aa not in (1, 2, 4):
        raise ValueError(f"aa: must be 1, 2 or 4, got {aa}")
    cam = supersampled(scene.camera, aa)
    everything = list(enumerate(scene.objects))
    if scene.camera_moves:
        moving, still = everything, []
    else:
        moving = [(k, o) for k, o in everything if o.is_moving]
        still = [(k, o) for k, o in everything if not o.is_moving]
    static = static_layer(scene, cam, still, aa) if (still or not moving) else None
    if not moving:
        f = Frame(
            static.rgba.copy(), static.depth.copy(), static.ids.copy(), np.zeros((*static.ids.shape, 2))
        )
        f.stats.update({"segments": 0})
        return f
    if segments is None:
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
    draws = [_draw(scene, o, k, times) for k, o in moving]
    cams = [scene.camera_at(t) for t in times] if scene.camera_moves else scene.camera
    background = None
    if static is not None:
        L = static.layer
        background = (L.rgba, L.depth, L.ids)
    lights = [(li.direction, li.intensity) for li in scene.lights]
    frame = rasterize_motion(
        cams, draws, times, samples=aa, shutter=scene.shutter, lights=lights,
        ambient=scene.ambient, gauss=gauss, reference_time=scene.reference_t, background=background,
    )  # fmt: skip
    frame.stats["segments"] = len(times) - 1
    return frame
