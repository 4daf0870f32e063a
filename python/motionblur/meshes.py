"""Built-in procedural meshes for demos, tests and benchmarks.

Every function returns ``(vertices, faces)``: vertices (V,3) float64 in scene units, faces (F,3)
int64, counter-clockwise seen from outside (outward normals).
"""

from __future__ import annotations

import numpy as np

__all__ = ["icosphere", "box", "torus", "cylinder", "uv_sphere"]


def icosphere(subdivisions: int = 2, radius: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """Geodesic sphere: 20 * 4**subdivisions faces (5: 20k, 6: 82k, 7: 328k, 8: 1.3M)."""
    if subdivisions < 0 or subdivisions > 9:
        raise ValueError(f"subdivisions: must be in 0..9, got {subdivisions}")
    t = (1.0 + 5.0**0.5) / 2.0
    v = np.array(
        [[-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0],
         [0, -1, t], [0, 1, t], [0, -1, -t], [0, 1, -t],
         [t, 0, -1], [t, 0, 1], [-t, 0, -1], [-t, 0, 1]], dtype=np.float64)  # fmt: skip
    f = np.array(
        [[0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11],
         [1, 5, 9], [5, 11, 4], [11, 10, 2], [10, 7, 6], [7, 1, 8],
         [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8], [3, 8, 9],
         [4, 9, 5], [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1]], dtype=np.int64)  # fmt: skip
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    for _ in range(subdivisions):
        # Midpoint of every edge, shared between the two faces that hold it.
        edges = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
        key = np.sort(edges, axis=1)
        uniq, inverse = np.unique(key, axis=0, return_inverse=True)
        inverse = inverse.reshape(-1)
        mid = v[uniq[:, 0]] + v[uniq[:, 1]]
        mid /= np.linalg.norm(mid, axis=1, keepdims=True)
        base = len(v)
        v = np.concatenate([v, mid])
        nf = len(f)
        a = base + inverse[:nf]
        b = base + inverse[nf : 2 * nf]
        c = base + inverse[2 * nf :]
        f = np.concatenate(
            [
                np.stack([f[:, 0], a, c], 1),
                np.stack([f[:, 1], b, a], 1),
                np.stack([f[:, 2], c, b], 1),
                np.stack([a, b, c], 1),
            ]
        )
    return v * radius, f


def box(extents=(1.0, 1.0, 1.0)) -> tuple[np.ndarray, np.ndarray]:
    """Axis-aligned box centred at the origin: 8 vertices, 12 faces."""
    e = np.asarray(extents, dtype=np.float64) / 2.0
    v = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], dtype=np.float64) * e
    f = np.array(
        [[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5],  # -x, +x
         [0, 4, 5], [0, 5, 1], [2, 3, 7], [2, 7, 6],  # -y, +y
         [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]],  # -z, +z
        dtype=np.int64)  # fmt: skip
    return v, f


def torus(major: float = 1.0, minor: float = 0.3, n_major: int = 32, n_minor: int = 16):
    """Torus around +Z: n_major * n_minor * 2 faces."""
    u = np.linspace(0, 2 * np.pi, n_major, endpoint=False)
    w = np.linspace(0, 2 * np.pi, n_minor, endpoint=False)
    uu, ww = np.meshgrid(u, w, indexing="ij")
    r = major + minor * np.cos(ww)
    v = np.stack([r * np.cos(uu), r * np.sin(uu), minor * np.sin(ww)], -1).reshape(-1, 3)
    i, j = np.meshgrid(np.arange(n_major), np.arange(n_minor), indexing="ij")
    a = i * n_minor + j
    b = ((i + 1) % n_major) * n_minor + j
    c = ((i + 1) % n_major) * n_minor + (j + 1) % n_minor
    d = i * n_minor + (j + 1) % n_minor
    f = np.concatenate([np.stack([a, b, c], -1).reshape(-1, 3), np.stack([a, c, d], -1).reshape(-1, 3)])
    return v, f.astype(np.int64)


def cylinder(radius: float = 0.5, height: float = 2.0, sections: int = 32, rings: int = 1):
    """Closed cylinder along +Z from z=0 to z=height, with `rings` bands (for bending)."""
    ang = np.linspace(0, 2 * np.pi, sections, endpoint=False)
    zs = np.linspace(0.0, height, rings + 1)
    ring = np.stack([radius * np.cos(ang), radius * np.sin(ang)], -1)
    side = np.concatenate([np.column_stack([ring, np.full(sections, z)]) for z in zs])
    v = np.concatenate([side, [[0, 0, 0], [0, 0, height]]])
    bottom, top = len(side), len(side) + 1
    faces = []
    for r in range(rings):
        for s in range(sections):
            a = r * sections + s
            b = r * sections + (s + 1) % sections
            c = b + sections
            d = a + sections
            faces += [[a, b, c], [a, c, d]]
    for s in range(sections):
        faces.append([bottom, (s + 1) % sections, s])
        base = rings * sections
        faces.append([top, base + s, base + (s + 1) % sections])
    return v.astype(np.float64), np.array(faces, dtype=np.int64)


def uv_sphere(n_lat: int = 16, n_lon: int = 32, radius: float = 1.0):
    """Latitude-longitude sphere with poles on +-Z (has thin triangles near the poles)."""
    lat = np.linspace(0, np.pi, n_lat + 1)[1:-1]
    lon = np.linspace(0, 2 * np.pi, n_lon, endpoint=False)
    la, lo = np.meshgrid(lat, lon, indexing="ij")
    ring = np.stack([np.sin(la) * np.cos(lo), np.sin(la) * np.sin(lo), np.cos(la)], -1).reshape(-1, 3)
    v = np.concatenate([[[0, 0, 1]], ring, [[0, 0, -1]]]) * radius
    south = len(v) - 1
    faces = []
    for j in range(n_lon):
        faces.append([0, 1 + j, 1 + (j + 1) % n_lon])
    for i in range(n_lat - 2):
        for j in range(n_lon):
            a = 1 + i * n_lon + j
            b = 1 + i * n_lon + (j + 1) % n_lon
            c = b + n_lon
            d = a + n_lon
            faces += [[a, d, c], [a, c, b]]
    base = 1 + (n_lat - 2) * n_lon
    for j in range(n_lon):
        faces.append([south, base + (j + 1) % n_lon, base + j])
    return v, np.array(faces, dtype=np.int64)
