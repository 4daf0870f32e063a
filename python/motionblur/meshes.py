"""Built-in procedural meshes for demos, tests and benchmarks.

Every function returns ``(vertices, faces)``: vertices (V,3) float64 in scene units, faces (F,3)
int64, counter-clockwise seen from outside (outward normals). Sizes are finite numbers > 0 (the
result within the coordinate range, ``MAX_COORD``) and counts integers in the stated ranges
(at most ``MAX_COUNT`` sections, rings or times); otherwise ValueError / TypeError naming the
argument.
"""

from __future__ import annotations

import numpy as np

from ._validate import MAX_COORD, as_array, as_float, as_int

#: Largest count of sections, rings, times or blades of a procedural mesh.
MAX_COUNT = 1 << 14


def _size(value, name: str) -> float:
    v = as_float(value, name)
    if not 0.0 < v <= MAX_COORD / 4:
        raise ValueError(f"{name}: must be in (0, MAX_COORD / 4], got {v:g}")
    return v


def _count(value, name: str, minimum: int) -> int:
    return as_int(value, name, minimum=minimum, maximum=MAX_COUNT)


__all__ = ["icosphere", "box", "torus", "cylinder", "uv_sphere"]
__all__ += ["bending_arm", "spinning_propeller"]


def icosphere(subdivisions: int = 2, radius: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """Geodesic sphere: 20 * 4**subdivisions faces (5: 20k, 6: 82k, 7: 328k, 8: 1.3M)."""
    subdivisions = as_int(subdivisions, "subdivisions", minimum=0, maximum=9)
    radius = _size(radius, "radius")
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
    if np.ndim(extents) == 0:
        extents = (extents,) * 3
    e = as_array(extents, "extents", np.float64, (3,))
    for x in e:
        _size(float(x), "extents")
    e = e / 2.0
    v = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], dtype=np.float64) * e
    f = np.array(
        [[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5],  # -x, +x
         [0, 4, 5], [0, 5, 1], [2, 3, 7], [2, 7, 6],  # -y, +y
         [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]],  # -z, +z
        dtype=np.int64)  # fmt: skip
    return v, f


def torus(major: float = 1.0, minor: float = 0.3, n_major: int = 32, n_minor: int = 16):
    """Torus around +Z: n_major * n_minor * 2 faces."""
    major, minor = _size(major, "major"), _size(minor, "minor")
    n_major, n_minor = _count(n_major, "n_major", 3), _count(n_minor, "n_minor", 3)
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
    radius, height = _size(radius, "radius"), _size(height, "height")
    sections, rings = _count(sections, "sections", 3), _count(rings, "rings", 1)
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
    n_lat, n_lon, radius = _count(n_lat, "n_lat", 2), _count(n_lon, "n_lon", 3), _size(radius, "radius")
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


# --- deforming meshes (blur shells): per-time positions (K,V,3) and faces (F,3)


def _shutter_times(times) -> np.ndarray:
    if isinstance(times, (int, np.integer)) and not isinstance(times, bool):
        return np.linspace(0.0, 1.0, _count(times, "times", 2))
    if np.ndim(times) == 0:
        raise TypeError(f"times: expected an int count or a (K,) finite array, got {type(times).__name__}")
    t = as_array(times, "times", np.float64, (None,))
    if len(t) > MAX_COUNT or np.abs(t).max() > MAX_COORD:
        raise ValueError(f"times: at most {MAX_COUNT} times within +-MAX_COORD")
    return t


def _rot(axis: int, angle: np.ndarray) -> np.ndarray:
    """(K,3,3) rotations about coordinate axis ``axis`` by ``angle`` (K,) radians."""
    c, s = np.cos(angle), np.sin(angle)
    i, j = [(1, 2), (2, 0), (0, 1)][axis]
    r = np.zeros((len(angle), 3, 3))
    r[:, axis, axis] = 1.0
    r[:, i, i], r[:, i, j], r[:, j, i], r[:, j, j] = c, -s, s, c
    return r


def bending_arm(
    times=9,
    radius: float = 0.25,
    length: float = 2.0,
    angle: float = np.pi / 2,
    sections: int = 24,
    rings: int = 24,
) -> tuple[np.ndarray, np.ndarray]:
    """A skinned cylinder (an arm along +Z from z=0 to ``length``) whose upper half bends about
    the elbow at z = length/2 around +X by ``angle * t`` radians (towards -Y).

    Two bones with linear blend skinning: weights go smoothly from the upper bone to the lower
    one over one radius either side of the elbow, so the mesh deforms (not a rigid motion).
    ``times``: an int K (K times evenly over [0, 1]) or (K,) times in shutter units.
    Returns ``(positions, faces)``: (K,V,3) float64 world positions and (F,3) int64 faces
    (closed, counter-clockwise outward; ``sections * rings * 2 + 2 * sections`` faces).
    """
    t = _shutter_times(times)
    angle = as_float(angle, "angle")
    v, f = cylinder(radius=radius, height=length, sections=sections, rings=rings)
    elbow = np.array([0.0, 0.0, length / 2.0])
    x = np.clip((v[:, 2] - (elbow[2] - radius)) / (2.0 * radius), 0.0, 1.0)
    w = (x * x * (3.0 - 2.0 * x))[None, :, None]
    rot = _rot(0, angle * t)
    bent = np.einsum("kij,vj->kvi", rot, v - elbow) + elbow
    return (1.0 - w) * v[None] + w * bent, f


def spinning_propeller(
    times=9,
    blades: int = 3,
    radius: float = 1.0,
    turns: float = 0.25,
    chord: float = 0.22,
    pitch: float = 0.35,
) -> tuple[np.ndarray, np.ndarray]:
    """A propeller in the XY plane spinning about +Z by ``turns`` revolutions over [0, 1]: a
    hub box and ``blades`` flat boxes (``radius`` long, ``chord`` wide, pitched by ``pitch``
    radians about their long axis). Returns ``(positions, faces)``: (K,V,3) float64 and (F,3)
    int64 (12 faces per box). ``times``: an int K or (K,) times in shutter units.
    """
    t = _shutter_times(times)
    blades = _count(blades, "blades", 1)
    radius, chord = _size(radius, "radius"), _size(chord, "chord")
    turns, pitch = as_float(turns, "turns"), as_float(pitch, "pitch")
    verts, faces = [], []
    hv, hf = box((0.2 * radius, 0.2 * radius, 0.12 * radius))
    verts.append(hv)
    faces.append(hf)
    for b in range(blades):
        bv, bf = box((radius, chord, 0.03 * radius))
        bv = bv @ _rot(0, np.array([pitch]))[0].T + [radius / 2.0, 0.0, 0.0]
        bv = bv @ _rot(2, np.array([2.0 * np.pi * b / blades]))[0].T
        faces.append(bf + sum(len(x) for x in verts))
        verts.append(bv)
    v = np.concatenate(verts)
    f = np.concatenate(faces)
    rot = _rot(2, 2.0 * np.pi * turns * t)
    return np.einsum("kij,vj->kvi", rot, v), f


from ._namespace import tidy  # noqa: E402  (dir() lists the API only; see motionblur._namespace)

tidy(__name__)
