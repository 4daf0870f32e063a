"""Seeded random scenes nobody picked: the content the error estimates and ``auto`` are measured on.

``random_scene(seed, width, height)`` builds one to three meshes over an optional lit floor, each
static, translating (across the view or toward the camera), turning by 0.2 rad to a full turn
about a random axis while it moves, on a curved five-key path, or deforming (a twist or a bend
as vertex keyframes); a fifth of the scenes move the camera too (a curved hand-held path), a
fifth are seen through a shutter other than the box, some objects are translucent. The same seed
gives the same scene.

Two disjoint sets, kept apart on purpose:

- **tuning** (`TUNING_SEEDS`, meshes `TUNING_MESHES`): the only scenes any constant
  of the library (an estimate's factor, ``auto``'s safety margin) was chosen on;
- **measuring** (`MEASURING_SEEDS`, which also draw from `HELD_OUT_MESHES`): the
  scenes the documented figures (docs/validation.md) and the calibration tables are measured on, never tuned on.

Held-out meshes are procedural (a (3,7) torus knot, a gear, a lumpy concave blob) so that the
set needs no data files.
"""

from __future__ import annotations

import numpy as np

from .. import meshes
from ..raster import Camera, look_at
from ..scene import DirectionalLight, Motion, Object, Scene, rotate, translate
from ..scenes_real import torus_knot

__all__ = [
    "random_scene",
    "random_mesh",
    "hand_held_path",
    "TUNING_SEEDS",
    "MEASURING_SEEDS",
    "TUNING_MESHES",
    "HELD_OUT_MESHES",
    "MOTION_KINDS",
]

#: Seeds of the tuning set (every tuned constant was chosen on these scenes only).
TUNING_SEEDS = range(0, 100_000)
#: Seeds of the measuring set (reported figures; never tuned on).
MEASURING_SEEDS = range(1_000_000, 1_100_000)
#: Meshes the tuning scenes draw from.
TUNING_MESHES = ("box", "icosphere", "torus", "cylinder", "knot23", "uv_sphere")
#: Meshes only the measuring scenes draw (half their objects).
HELD_OUT_MESHES = ("knot37", "gear", "blob")
#: The motions an object draws from (``static`` only for the second and third objects).
MOTION_KINDS = ("translate", "toward", "turn", "curved", "deforming", "static")


def _gear(teeth: int = 12) -> tuple[np.ndarray, np.ndarray]:
    """A flat gear: a prism over a toothed outline (concave), centred, height 0.4."""
    n = 4 * teeth
    a = np.linspace(0.0, 2.0 * np.pi, n, endpoint=False)
    r = np.where((np.arange(n) // 2) % 2 == 0, 1.0, 0.72)
    ring = np.stack([r * np.cos(a), r * np.sin(a)], -1)
    top = np.concatenate([[[0.0, 0.0]], ring])
    v = np.concatenate([np.c_[top, np.full(n + 1, 0.2)], np.c_[top, np.full(n + 1, -0.2)]])
    k = np.arange(n)
    nxt = (k + 1) % n
    caps = [
        np.stack([np.zeros(n, int), 1 + k, 1 + nxt], -1),
        np.stack([np.full(n, n + 1), n + 2 + nxt, n + 2 + k], -1),
    ]
    side = [np.stack([1 + k, n + 2 + k, 1 + nxt], -1), np.stack([1 + nxt, n + 2 + k, n + 2 + nxt], -1)]
    return v, np.concatenate(caps + side).astype(np.int64)


def _blob(rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """An icosphere pushed in and out by three random lobes (concave in places)."""
    v, f = meshes.icosphere(3)
    d = rng.normal(size=(3, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    r = 1.0 + 0.35 * np.sin(4.0 * (v @ d.T)).sum(axis=1) / 3.0
    return v * r[:, None], f


def random_mesh(name: str, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """``(vertices (V,3) float64, faces (F,3) int64)`` of pool mesh ``name``, scaled to a largest
    extent of about 1 scene unit (random proportions where the mesh has any)."""
    if name == "box":
        v, f = meshes.box(tuple(rng.uniform(0.4, 1.0, 3)))
    elif name == "icosphere":
        v, f = meshes.icosphere(int(rng.integers(1, 4)), 0.5)
    elif name == "torus":
        v, f = meshes.torus(0.5, float(rng.uniform(0.1, 0.22)), 32, 12)
    elif name == "cylinder":
        v, f = meshes.cylinder(float(rng.uniform(0.2, 0.4)), float(rng.uniform(0.6, 1.0)), 24)
    elif name == "uv_sphere":
        v, f = meshes.uv_sphere(12, 24, 0.5)
    elif name == "knot23":
        v, f = torus_knot(2, 3, 0.45, 0.09, 120, 8)
    elif name == "knot37":
        v, f = torus_knot(3, 7, 0.45, 0.07, 200, 8)
    elif name == "gear":
        v, f = _gear(int(rng.integers(8, 16)))
        v = v * 0.5
    elif name == "blob":
        v, f = _blob(rng)
        v = v * 0.45
    else:
        raise ValueError(f"name: unknown pool mesh {name!r}")
    return np.asarray(v, np.float64), np.asarray(f, np.int64)


def _axis(rng: np.random.Generator) -> np.ndarray:
    a = rng.normal(size=3)
    return a / np.linalg.norm(a)


def _rigid_motion(kind: str, start: np.ndarray, rng: np.random.Generator, right, up, back) -> Motion:
    """A rigid motion of ``kind`` starting near ``start`` (world), in the camera's frame."""
    ts = np.linspace(0.0, 1.0, 5)
    if kind == "translate":
        d = (rng.normal(size=2) * rng.uniform(0.2, 1.6)) @ np.stack([right, up])
        return Motion.linear(translate(start - 0.5 * d), translate(start + 0.5 * d))
    if kind == "toward":
        d = back * rng.uniform(0.8, 2.5) + 0.3 * rng.normal(size=2) @ np.stack([right, up])
        return Motion.linear(translate(start - 0.6 * d), translate(start + 0.4 * d))
    axis, angle = _axis(rng), rng.uniform(0.2, 2.0 * np.pi)
    if kind == "turn":
        d = (rng.normal(size=2) * rng.uniform(0.0, 1.2)) @ np.stack([right, up])
        mats = [translate(start + (t - 0.5) * d) @ rotate(angle * t, axis) for t in ts]
        return Motion(ts, np.stack(mats))
    if kind == "curved":
        pts = start + np.cumsum(rng.normal(size=(5, 3)) * 0.35, axis=0)
        pts -= pts.mean(0) - start
        mats = [translate(p) @ rotate(angle * t, axis) for t, p in zip(ts, pts)]
        return Motion(ts, np.stack(mats))
    raise ValueError(f"kind: unknown rigid motion {kind!r}")


def _deforming(v: np.ndarray, start: np.ndarray, rng: np.random.Generator) -> Motion:
    """Vertex keyframes: a twist about a random axis growing along it, while sliding."""
    axis = _axis(rng)
    amount = rng.uniform(0.5, 2.5)
    slide = rng.normal(size=3) * 0.4
    ts = np.linspace(0.0, 1.0, 5)
    h = v @ axis
    frames = []
    for t in ts:
        ang = amount * t * h
        c, s = np.cos(ang)[:, None], np.sin(ang)[:, None]
        par = h[:, None] * axis
        perp = v - par
        twisted = par + perp * c + np.cross(axis, perp) * s
        frames.append(twisted + start + (t - 0.5) * slide)
    return Motion.deforming(ts, np.stack(frames))


def hand_held_path(rng: np.random.Generator, amount: float = 1.0) -> Motion:
    """A hand-held camera path for ``Scene(camera_motion=...)``: five keys of small random
    shifts (steps of about 0.08 ``amount`` scene units) and turns (0.05 ``amount`` rad about
    each axis), drawn from ``rng``."""
    ts = np.linspace(0.0, 1.0, 5)
    walk = np.cumsum(rng.normal(size=(5, 3)) * 0.08 * amount, axis=0)
    turn = np.cumsum(rng.normal(size=(5, 3)) * 0.05 * amount, axis=0)
    mats = []
    for p, r in zip(walk, turn):
        m = translate(p)
        for k in range(3):
            m = m @ rotate(float(r[k]), np.eye(3)[k])
        mats.append(m)
    return Motion(ts, np.stack(mats))


def _shutter(rng: np.random.Generator):
    u = rng.random()
    if u < 0.8:
        return "box"
    if u < 0.9:
        return str(rng.choice(["triangle", "gaussian", "ramp"]))
    return rng.uniform(0.0, 1.0, int(rng.integers(3, 8))) + 0.05


def random_scene(seed: int, width: int = 96, height: int = 72, held_out: bool | None = None) -> Scene:
    """A seeded random scene (see the module docs) of ``width`` x ``height`` pixels.

    ``held_out``: draw half the meshes from `HELD_OUT_MESHES` (default: exactly when
    ``seed`` is a measuring seed). The same arguments give the same scene."""
    seed = int(seed)
    rng = np.random.default_rng(seed)
    if held_out is None:
        held_out = seed in MEASURING_SEEDS
    eye = np.array([0.0, 0.6, 5.0]) + rng.normal(size=3) * [1.0, 0.5, 0.5]
    target = rng.normal(size=3) * 0.3
    pose = look_at(tuple(eye), tuple(target))
    right, up, back = pose[:3, 0], pose[:3, 1], pose[:3, 2]
    cam = Camera(pose, float(rng.uniform(0.55, 0.9)), int(width), int(height), znear=0.3, zfar=60.0)
    objects = []
    for k in range(int(rng.integers(1, 4))):
        pool = HELD_OUT_MESHES if (held_out and rng.random() < 0.5) else TUNING_MESHES
        name = str(rng.choice(pool))
        v, f = random_mesh(name, rng)
        v = v @ rotate(rng.uniform(0, 2 * np.pi), _axis(rng))[:3, :3].T * rng.uniform(0.7, 1.4)
        start = target + (rng.normal(size=2) * 0.7) @ np.stack([right, up]) - back * rng.uniform(-0.5, 1.5)
        kinds = MOTION_KINDS if k else MOTION_KINDS[:-1]
        kind = str(rng.choice(kinds, p=None))
        rgb = rng.uniform(0.15, 1.0, 3)
        alpha = 1.0 if rng.random() < 0.85 else float(rng.uniform(0.3, 0.8))
        shading = "lambert" if rng.random() < 0.7 else "flat"
        if kind == "deforming":
            motion = _deforming(v, start, rng)
            v = motion.vertices_at(0.0)
        elif kind == "static":
            v, motion = v + start, None
        else:
            motion = _rigid_motion(kind, start, rng, right, up, back)
        objects.append(Object((v, f), color=(*rgb, alpha), shading=shading, motion=motion, name=f"{name}{k}"))
    if rng.random() < 0.5:
        fv, ff = meshes.box((12.0, 0.1, 12.0))
        objects.append(
            Object((fv + (0.0, -1.3, -2.0), ff), color=(0.35, 0.35, 0.38), shading="lambert", name="floor")
        )
    light = DirectionalLight(
        tuple(-np.abs(_axis(rng)) * [1, 1, 1] + [0, -0.5, 0]), float(rng.uniform(0.7, 1.2))
    )
    camera_motion = hand_held_path(rng) if rng.random() < 0.2 else None
    background = (0.0, 0.0, 0.0, 0.0) if rng.random() < 0.5 else (*rng.uniform(0.0, 0.5, 3), 1.0)
    return Scene(
        objects,
        cam,
        lights=[light],
        camera_motion=camera_motion,
        shutter=_shutter(rng),
        background=background,
        reference_time=float(rng.choice([0.0, 0.5, 1.0])),
        ambient=float(rng.uniform(0.05, 0.3)),
    )
