"""Built-in scenes for demos, tests and the speed-against-error report.

``SCENES[name](width=..., height=...) -> Scene``. Each scene is a function decorated with
[`builtin_scene`][motionblur.scenes_builtin.builtin_scene]; other modules add scenes by adding decorated functions at the end of this
file. Shading is chosen so that the Mitsuba reference sees the same light as the rasterizer:
scenes with static backdrops are flat (no shadows to disagree about), lit scenes have no
surface another object could shadow.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from . import meshes
from .raster import Camera, look_at
from .scene import DirectionalLight, Motion, Object, Scene, rotate, translate

__all__ = ["SCENES", "builtin_scene", "airplane_mesh"]

#: Built-in scenes by name: functions ``(width=..., height=...) -> Scene``.
SCENES: dict[str, Callable[..., Scene]] = {}


def builtin_scene(name: str):
    """Decorator: register a scene function ``(width, height) -> Scene`` under ``name``."""

    def deco(fn):
        SCENES[name] = fn
        return fn

    return deco


def _scaled(mesh, scale, offset=(0.0, 0.0, 0.0)):
    v, f = mesh
    return v * np.asarray(scale) + np.asarray(offset), f


def _merge(*parts):
    vs, fs, n = [], [], 0
    for v, f in parts:
        vs.append(v)
        fs.append(f + n)
        n += len(v)
    return np.concatenate(vs), np.concatenate(fs)


def airplane_mesh():
    """An airplane-like mesh of 2240 triangles, nose along +X: an ellipsoid fuselage (1280),
    wings, tailplane and fin (320 each), each a closed component."""
    return _merge(
        _scaled(meshes.icosphere(3), (1.0, 0.17, 0.17)),
        _scaled(meshes.icosphere(2), (0.22, 0.03, 0.85), (0.05, 0.0, 0.0)),
        _scaled(meshes.icosphere(2), (0.12, 0.02, 0.35), (-0.85, 0.02, 0.0)),
        _scaled(meshes.icosphere(2), (0.14, 0.22, 0.02), (-0.85, 0.17, 0.0)),
    )


def _floor(y=-0.6, size=(8.0, 0.1, 4.0), z=-1.0):
    return _scaled(meshes.box(size), 1.0, (0.0, y - size[1] / 2, z))


@builtin_scene("cube")
def translating_cube(width: int = 320, height: int = 240) -> Scene:
    """The paper's example: a cube translating quickly to the right over a static floor and wall (flat)."""
    cam = Camera(look_at((0.0, 0.6, 4.0), (0.0, 0.0, 0.0)), 0.7, width, height, znear=0.5, zfar=30.0)
    cube = Object(
        meshes.box((0.7, 0.7, 0.7)),
        color=(0.9, 0.35, 0.1),
        motion=Motion.linear(translate((-1.2, 0.0, 0.0)), translate((0.6, 0.0, 0.0))),
        name="cube",
    )
    floor = Object(_floor(), color=(0.25, 0.3, 0.35), name="floor")
    wall = Object(
        _scaled(meshes.box((8.0, 3.0, 0.1)), 1.0, (0.0, 0.8, -2.2)), color=(0.5, 0.5, 0.45), name="wall"
    )
    return Scene([cube, floor, wall], cam, shutter="box")


@builtin_scene("airplane")
def airplane(width: int = 320, height: int = 240) -> Scene:
    """An airplane-like mesh (2240 triangles) flying forward and banking slightly, lambert lit."""
    cam = Camera(look_at((0.0, 0.8, 4.5), (0.0, 0.0, 0.0)), 0.7, width, height, znear=0.5, zfar=30.0)
    start = translate((-1.0, -0.1, 0.0)) @ rotate(0.15, (1.0, 0.0, 0.0))
    end = translate((0.8, 0.15, 0.0)) @ rotate(-0.1, (1.0, 0.0, 0.0)) @ rotate(0.12, (0.0, 0.0, 1.0))
    plane = Object(
        airplane_mesh(),
        color=(0.8, 0.8, 0.85),
        shading="lambert",
        motion=Motion.linear(start, end),
        name="airplane",
    )
    light = DirectionalLight((-0.3, -1.0, -0.6), 1.0)
    return Scene([plane], cam, lights=[light], ambient=0.0, shutter="box")


@builtin_scene("sphere80k")
def sphere80k(width: int = 320, height: int = 240) -> Scene:
    """An 82k-triangle sphere (icosphere level 6) translating diagonally, lambert lit."""
    cam = Camera(look_at((0.0, 0.0, 5.0), (0.0, 0.0, 0.0)), 0.7, width, height, znear=0.5, zfar=30.0)
    sphere = Object(
        meshes.icosphere(6, 0.6),
        color=(0.2, 0.5, 0.9),
        shading="lambert",
        motion=Motion.linear(translate((-1.2, -0.3, 0.0)), translate((0.9, 0.4, 0.0))),
        name="sphere",
    )
    light = DirectionalLight((-0.4, -0.5, -1.0), 1.0)
    return Scene([sphere], cam, lights=[light], shutter="box")


@builtin_scene("curved")
def curved_path(width: int = 320, height: int = 240) -> Scene:
    """A torus on a half-circle arc (9 keyframes), turning with its path, over a static floor (flat)."""
    cam = Camera(look_at((0.0, 0.5, 4.5), (0.0, 0.2, 0.0)), 0.75, width, height, znear=0.5, zfar=30.0)
    angles = np.linspace(np.pi, 0.0, 9)
    radius = 1.3
    mats = []
    for a in angles:
        pos = (radius * np.cos(a), 0.25 + 0.9 * np.sin(a) - 0.45, 0.0)
        mats.append(translate(pos) @ rotate(a - np.pi, (0.0, 0.0, 1.0)) @ rotate(0.5, (1.0, 0.0, 0.0)))
    torus = Object(
        meshes.torus(0.32, 0.12, 32, 12),
        color=(0.2, 0.8, 0.3),
        motion=Motion(np.linspace(0.0, 1.0, 9), np.stack(mats)),
        name="torus",
    )
    floor = Object(_floor(-0.7), color=(0.3, 0.3, 0.32), name="floor")
    return Scene([torus, floor], cam, shutter="box")


@builtin_scene("pan")
def camera_pan(width: int = 320, height: int = 240) -> Scene:
    """A still scene (columns on a floor) seen by a camera panning 10 degrees during the shutter (flat)."""
    eye = np.array([0.0, 0.6, 4.0])
    cam = Camera(look_at(eye, (0.0, 0.2, 0.0)), 0.7, width, height, znear=0.5, zfar=30.0)
    objs = [Object(_floor(-0.6, (10.0, 0.1, 6.0)), color=(0.3, 0.3, 0.3), name="floor")]
    colours = [(0.9, 0.2, 0.2), (0.2, 0.8, 0.3), (0.2, 0.4, 0.9), (0.9, 0.8, 0.2), (0.8, 0.3, 0.8)]
    for i, x in enumerate(np.linspace(-1.6, 1.6, 5)):
        v, f = meshes.cylinder(0.18, 1.4, 24)
        v = v[:, [0, 2, 1]] * (1.0, 1.0, 1.0)  # along +Y
        f = f[:, [0, 2, 1]]  # the axis swap mirrors: restore counter-clockwise winding
        objs.append(Object((v + (x, -0.6, -0.4 * i), f), color=colours[i], name=f"column{i}"))
    pan = Motion.linear(np.eye(4), rotate(np.radians(10.0), (0.0, 1.0, 0.0), eye))
    return Scene(objs, cam, camera_motion=pan, shutter="box")


# --- deforming scenes (blur shells, branch shell)


@builtin_scene("bending_arm")
def bending_arm_scene(width: int = 320, height: int = 240) -> Scene:
    """A skinned cylinder (1,200 triangles) bending 60 degrees at the elbow during the shutter,
    seen from the side (flat): a deforming mesh (``Motion.deforming``, 17 vertex keyframes)."""
    pos, faces = meshes.bending_arm(17, radius=0.22, length=2.0, angle=np.pi / 3, sections=24, rings=24)
    cam = Camera(
        look_at((5.0, -0.5, 1.1), (0.0, -0.5, 1.1), up=(0.0, 0.0, 1.0)),
        0.62,
        width,
        height,
        znear=0.5,
        zfar=30.0,
    )
    arm = Object(
        (pos[0], faces),
        color=(0.95, 0.55, 0.15),
        motion=Motion.deforming(np.linspace(0.0, 1.0, len(pos)), pos),
        name="arm",
    )
    return Scene([arm], cam, shutter="box")


@builtin_scene("deforming_propeller")
def deforming_propeller(width: int = 320, height: int = 240) -> Scene:
    """A three-blade propeller spinning 0.08 turns during the shutter, given as vertex keyframes
    (``Motion.deforming``, 33 keyframes), seen from the front and slightly below (flat)."""
    pos, faces = meshes.spinning_propeller(33, blades=3, radius=1.0, turns=0.08, chord=0.3)
    cam = Camera(look_at((0.0, -1.0, 3.6), (0.0, 0.0, 0.0)), 0.75, width, height, znear=0.5, zfar=30.0)
    prop = Object(
        (pos[0], faces),
        color=(0.2, 0.6, 0.95),
        motion=Motion.deforming(np.linspace(0.0, 1.0, len(pos)), pos),
        name="propeller",
    )
    return Scene([prop], cam, shutter="box")


# --- rotating scenes (spin volumes, paper section 4.3)


@builtin_scene("spinning_propeller")
def spinning_propeller_scene(width: int = 320, height: int = 240) -> Scene:
    """A rigid three-blade propeller turning 0.15 turns (54 degrees) about its axis (+Z) during
    the shutter, with no translation (``Motion`` of 9 rotation keyframes), seen from the front
    and slightly below (flat): the spin case of the motion-volume paper (section 4.3)."""
    pos, faces = meshes.spinning_propeller(2, blades=3, radius=1.0, turns=0.0, chord=0.3)
    cam = Camera(look_at((0.0, -1.0, 3.6), (0.0, 0.0, 0.0)), 0.75, width, height, znear=0.5, zfar=30.0)
    times = np.linspace(0.0, 1.0, 9)
    spin = Motion(times, np.stack([rotate(2.0 * np.pi * 0.15 * t, (0.0, 0.0, 1.0)) for t in times]))
    prop = Object((pos[0], faces), color=(0.2, 0.6, 0.95), motion=spin, name="propeller")
    return Scene([prop], cam, shutter="box")


from ._namespace import tidy  # noqa: E402  (dir() lists the API only; see motionblur._namespace)

tidy(__name__)
