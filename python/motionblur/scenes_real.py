"""Scenes built from real scanned and modelled meshes, and from procedural concave ones.

``REAL_SCENES[name](width=..., height=...) -> Scene``, the same signature as
`motionblur.SCENES`; the speed-against-error report runs both sets. Every scene is one
mesh over a static floor, lambert-lit by one directional light (ambient 0, so that Mitsuba sees
the same light; Mitsuba also draws the mover's shadow on the floor, which the rasterizer does
not: the report's second reference, each method's own limit, leaves that difference out).

Meshes (each normalised to a largest extent of `SIZE` scene units, its base on the floor):

- ``bunny``: the Stanford bunny scan (Stanford 3D Scanning Repository; the 99,785-face file
  that pymeshfix 0.18's wheel carries, with the scan's holes) decimated to `BUNNY_FACES`
  faces (5,998) by quadric decimation (fast-simplification 0.2), shipped with the package as
  ``motionblur/data/bunny.ply``;
- ``ant``: the modelled ant of the PLY format's examples (912 faces, thin legs: the concave
  case), as pyvista 0.49 ships it (``pyvista/examples/ant.ply``), shipped with the package as
  ``motionblur/data/ant.ply``. ``motionblur/data/README.md`` states both files' sources and
  terms; they are read with trimesh (the ``meshes`` extra);
- ``torus`` (a ring seen at an angle: the hole shows) and ``knot`` (a (2,3) torus knot tube),
  procedural.

Motions, each over the whole shutter: ``translate`` (across the view), ``turn`` (a 100 degree
turn about the vertical while moving across) and ``toward`` (toward the camera, growing on
screen); and one deforming case, ``knot_twist`` (vertex keyframes twisting the knot about the
vertical by up to 70 degrees at its top). Names are ``<mesh>_<motion>``.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import cache
from pathlib import Path

import numpy as np

from . import meshes
from ._optional import require
from .raster import Camera, look_at
from .scene import DirectionalLight, Motion, Object, Scene, rotate, translate

__all__ = ["REAL_SCENES", "real_mesh", "shipped_mesh", "torus_knot", "MESHES", "MOTIONS"]

#: Scenes by name: functions ``(width=..., height=...) -> Scene``.
REAL_SCENES: dict[str, Callable[..., Scene]] = {}
#: Largest extent of every mesh, scene units.
SIZE = 0.8
#: Faces the bunny scan was decimated to (from 99,785; the decimation gave 5,998) before it was
#: shipped: the analytic method's time grows with the triangles it bins, and the report must
#: stay within its time budget.
BUNNY_FACES = 6000
#: Top of the static floor (scene units).
FLOOR_Y = -0.6
MESHES = ("bunny", "ant", "torus", "knot")
MOTIONS = ("translate", "turn", "toward")
_COLORS = {
    "bunny": (0.85, 0.62, 0.42),
    "ant": (0.75, 0.2, 0.15),
    "torus": (0.25, 0.7, 0.35),
    "knot": (0.3, 0.45, 0.9),
}


def shipped_mesh(name: str) -> tuple[np.ndarray, np.ndarray]:
    """``(vertices (V,3) float64, faces (F,3) int64)`` of the mesh file ``motionblur/data/<name>.ply``
    shipped with the package (``"bunny"`` or ``"ant"``), as stored (not normalised), read with
    trimesh (vertex order kept, nothing merged)."""
    if name not in ("bunny", "ant"):
        raise ValueError(f"name: unknown shipped mesh {name!r}; expected 'bunny' or 'ant'")
    trimesh = require("trimesh", "the real meshes of the report")
    mesh = trimesh.load(str(Path(__file__).parent / "data" / f"{name}.ply"), process=False, force="mesh")
    return np.asarray(mesh.vertices, np.float64), np.asarray(mesh.faces, np.int64)


def torus_knot(
    p: int = 2, q: int = 3, radius: float = 1.0, tube: float = 0.18, n: int = 200, sections: int = 12
):
    """A (p,q) torus knot tube: ``n * sections * 2`` faces, counter-clockwise from outside.
    ``radius``: the torus's major radius (the knot's curve has minor radius ``0.4 * radius``);
    ``tube``: the tube's radius. Returns ``(vertices (V,3) float64, faces (F,3) int64)``."""
    t = np.linspace(0.0, 2.0 * np.pi, n, endpoint=False)

    def curve(t):
        r = radius * (1.0 + 0.4 * np.cos(q * t))
        return np.stack([r * np.cos(p * t), r * np.sin(p * t), 0.4 * radius * np.sin(q * t)], -1)

    c = curve(t)
    tan = curve(t + 1e-4) - curve(t - 1e-4)
    tan /= np.linalg.norm(tan, axis=1, keepdims=True)
    nrm = np.cross(tan, [0.0, 0.0, 1.0])
    nrm /= np.linalg.norm(nrm, axis=1, keepdims=True)
    bin_ = np.cross(tan, nrm)
    a = np.linspace(0.0, 2.0 * np.pi, sections, endpoint=False)
    ring = np.cos(a)[None, :, None] * nrm[:, None] + np.sin(a)[None, :, None] * bin_[:, None]
    v = (c[:, None] + tube * ring).reshape(-1, 3)
    i, j = np.meshgrid(np.arange(n), np.arange(sections), indexing="ij")
    a0 = i * sections + j
    b0 = ((i + 1) % n) * sections + j
    c0 = ((i + 1) % n) * sections + (j + 1) % sections
    d0 = i * sections + (j + 1) % sections
    f = np.concatenate([np.stack([a0, c0, b0], -1).reshape(-1, 3), np.stack([a0, d0, c0], -1).reshape(-1, 3)])
    return v, f.astype(np.int64)


def _normalised(v: np.ndarray, f: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Scaled to a largest extent of SIZE, centred in x and z, its lowest point at y = 0."""
    lo, hi = v.min(0), v.max(0)
    v = (v - [(lo[0] + hi[0]) / 2, lo[1], (lo[2] + hi[2]) / 2]) * (SIZE / (hi - lo).max())
    return np.ascontiguousarray(v), np.ascontiguousarray(f)


@cache
def real_mesh(name: str) -> tuple[np.ndarray, np.ndarray]:
    """``(vertices (V,3) float64, faces (F,3) int64)`` of mesh ``name`` (`MESHES`), in scene
    units, normalised (largest extent `SIZE`, base at y = 0), read-only arrays."""
    if name == "bunny":
        v, f = shipped_mesh("bunny")  # decimated to BUNNY_FACES already
        v = (
            v
            @ (rotate(np.radians(-90.0), (1.0, 0.0, 0.0)) @ rotate(np.radians(-60.0), (0.0, 0.0, 1.0)))[
                :3, :3
            ].T
        )  # z-up scan
    elif name == "ant":
        v, f = shipped_mesh("ant")
        v = v @ rotate(np.radians(90.0), (0.0, 1.0, 0.0))[:3, :3].T  # its length along x (the file's z)
    elif name == "torus":
        v, f = meshes.torus(1.0, 0.38, 48, 16)
        r = rotate(np.radians(20.0), (0.0, 1.0, 0.0))[:3, :3]  # standing, the ring's hole facing the camera
        v = v @ r.T
    elif name == "knot":
        v, f = torus_knot(n=160, sections=10)
        v = v @ rotate(np.radians(70.0), (1.0, 0.0, 0.0))[:3, :3].T
    else:
        raise ValueError(f"name: unknown mesh {name!r}; expected one of {', '.join(MESHES)}")
    v, f = _normalised(v, f)
    v.flags.writeable = False
    f.flags.writeable = False
    return v, f


def _camera(width: int, height: int) -> Camera:
    return Camera(look_at((0.0, 0.9, 3.0), (0.0, -0.25, 0.0)), 0.7, width, height, znear=0.5, zfar=30.0)


def _floor() -> Object:
    v, f = meshes.box((8.0, 0.1, 6.0))
    return Object(
        (v + (0.0, FLOOR_Y - 0.05, -1.5), f), color=(0.3, 0.3, 0.32), shading="lambert", name="floor"
    )


def _motion(kind: str) -> Motion:
    base = (0.0, FLOOR_Y + 0.002, 0.0)
    if kind == "translate":
        return Motion.linear(translate((-0.75, base[1], 0.0)), translate((0.45, base[1], 0.0)))
    if kind == "turn":  # 100 degrees about the vertical through the mesh, while moving across
        ts = np.linspace(0.0, 1.0, 5)
        mats = [
            translate((-0.5 + 0.8 * t, base[1], 0.0)) @ rotate(np.radians(100.0) * t, (0, 1, 0)) for t in ts
        ]
        return Motion(ts, np.stack(mats))
    if kind == "toward":  # from 1.6 units behind the origin to 0.8 in front of it, drifting right
        return Motion.linear(translate((-0.3, base[1], -1.6)), translate((0.2, base[1], 0.8)))
    raise ValueError(f"kind: unknown motion {kind!r}; expected one of {', '.join(MOTIONS)}")


def _scene(mesh_name: str, kind: str, width: int, height: int) -> Scene:
    obj = Object(
        real_mesh(mesh_name),
        color=_COLORS[mesh_name],
        shading="lambert",
        motion=_motion(kind),
        name=mesh_name,
    )
    light = DirectionalLight((-0.35, -1.0, -0.55), 1.0)
    return Scene([obj, _floor()], _camera(width, height), lights=[light], ambient=0.0, shutter="box")


def _register(mesh_name: str, kind: str) -> None:
    def build(width: int = 320, height: int = 240) -> Scene:
        return _scene(mesh_name, kind, width, height)

    build.__name__ = f"{mesh_name}_{kind}"
    build.__doc__ = f"The {mesh_name} mesh, motion {kind!r}, over a static floor (lambert)."
    REAL_SCENES[build.__name__] = build


for _m in MESHES:
    for _k in MOTIONS:
        _register(_m, _k)


def knot_twist(width: int = 320, height: int = 240) -> Scene:
    """The torus knot twisting about the vertical (up to 70 degrees at its top, 9 vertex
    keyframes, ``Motion.deforming``) while it slides right, over a static floor (lambert)."""
    v, f = real_mesh("knot")
    ts = np.linspace(0.0, 1.0, 9)
    frames = []
    for t in ts:
        ang = np.radians(70.0) * t * (v[:, 1] / SIZE)
        c, s = np.cos(ang), np.sin(ang)
        x, z = v[:, 0] * c + v[:, 2] * s, -v[:, 0] * s + v[:, 2] * c
        frames.append(np.stack([x - 0.5 + 0.6 * t, v[:, 1] + FLOOR_Y + 0.002, z], -1))
    pos = np.stack(frames)
    obj = Object(
        (pos[0], f), color=_COLORS["knot"], shading="lambert", motion=Motion.deforming(ts, pos), name="knot"
    )
    light = DirectionalLight((-0.35, -1.0, -0.55), 1.0)
    return Scene([obj, _floor()], _camera(width, height), lights=[light], ambient=0.0, shutter="box")


REAL_SCENES["knot_twist"] = knot_twist


from ._namespace import tidy  # noqa: E402  (dir() lists the API only; see motionblur._namespace)

tidy(__name__)
