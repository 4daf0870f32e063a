"""Plain numpy + trimesh twins of the geometry kernels, shared by the geometry tests.

The twins evaluate the face classification with the same floating-point operations as the
Rust core (``np.cross`` order, left-to-right dot product), so contour sets compare exactly.
``tests/core/test_geometry_twins.py`` checks the twins themselves on cases worked out by hand.
"""

from __future__ import annotations

import numpy as np
import trimesh

from motionblur import meshes


def raw_normals(v: np.ndarray, f: np.ndarray) -> np.ndarray:
    """(F,3) ``(b - a) x (c - a)``."""
    a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    u, w = b - a, c - a
    return np.stack(
        [
            u[:, 1] * w[:, 2] - u[:, 2] * w[:, 1],
            u[:, 2] * w[:, 0] - u[:, 0] * w[:, 2],
            u[:, 0] * w[:, 1] - u[:, 1] * w[:, 0],
        ],
        axis=1,
    )


def dot3(n: np.ndarray, m) -> np.ndarray:
    """Row-wise ``n . m`` summed left to right, as the core does."""
    m = np.asarray(m, dtype=np.float64)
    if m.ndim == 1:
        return n[:, 0] * m[0] + n[:, 1] * m[1] + n[:, 2] * m[2]
    return n[:, 0] * m[:, 0] + n[:, 1] * m[:, 1] + n[:, 2] * m[:, 2]


def front_faces(v, f, motion) -> np.ndarray:
    return dot3(raw_normals(v, f), motion) >= 0.0


def _orient(f: np.ndarray, face: np.ndarray, p: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Rows (p, q) or (q, p): as the edge runs in ``face``."""
    t = f[face]
    fwd = (
        ((t[:, 0] == p) & (t[:, 1] == q))
        | ((t[:, 1] == p) & (t[:, 2] == q))
        | ((t[:, 2] == p) & (t[:, 0] == q))
    )
    return np.where(fwd[:, None], np.stack([p, q], 1), np.stack([q, p], 1))


def sorted_rows(e: np.ndarray) -> np.ndarray:
    e = np.asarray(e, dtype=np.int64).reshape(-1, 2)
    key = np.sort(e, axis=1)
    return e[np.lexsort((key[:, 1], key[:, 0]))]


def reference_contour(tm: trimesh.Trimesh, motion, camera_position=None) -> np.ndarray:
    """Contour edges of a closed mesh from trimesh's ``face_adjacency``, oriented as in the
    front face, rows sorted by ``(min, max)``; with a camera, the contour-line subset."""
    v, f = np.asarray(tm.vertices), np.asarray(tm.faces)
    front = front_faces(v, f, motion)
    adj = tm.face_adjacency
    edges = tm.face_adjacency_edges
    sel = front[adj[:, 0]] != front[adj[:, 1]]
    if camera_position is not None:
        eye = np.asarray(camera_position, dtype=np.float64)
        vis = dot3(raw_normals(v, f), eye[None] - v[f[:, 0]]) > 0.0
        sel &= vis[adj[:, 0]] | vis[adj[:, 1]]
    adj, edges = adj[sel], edges[sel]
    ff = np.where(front[adj[:, 0]], adj[:, 0], adj[:, 1])
    return sorted_rows(_orient(f, ff, edges[:, 0], edges[:, 1]))


def reference_contour_any(v, f, motion) -> np.ndarray:
    """The documented rule for any mesh (boundary and non-manifold edges included), by numpy
    grouping of half-edges: net front / net back windings."""
    v, f = np.asarray(v, dtype=np.float64), np.asarray(f, dtype=np.int64)
    front = front_faces(v, f, motion)
    he = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
    face = np.tile(np.arange(len(f)), 3)
    keep = he[:, 0] != he[:, 1]
    he, face = he[keep], face[keep]
    key = np.sort(he, axis=1)
    sign = np.where(he[:, 0] < he[:, 1], 1, -1)
    uniq, inv = np.unique(key, axis=0, return_inverse=True)
    inv = inv.reshape(-1)
    net_front = np.bincount(inv, weights=sign * front[face], minlength=len(uniq))
    net_back = np.bincount(inv, weights=sign * ~front[face], minlength=len(uniq))
    is_c = (net_front != 0) | (net_back != 0)
    forward = np.where(net_front != 0, net_front > 0, net_back < 0)
    u = uniq[is_c]
    fw = forward[is_c]
    return np.where(fw[:, None], u, u[:, ::-1])


def signed_volume(v, f, center=None) -> float:
    """Divergence-theorem volume of a closed mesh, ``sum (a - o) . ((b - a) x (c - a)) / 6``
    about ``center`` (default: the mean), in extended precision (x87 long double): the joining
    quads of a huge motion are long slivers whose cross products lose digits in float64."""
    v = np.asarray(v, dtype=np.float64)
    c = v.mean(axis=0) if center is None else np.asarray(center, dtype=np.float64)
    v = v.astype(np.longdouble) - c.astype(np.longdouble)
    return float(np.einsum("ij,ij->i", v[f[:, 0]], raw_normals(v, f)).sum() / 6.0)


def swept_volume(tm: trimesh.Trimesh, m) -> float:
    """Exact volume swept by a convex mesh translated by ``m``: its volume plus ``|m|`` times its
    shadow area on the plane normal to ``m`` (``sum |n_f . u| / 4`` with raw normals)."""
    m = np.asarray(m, dtype=np.float64)
    L = float(np.linalg.norm(m))
    if L == 0:
        return float(tm.volume)
    shadow = np.abs(raw_normals(np.asarray(tm.vertices), np.asarray(tm.faces)) @ (m / L)).sum() / 4.0
    return float(tm.volume + L * shadow)


def hull_volume(*point_sets, center=None) -> float:
    pts = np.vstack(point_sets)
    c = pts.mean(axis=0) if center is None else center
    return float(trimesh.convex.convex_hull(pts - c).volume)


def random_convex(rng: np.random.Generator, n_points: int | None = None) -> trimesh.Trimesh:
    n = int(rng.integers(6, 40)) if n_points is None else n_points
    pts = rng.normal(size=(n, 3)) * rng.uniform(0.2, 3.0, size=3)
    return trimesh.convex.convex_hull(pts)


def concave_mesh() -> trimesh.Trimesh:
    """A closed, consistently wound, clearly non-convex blob (radially bumped icosphere)."""
    v, f = meshes.icosphere(3)
    r = 1.0 + 0.35 * np.sin(5 * v[:, 0]) * np.cos(4 * v[:, 1]) + 0.2 * np.sin(3 * v[:, 2])
    return trimesh.Trimesh(v * r[:, None], f, process=False)


def builtin(make, *args) -> trimesh.Trimesh:
    v, f = make(*args)
    return trimesh.Trimesh(v, f, process=False)
