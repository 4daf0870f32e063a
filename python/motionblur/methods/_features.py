"""What an object does on screen over the shutter: the features the ``auto`` planner's cost and
error model reads (:mod:`motionblur.methods.auto`), and the report measures them the same way to
fit that model (:mod:`motionblur.evaluation.autofit`).

:func:`group_features` of a group of objects (pairs ``(index, Object)``) seen by a scene's
camera (moving or not) returns a dict of floats:

- ``motion_px``: the longest screen path of a test point over the shutter, pixels (the path
  summed over 8 equal steps, so a turn counts its arc); test points are each rigid object's
  bounding-box corners plus up to 64 of its vertices, or up to 64 vertices of a deforming one;
- ``tri_px``: the mean screen area of the group's triangles at the reference time, pixels^2
  (estimated from up to 2,000 faces spread evenly over each mesh);
- ``faces``: triangles in the group;
- ``rotation``: the largest angle the objects turn relative to the camera over the shutter,
  radians (0 for deforming objects);
- ``spread``: how unlike one translation the test points' screen motions are: the spread of
  their displacement vectors from shutter open to close over their mean length plus a pixel
  (0 for a pure translation parallel to the image; turns, motion toward the camera and
  deformation raise it);
- ``concavity``: the concave share of the meshes' bending, 0 for convex meshes: the sum over
  edges of length times the concave dihedral angle over the sum of length times the absolute
  dihedral angle (a torus 0.3-0.5, the bunny scan about 0.4; cached per mesh);
- ``hollowness``: how far the objects' silhouette at the reference time falls short of its convex
  hull: 1 - (pixels covered, from a one-sample raster of the group) / (area of the convex hull
  of its projected vertices), at half the image size; 0 for a convex outline, large for a ring's hole or an ant's legs.
  The motion volume's coverage model takes the hull, so this is what it over-covers;
- ``coverage_px``: the screen area the group sweeps, pixels (the union of its test points'
  bounding boxes over the shutter, clipped to the image);
- ``deforming``, ``camera_moves``: 1.0 or 0.0.

Cost: a few hundred points projected at 9 times, plus one pass over each mesh's edges the first
time it is seen; under a millisecond for the report's scenes after the first frame.
"""

from __future__ import annotations

import numpy as np

from ..scene import Object, Scene

__all__ = ["group_features", "FEATURES", "concavity", "screen_points"]

#: The names :func:`group_features` returns, in a fixed order.
FEATURES = (
    "motion_px", "tri_px", "faces", "rotation", "spread", "concavity", "hollowness", "coverage_px", "deforming",
    "camera_moves",
)  # fmt: skip
_STEPS = 8
_POINTS = 64
_FACES = 2000
_CACHE_SIZE = 64
_concavity_cache: dict[int, tuple[object, float]] = {}  # id(mesh) -> (mesh, value): the mesh kept alive


def concavity(mesh) -> float:
    """The concave share of ``mesh``'s bending in [0, 1] (see the module docs); cached per mesh."""
    hit = _concavity_cache.get(id(mesh))
    if hit is not None and hit[0] is mesh:
        return hit[1]
    v, f = np.asarray(mesh.vertices, np.float64), np.asarray(mesh.faces, np.int64)
    n = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
    e = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
    face = np.tile(np.arange(len(f)), 3)
    key2 = np.sort(e, axis=1)
    order = np.lexsort((key2[:, 1], key2[:, 0]))
    ks, fs, es = key2[order], face[order], e[order]
    pair = (ks[1:] == ks[:-1]).all(axis=1)  # manifold edges: two consecutive equal keys
    i = np.nonzero(pair)[0]
    fa, fb = fs[i], fs[i + 1]
    a, b = v[es[i, 0]], v[es[i, 1]]
    length = np.linalg.norm(b - a, axis=1)
    cosang = np.clip(np.einsum("ij,ij->i", n[fa], n[fb]), -1.0, 1.0)
    ang = np.arccos(cosang)
    # concave where face b's far vertex lies above face a's plane
    far = v[f[fb]].sum(axis=1) / 3.0
    concave = np.einsum("ij,ij->i", far - a, n[fa]) > 0
    total = float((length * ang).sum())
    out = float((length * ang * concave).sum() / total) if total > 0 else 0.0
    if len(_concavity_cache) >= _CACHE_SIZE:
        _concavity_cache.pop(next(iter(_concavity_cache)))
    _concavity_cache[id(mesh)] = (mesh, out)
    return out


def _object_points(obj: Object) -> tuple[np.ndarray | None, np.ndarray]:
    """(object-space test points of a rigid object or None, vertex indices of up to 64 vertices)."""
    v = obj.mesh.vertices
    idx = np.linspace(0, len(v) - 1, min(len(v), _POINTS)).astype(np.int64)
    if obj.motion is not None and obj.motion.is_deforming:
        return None, idx
    a, b = v.min(axis=0), v.max(axis=0)
    corners = np.array([[x, y, z] for x in (a[0], b[0]) for y in (a[1], b[1]) for z in (a[2], b[2])])
    return np.concatenate([corners, v[idx]]), idx


def _cameras(scene: Scene, times) -> list:
    """The camera at each of ``times`` (one object when the camera does not move)."""
    if not scene.camera_moves:
        return [scene.camera] * len(times)
    return [scene.camera_at(float(t)) for t in times]


def screen_points(scene: Scene, objects, times, cameras=None) -> np.ndarray:
    """(T,P,3) screen x, y (pixels, +y down) and clip w of the test points of ``objects`` (pairs
    ``(index, Object)``) at ``times`` (T,) (see the module docs)."""
    out = []
    prepared = [(o, *_object_points(o)) for _, o in objects]
    for t, cam in zip(times, cameras or _cameras(scene, times)):
        vp = cam.view_projection
        world = []
        for o, pts, idx in prepared:
            if pts is None:
                world.append(o.world_vertices(float(t))[idx])
            else:
                m = o.transform_at(float(t))
                world.append(pts @ m[:3, :3].T + m[:3, 3])
        p = np.concatenate(world)
        clip = p @ vp[:3, :3].T + vp[:3, 3]
        w = p @ vp[3, :3] + vp[3, 3]
        ws = np.where(w > 1e-6, w, 1e-6)
        x = (clip[:, 0] / ws + 1.0) * 0.5 * cam.width
        y = (1.0 - clip[:, 1] / ws) * 0.5 * cam.height
        out.append(np.stack([x, y, w], -1))
    return np.stack(out)


def _rotation(obj: Object, times, cameras) -> float:
    if (obj.motion is None or obj.motion.is_deforming) and cameras[0] is cameras[-1]:
        return 0.0
    rel = []
    for t, cam in zip(times, cameras):
        r = cam.view[:3, :3] @ obj.transform_at(float(t))[:3, :3]
        rel.append(r / np.cbrt(np.linalg.det(r)))
    c = (np.trace(rel[0].T @ rel[-1]) - 1.0) / 2.0
    direct = float(np.arccos(np.clip(c, -1.0, 1.0)))
    steps = sum(
        float(np.arccos(np.clip((np.trace(a.T @ b) - 1.0) / 2.0, -1.0, 1.0))) for a, b in zip(rel, rel[1:])
    )
    return max(direct, steps)


def _tri_px(scene: Scene, objects) -> float:
    cam = scene.camera_at(scene.reference_t)
    vp = cam.view_projection
    areas = []
    for _, o in objects:
        f = o.mesh.faces
        sel = f[np.linspace(0, len(f) - 1, min(len(f), _FACES)).astype(np.int64)]
        v = o.world_vertices(scene.reference_t)
        used = np.unique(sel)
        p = v[used]
        w = np.maximum(p @ vp[3, :3] + vp[3, 3], 1e-6)
        xy = (p @ vp[:2, :3].T + vp[:2, 3]) / w[:, None] * 0.5 * np.array([cam.width, cam.height])
        remap = np.searchsorted(used, sel)
        a, b, c = xy[remap[:, 0]], xy[remap[:, 1]], xy[remap[:, 2]]
        areas.append(
            0.5
            * np.abs((b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0]))
        )
    return float(np.concatenate(areas).mean()) if areas else 0.0


def _hull_area(xy: np.ndarray) -> float:
    """Area of the convex hull of the points ``xy`` (N,2) (Andrew's monotone chain)."""
    pts = np.unique(np.round(xy, 6), axis=0)
    if len(pts) < 3:
        return 0.0

    def half(points):
        chain: list = []
        for p in points:
            while len(chain) >= 2:
                (ax, ay), (bx, by) = chain[-2], chain[-1]
                if (bx - ax) * (p[1] - ay) - (by - ay) * (p[0] - ax) > 0:
                    break
                chain.pop()
            chain.append((p[0], p[1]))
        return chain

    lower, upper = half(pts), half(pts[::-1])
    hull = np.array(lower[:-1] + upper[:-1])
    x, y = hull[:, 0], hull[:, 1]
    return float(0.5 * abs(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1))))


def _hollowness(scene: Scene, objects) -> float:
    from ..raster import Draw, rasterize

    t = scene.reference_t
    full = scene.camera_at(t) if scene.camera_moves else scene.camera
    cam = full.resized(max(8, full.width // 2), max(6, full.height // 2))  # half size: a quarter of the cost
    draws, pts = [], []
    vp = cam.view_projection
    for _, o in objects:
        v = o.world_vertices(t)
        draws.append(Draw(v, o.mesh.faces, (1.0, 1.0, 1.0, 1.0)))
        sub = v[np.linspace(0, len(v) - 1, min(len(v), 4 * _FACES)).astype(np.int64)]
        w = sub @ vp[3, :3] + vp[3, 3]
        sub = sub[w > cam.znear * 0.5]
        w = w[w > cam.znear * 0.5]
        xy = (sub @ vp[:2, :3].T + vp[:2, 3]) / w[:, None]
        pts.append(np.column_stack([(xy[:, 0] + 1) * 0.5 * cam.width, (1 - xy[:, 1]) * 0.5 * cam.height]))
    hull = _hull_area(np.concatenate(pts)) if pts else 0.0
    if hull < 1.0:
        return 0.0
    area = float((rasterize(cam, draws).rgba[..., 3] > 0.5).sum())
    return float(np.clip(1.0 - area / hull, 0.0, 1.0))


def group_features(scene: Scene, objects) -> dict[str, float]:
    """The features of the group ``objects`` (pairs ``(index, Object)``) in ``scene`` (see the
    module docs): a dict with every name of :data:`FEATURES`."""
    objects = list(objects)
    times = np.linspace(0.0, 1.0, _STEPS + 1)
    cams = _cameras(scene, times)
    sp = screen_points(scene, objects, times, cams)  # (T,P,3)
    xy = sp[..., :2]
    path = np.linalg.norm(np.diff(xy, axis=0), axis=-1).sum(axis=0)
    disp = xy[-1] - xy[0]
    mean = disp.mean(axis=0)
    spread = float(
        np.sqrt(((disp - mean) ** 2).sum(axis=1).mean()) / (np.linalg.norm(disp, axis=1).mean() + 1.0)
    )
    cam = scene.camera
    lo = np.clip(xy.reshape(-1, 2).min(axis=0), 0, [cam.width, cam.height])
    hi = np.clip(xy.reshape(-1, 2).max(axis=0), 0, [cam.width, cam.height])
    return {
        "motion_px": float(path.max()) if path.size else 0.0,
        "tri_px": _tri_px(scene, objects),
        "faces": float(sum(len(o.mesh.faces) for _, o in objects)),
        "rotation": max((_rotation(o, times, cams) for _, o in objects), default=0.0),
        "spread": spread,
        "concavity": max((concavity(o.mesh) for _, o in objects), default=0.0),
        "hollowness": _hollowness(scene, objects),
        "coverage_px": float(np.prod(np.maximum(hi - lo, 0.0))),
        "deforming": float(any(o.motion is not None and o.motion.is_deforming for _, o in objects)),
        "camera_moves": float(scene.camera_moves),
    }


def screen_box(scene: Scene, objects) -> tuple[float, float, float, float]:
    """``(x0, y0, x1, y1)`` pixels: the box the test points of ``objects`` sweep over the shutter."""
    xy = screen_points(scene, list(objects), np.linspace(0.0, 1.0, _STEPS + 1))[..., :2].reshape(-1, 2)
    lo, hi = xy.min(axis=0), xy.max(axis=0)
    return float(lo[0]), float(lo[1]), float(hi[0]), float(hi[1])
