"""The motion volume's coverage model at many segments: time linear in the segments, accuracy kept.

Past ``MAX_MODEL_SEGMENTS`` (64) path segments the model follows the path on 64 spans of
consecutive segments, so a vertex's coverage costs the same for any count and a volume's alphas
cost time linear in its segments (they grew with the square: icosphere(3) 512 segments 1.6 s,
4096 segments 59 s; a 12-face box with the gaussian filter and 4096 segments ran past 300 s).
The timings are ratios of best-of-3 runs in the same test (the machine is shared), with margins
far from both laws; the accuracy is measured against a 512-sample accumulation of the same
scene, before (64 segments) and after (65, 512) the spans start.
"""

from __future__ import annotations

import time

import numpy as np
import pytest

import motionblur as mb
from motionblur import meshes
from motionblur.scene import rotate, translate


def best_time(fn, rounds=3):
    out = []
    for _ in range(rounds):
        t = time.perf_counter()
        fn()
        out.append(time.perf_counter() - t)
    return min(out)


def test_the_alphas_cost_time_linear_in_the_segments():
    # 8x the segments: linear is 8x the time, the old square law 40-64x.
    mesh = mb.Mesh(*meshes.icosphere(3))

    def build(s):
        return lambda: mb.motion_volume(
            mesh, [1.0, 0.3, 0.0], segments=s, filter="box", camera_position=[0, 0, 6]
        )

    build(256)()  # warm-up (mesh caches, thread pool)
    t256, t2048 = best_time(build(256)), best_time(build(2048))
    assert t2048 / t256 < 20, f"256 segments {t256:.3f} s, 2048 segments {t2048:.3f} s"


def test_a_box_with_the_gaussian_filter_and_many_segments_finishes():
    # 1024 segments: about a second now; the square law took ~100 s (128 segments took 1.6 s).
    mesh = mb.Mesh(*meshes.box((1.0, 1.0, 1.0)))
    t = best_time(lambda: mb.motion_volume(mesh, [1.0, 0.3, 0.0], segments=1024, filter="gaussian"), rounds=1)
    assert t < 20.0, f"{t:.1f} s"


@pytest.fixture(scope="module")
def turning_scene():
    """A box that turns about a tilted axis along a curved, slightly receding path."""
    cam = mb.Camera(mb.look_at((0, 0, 5), (0, 0, 0)), 0.7, 160, 120, znear=0.5, zfar=30)
    times = np.linspace(0.0, 1.0, 5)
    mats = [
        translate((np.cos(2.5 * t) - 0.5, np.sin(2.5 * t) - 0.3, 0.2 * t)) @ rotate(1.2 * t, (0.3, 1, 0.2))
        for t in times
    ]
    obj = mb.Object(meshes.box((0.6, 0.4, 0.5)), (0.9, 0.5, 0.2), motion=mb.Motion(times, np.array(mats)))
    return mb.Scene([obj], cam)


@pytest.mark.parametrize("filt", ["box", "gaussian"])
def test_spans_keep_the_coverage_of_every_segment(turning_scene, filt):
    scene = turning_scene.with_(shutter=filt)
    ref = mb.render(scene, "accumulation", samples=512, aa=2).rgba[..., 3]
    alphas = {}
    for s in (64, 65, 512):
        got = mb.render(scene, "motion_volume", aa=2, segments=s).rgba[..., 3]
        total = got.sum() / ref.sum() - 1
        pixel = np.abs(got - ref).sum() / ref.sum()
        # measured: total +1.8% (box) / +3.8% (gaussian), per pixel 11.2% / 7.7% at every count
        assert abs(total) < 0.05, f"{s} segments: total {total:+.3f}"
        assert pixel < 0.13, f"{s} segments: per pixel {pixel:.3f}"
        alphas[s] = got
    # the spans (65, 512 segments) stay within a per cent of following every segment (64)
    for s in (65, 512):
        assert np.abs(alphas[s] - alphas[64]).sum() / ref.sum() < 0.01
