"""The planner's forecast (`motionblur.methods._sweep`): the compiled screen sweep equals a numpy
twin of its definition, and it moves as the geometry says it should.

Tuning scenes only (seeds < 100), 96x72."""

from __future__ import annotations

import numpy as np
import pytest

import motionblur as mb
from motionblur.evaluation.random_scenes import random_scene
from motionblur.methods._sweep import POINTS, SHADE, TIMES, sweep_scale


def _twin(scene) -> float:
    """The sweep's definition in numpy, step by step (the module docs)."""
    objects = scene.objects if scene.camera_moves else [o for o in scene.objects if o.is_moving]
    cam = scene.camera
    size = np.array([cam.width, cam.height], np.float64)
    times = np.linspace(0.0, 1.0, TIMES)
    bg = np.asarray(scene.background, np.float64)
    under = np.r_[bg[:3] * bg[3], bg[3]]
    total = 0.0
    for o in objects:
        faces = np.asarray(o.mesh.faces)
        m = np.arange(min(POINTS, 4 * len(faces)))
        u, v = (m * 0.6180339887498949) % 1.0, (m * 0.7548776662466927 + 0.5) % 1.0
        fold = u + v > 1.0
        u, v = np.where(fold, 1 - u, u), np.where(fold, 1 - v, v)
        w = np.stack([1 - u - v, u, v], -1)
        pick = faces[(m * len(faces)) // len(m)]
        xy, front = [], []
        for t in times:
            verts = o.world_vertices(float(t))
            p = np.einsum("mk,mkj->mj", w, verts[pick])
            c = mb.Camera(
                scene.camera_pose_at(float(t)),
                cam.yfov,
                cam.width,
                cam.height,
                znear=cam.znear,
                zfar=cam.zfar,
            )
            q, depth = c.project(p)
            xy.append(q)
            front.append(depth > 1e-9)
        xy, front = np.stack(xy), np.stack(front)
        seen = (front & np.all((xy >= 0) & (xy <= size), axis=-1)).any(0)
        if not seen.any():
            continue
        steps = np.where(front[1:] & front[:-1], np.linalg.norm(np.diff(xy, axis=0), axis=-1), 0.0)
        path = steps.sum(0)[seen].mean()
        mid = np.clip(xy[TIMES // 2][seen & front[TIMES // 2]], 0, size)
        extent = (mid.max(0) - mid.min(0)).sum() if len(mid) else 0.0
        r, g, b, a = np.asarray(o.rgba, np.float64)
        d = np.array(
            [
                (r * SHADE - under[0]) * a,
                (g * SHADE - under[1]) * a,
                (b * SHADE - under[2]) * a,
                (1 - under[3]) * a,
            ]
        )
        total += (2 * extent + 1) * path * np.mean(d**2)
    return float(np.sqrt(total / (cam.width * cam.height)))


def _kinds(scene) -> set[str]:
    kinds = {"camera"} if scene.camera_moves else set()
    return kinds | {"deforming" for o in scene.objects if o.motion is not None and o.motion.is_deforming}


def test_the_compiled_sweep_is_its_definition():
    """Relative 1e-9: the same arithmetic up to the order of sums and the view's inverse. The
    seeds include camera motion and deforming objects."""
    seen = set()
    for seed in range(40):
        scene = random_scene(seed, 96, 72)
        got, want = sweep_scale(scene), _twin(scene)
        assert got == pytest.approx(want, rel=1e-9, abs=1e-15), seed
        seen |= _kinds(scene)
    assert seen == {"camera", "deforming"}


def _square_scene(length: float, color=(1.0, 1.0, 1.0, 1.0), background=(0.0, 0.0, 0.0, 0.0)):
    v = np.array([[-0.5, -0.5, 0.0], [0.5, -0.5, 0.0], [0.5, 0.5, 0.0], [-0.5, 0.5, 0.0]])
    f = np.array([[0, 1, 2], [0, 2, 3]])
    motion = mb.Motion.linear(mb.translate((0.0, 0.0, 0.0)), mb.translate((length, 0.0, 0.0)))
    cam = mb.Camera(mb.look_at((0.0, 0.0, 5.0), (0.0, 0.0, 0.0)), np.pi / 2, 100, 100)
    return mb.Scene([mb.Object((v, f), color=color, motion=motion)], cam, background=background)


def test_the_sweep_grows_as_the_root_of_the_path_and_needs_contrast():
    a, b = sweep_scale(_square_scene(0.5)), sweep_scale(_square_scene(2.0))
    assert b / a == pytest.approx(2.0, rel=1e-9)
    assert sweep_scale(_square_scene(2.0, background=(0.6, 0.6, 0.6, 1.0))) == 0.0
    assert sweep_scale(_square_scene(0.0)) == 0.0
