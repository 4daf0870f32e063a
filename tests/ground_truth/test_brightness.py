"""The brightness convention: a frame is the shutter-weighted *average* over the exposure, so a
longer motion (a longer exposure of the same speed) spreads an object's light over more pixels
without changing its total, and the shutter filter does not change a still scene at all.

Oracle: a flat square facing the camera on a black background, 28 pixels wide with its edges on
pixel boundaries, fully in view at every time: its total premultiplied colour is its colour times
784 pixels in the sharp frame and in every blurred one (its rows are exact; along the motion the
analytic frame integrates coverage exactly, 1e-4 relative; accumulation's samples each cover a
whole number of columns, so its total is off by at most one column's share, 1/28)."""

from __future__ import annotations

import numpy as np
import pytest

import motionblur as mb


def _scene(shift: float, shutter="box") -> mb.Scene:
    h = 14.0 * 5.0 * np.tan(0.4) / 60.0  # 14 pixels at distance 5 (yfov 0.8, 120 rows)
    v = np.array([[-h, -h, 0], [h, -h, 0], [h, h, 0], [-h, h, 0]], float)
    motion = mb.Motion.linear(np.array([-shift / 2, 0, 0]), np.array([shift / 2, 0, 0]))
    obj = mb.Object(mb.Mesh(v, [[0, 1, 2], [0, 2, 3]]), color=(0.8, 0.6, 0.2), motion=motion)
    cam = mb.Camera(mb.look_at((0.0, 0.0, 5.0), (0.0, 0.0, 0.0)), 0.8, 160, 120, znear=0.1, zfar=100.0)
    return mb.Scene([obj], cam, shutter=shutter, background=(0, 0, 0, 0))


@pytest.mark.parametrize("method", ["analytic", "accumulation"])
@pytest.mark.parametrize("shift", [0.2, 1.0, 2.5])
def test_a_longer_motion_spreads_the_light_without_changing_its_total(method, shift):
    sharp = mb.render(_scene(0.0), method, error_estimate=False).rgba.sum(axis=(0, 1))
    np.testing.assert_allclose(sharp, 784 * np.array([0.8, 0.6, 0.2, 1.0]), rtol=1e-5)
    blurred = mb.render(_scene(shift), method, error_estimate=False).rgba.sum(axis=(0, 1))
    np.testing.assert_allclose(blurred, sharp, rtol=1e-4 if method == "analytic" else 1 / 28)
    assert (mb.render(_scene(shift), method, error_estimate=False).rgba[..., 3] > 0).sum() > (
        mb.render(_scene(0.0), method, error_estimate=False).rgba[..., 3] > 0
    ).sum()


@pytest.mark.parametrize("shutter", ["ramp", "triangle", "gaussian", [0.0, 1.0, 3.0]])
def test_the_shutter_filter_weighs_time_and_leaves_a_still_scene_unchanged(shutter):
    still = mb.render(_scene(0.0), "analytic", error_estimate=False).rgba
    np.testing.assert_array_equal(
        mb.render(_scene(0.0, shutter), "analytic", error_estimate=False).rgba, still
    )
    moving = mb.render(_scene(1.0, shutter), "analytic", error_estimate=False).rgba.sum(axis=(0, 1))
    np.testing.assert_allclose(moving, still.sum(axis=(0, 1)), rtol=1e-4)
