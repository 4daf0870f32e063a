"""The image-space methods' sharp frame with objects of both shading modes: one rasterizer call,
so its depth test and its transparent sort are per sample (the frame formerly merged one call
per mode by one depth a pixel, wrong at aa 2 and 4 on edges where the modes meet and where a
transparent surface of one mode lies between two of the other's).

Oracles: the same frame drawn at twice the size with one sample a pixel and box-resolved (what
``aa`` 2 means), and accumulation's one-sample frame (which sorts every surface per sample)."""

from __future__ import annotations

import numpy as np
import pytest

import motionblur as mb
from motionblur.evaluation.random_scenes import random_scene
from motionblur.methods._sharp import sharp_frame


def _mixed_seeds(count: int) -> list[int]:
    found = []
    for seed in range(200):
        scene = random_scene(seed, 48, 36)
        if len({o.shading for o in scene.objects}) == 2:
            found.append(seed)
        if len(found) == count:
            return found
    raise AssertionError("too few tuning scenes with both shading modes")


@pytest.mark.parametrize("seed", _mixed_seeds(6))
def test_aa_2_is_the_box_resolve_of_twice_the_size(seed):
    """Tolerance 1e-6: the resolve's float32 sums in another order. The old per-mode merge was
    off by up to 0.2-0.3 on such scenes' edges."""
    scene = random_scene(seed, 48, 36)
    big = scene.with_(camera=scene.camera.resized(96, 72))
    f2 = sharp_frame(scene, 0.5, aa=2).rgba.astype(np.float64)
    f1 = sharp_frame(big, 0.5, aa=1).rgba.astype(np.float64)
    resolved = f1.reshape(36, 2, 48, 2, 4).mean(axis=(1, 3))
    assert np.abs(f2 - resolved).max() <= 1e-6


def _quad(z: float, size: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    s = size
    v = np.array([[-s, -s, z], [s, -s, z], [s, s, z], [-s, s, z]], np.float64)
    return v, np.array([[0, 1, 2], [0, 2, 3]])


def test_a_translucent_surface_between_two_of_the_other_mode_shows():
    """A lambert wall, a flat translucent quad, a lambert translucent quad in front: the flat one
    shows through the front one (the old merge hid it behind the lambert call's nearer depth)."""
    cam = mb.Camera(mb.look_at((0.0, 0.0, 4.0), (0.0, 0.0, 0.0)), 0.8, 40, 30)
    light = [mb.DirectionalLight((0.0, 0.0, -1.0))]
    wall = mb.Object(_quad(-1.0, 3.0), color=(0.2, 0.3, 0.9, 1.0), shading="lambert")
    middle = mb.Object(_quad(0.0, 0.6), color=(1.0, 0.1, 0.1, 0.5), shading="flat")
    front = mb.Object(_quad(1.0, 0.6), color=(0.1, 1.0, 0.1, 0.5), shading="lambert")
    scene = mb.Scene([wall, middle, front], cam, lights=light)
    without = scene.with_(objects=[wall, front])
    got = sharp_frame(scene, 0.5).rgba
    oracle = mb.render(scene, "accumulation", samples=1, error_estimate=False).rgba
    assert np.abs(got - oracle).max() <= 1e-6
    centre = got[15, 20] - sharp_frame(without, 0.5).rgba[15, 20]
    assert centre[0] > 0.1  # the red flat quad adds to the centre
