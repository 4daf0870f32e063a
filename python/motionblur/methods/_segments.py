"""The analytic method's segment rule: where the shutter is cut so that every vertex moves
linearly in clip space within a segment (shared by ``analytic`` and ``auto``, which predicts the
analytic frame's cost from its segment count)."""

from __future__ import annotations

import heapq

import numpy as np

from .._validate import as_float
from ..geometry import Mesh
from ..raster import Camera
from ..scene import Object, Scene

__all__ = ["segment_times", "MAX_SEGMENTS", "MIN_PIECE", "NORMAL_TOLERANCE"]

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
    vertex's unit normal at the middle lies more than `NORMAL_TOLERANCE` from the
    direction of the mean of its normals at the ends. At most `MAX_SEGMENTS` segments, none
    halved below `MIN_PIECE` of the shutter: the piece furthest over its tolerance is
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
