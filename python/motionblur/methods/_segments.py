"""The analytic method's segment rule: where the shutter is cut so that every vertex moves
linearly in clip space within a segment (shared by ``analytic`` and ``auto``, which predicts the
analytic frame's cost from its segment count)."""

from __future__ import annotations

import numpy as np

from .._validate import as_float
from ..geometry import Mesh
from ..raster import Camera
from ..scene import Object, Scene

__all__ = ["segment_times", "MAX_SEGMENTS", "MIN_PIECE", "NORMAL_TOLERANCE"]

#: Most segments the automatic rule makes.
MAX_SEGMENTS = 256
#: Shortest piece the rule halves: a test point that crosses the camera's plane is never
#: "straight" around the crossing, and halving towards it would end in equal boundaries.
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
    puts it (points behind the camera count as off). Test points are the corners of each rigid
    object's bounding box (the farthest points from any rotation axis) and up to 256 vertices
    of each deforming one. A deforming lambert object's piece is also halved while a test
    vertex's unit normal at the middle lies more than :data:`NORMAL_TOLERANCE` from the
    direction of the mean of its normals at the ends. At most :data:`MAX_SEGMENTS` segments, none
    halved below :data:`MIN_PIECE` of the shutter."""
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

    def pixels(xyz, wc):
        with np.errstate(divide="ignore", invalid="ignore"):
            x = (xyz[:, 0] / wc + 1.0) * 0.5 * w
            y = (1.0 - xyz[:, 1] / wc) * 0.5 * h
        return x, y, wc > 1e-9

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

    def normals_straight(a: float, b: float) -> bool:
        for na, nb, nm in zip(normals(a), normals(b), normals(0.5 * (a + b))):
            mean = na + nb
            length = np.linalg.norm(mean, axis=1, keepdims=True)
            ok = (length[:, 0] > 1e-12) & (np.linalg.norm(nm, axis=1) > 0)
            mean = mean / np.where(length > 1e-12, length, 1.0)
            if not (np.linalg.norm(nm[ok] - mean[ok], axis=1) <= NORMAL_TOLERANCE).all():
                return False
        return True

    def straight(a: float, b: float) -> bool:
        (ca, wa), (cb, wb), (cm, wm) = at(a), at(b), at(0.5 * (a + b))
        xl, yl, okl = pixels(0.5 * (ca + cb), 0.5 * (wa + wb))
        xm, ym, okm = pixels(cm, wm)
        if not (okl == okm).all():
            return False
        ok = okl & okm
        if not (np.hypot(xl[ok] - xm[ok], yl[ok] - ym[ok]) <= tol).all():
            return False
        return normals_straight(a, b)

    cuts = {0.0, 1.0}
    motions = [o.motion for o in objects if o.motion is not None]
    if scene.camera_motion is not None:
        motions.append(scene.camera_motion)
    for m in motions:
        cuts.update(float(t) for t in m.times if 0.0 < t < 1.0)
    todo = sorted(cuts)
    out = [todo[0]]
    stack = list(zip(todo[:-1], todo[1:]))[::-1]
    while stack:
        a, b = stack.pop()
        if b - a > MIN_PIECE and len(out) - 1 + len(stack) + 1 < MAX_SEGMENTS and not straight(a, b):
            m = 0.5 * (a + b)
            stack.append((m, b))
            stack.append((a, m))
            continue
        out.append(b)
    return np.array(out)
