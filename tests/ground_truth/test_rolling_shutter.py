"""The rolling shutter (``Scene(rolling=R, rolling_direction=...)``): pixel row ``y`` of ``H`` is
exposed over ``[o, o + 1 - R]`` of the scene's time, ``o = R * y / H`` top to bottom or
``o = R * (H - 1 - y) / H`` bottom to top, the shutter filter rescaled to that window.

Oracle: a vertical bar 6 pixels wide, taller than the view, facing the camera on an empty
background, translating horizontally by ``V`` = 40 pixels over the scene's time, edges on pixel
boundaries at the open. With a box shutter each row's alpha-weighted centroid (pixel centres
``x + 0.5``) is the bar's mean centre over that row's window, ``60 + V * (o + s / 2)``
(``s = 1 - R``): the analytic frame's coverage is exact, and the sampling sawtooth of the
pixel centres averages to zero over a window of ``V * s`` = 20 (a whole number of) pixels, so
the only error is float32 rounding (1.1e-7 px measured at R = 0.5, 3.3e-7 at R = 0.9; bound 1e-5 px). The bar therefore
leans by ``V * R * (H - 1) / H`` pixels from the top row to the bottom one, the other way
bottom to top. A still scene is unchanged by any readout. Accumulation weighs its renders per
row and converges to the analytic frame; the other methods refuse a rolling shutter."""

from __future__ import annotations

import pickle

import numpy as np
import pytest

import motionblur as mb
from motionblur.render import METHODS, ROLLING_METHODS

H, W = 120, 160
PX = 2 * 5 * np.tan(0.4) / H  # one pixel at distance 5 (yfov 0.8)
V = 40.0  # pixels over the scene's time


def _bar(rolling=0.0, direction="top_to_bottom", speed=V, shutter="box", **extra) -> mb.Scene:
    hw, hh = 3 * PX, 5.0  # 6 pixels wide, taller than the view (4.2 units)
    verts = np.array([[-hw, -hh, 0], [hw, -hh, 0], [hw, hh, 0], [-hw, hh, 0]], float)
    start = np.array([-20 * PX, 0.0, 0.0])  # centre at pixel 60 at the open
    motion = mb.Motion.linear(start, start + np.array([speed * PX, 0.0, 0.0]))
    obj = mb.Object(mb.Mesh(verts, [[0, 1, 2], [0, 2, 3]]), color=(0.9, 0.5, 0.2), motion=motion)
    cam = mb.Camera(mb.look_at((0.0, 0.0, 5.0), (0.0, 0.0, 0.0)), 0.8, W, H, znear=0.1, zfar=100.0)
    return mb.Scene([obj], cam, shutter=shutter, rolling=rolling, rolling_direction=direction, **extra)


def _centroids(rgba: np.ndarray) -> np.ndarray:
    a = rgba[..., 3].astype(np.float64)
    return (a * (np.arange(W) + 0.5)).sum(axis=1) / a.sum(axis=1)


def _offsets(readout: float, direction: str) -> np.ndarray:
    y = np.arange(H, dtype=np.float64)
    return readout * (y if direction == "top_to_bottom" else H - 1 - y) / H


@pytest.mark.parametrize("direction", ["top_to_bottom", "bottom_to_top"])
@pytest.mark.parametrize("readout", [0.0, 0.5, 0.9])
def test_a_translating_bar_leans_by_readout_times_speed(readout, direction):
    frame = mb.render(_bar(readout, direction), "analytic", error_estimate=False)
    s = 1.0 - readout
    if readout == 0.9:  # a window of V * s = 4 pixels: still a whole number
        assert V * s == pytest.approx(4.0)
    expected = 60.0 + V * (_offsets(readout, direction) + s / 2)
    np.testing.assert_allclose(_centroids(frame.rgba), expected, rtol=0, atol=1e-5)
    # every row holds the bar's whole light (6 pixels of alpha 1) over its own window
    np.testing.assert_allclose(frame.rgba[..., 3].sum(axis=1), 6.0, rtol=1e-6)
    lean = _centroids(frame.rgba)[-1] - _centroids(frame.rgba)[0]
    sign = 1.0 if direction == "top_to_bottom" else -1.0
    assert lean == pytest.approx(sign * V * readout * (H - 1) / H, abs=1e-5)


def test_depth_ids_and_velocity_describe_each_rows_reference_instant():
    """With the reference time at the open, row ``y`` reports the bar where it is at ``o_y``:
    its front surface covers pixel centres within 3 px of ``60 + V * o_y``."""
    frame = mb.render(_bar(0.5, reference_time="open"), "analytic", error_estimate=False)
    for y in (0, 60, 119):
        c = 60.0 + V * 0.5 * y / H
        covered = np.flatnonzero(frame.ids[y] == 0) + 0.5
        assert covered.min() > c - 3 and covered.max() < c + 3, (y, covered)
        np.testing.assert_allclose(
            frame.velocity[y, covered.astype(int)], [[V, 0.0]] * len(covered), atol=1e-3
        )


@pytest.mark.parametrize("shutter", ["box", "triangle"])
def test_a_still_scene_is_unchanged_by_any_readout(shutter):
    still = mb.render(_bar(0.0, speed=0.0, shutter=shutter), "analytic", error_estimate=False)
    for direction in ("top_to_bottom", "bottom_to_top"):
        rolled = mb.render(_bar(0.7, direction, speed=0.0, shutter=shutter), "analytic", error_estimate=False)
        np.testing.assert_array_equal(rolled.rgba, still.rgba)
        np.testing.assert_array_equal(rolled.depth, still.depth)
        np.testing.assert_array_equal(rolled.ids, still.ids)


def test_a_zero_readout_is_the_global_shutter_bit_for_bit():
    scene = _bar()
    cam = scene.camera
    plain = mb.Scene(scene.objects, cam)
    for method in ("analytic", "accumulation"):
        a = mb.render(plain, method, error_estimate=False)
        b = mb.render(_bar(0.0), method, error_estimate=False)
        np.testing.assert_array_equal(a.rgba, b.rgba)
        np.testing.assert_array_equal(a.velocity, b.velocity)


def test_a_filter_applies_within_each_rows_window():
    """A ramp shutter weighs each row's window by ``2 u``: the bar's mean centre over the window
    is at ``o + 2 s / 3``. The ramp's weight of coverage is exact; the centroid's sampling
    sawtooth (pixel centres) no longer averages out exactly under a weight: 0.0083 px measured,
    bound 0.02 px."""
    frame = mb.render(_bar(0.5, shutter="ramp"), "analytic", error_estimate=False)
    expected = 60.0 + V * (_offsets(0.5, "top_to_bottom") + 0.5 * 2 / 3)
    np.testing.assert_allclose(_centroids(frame.rgba), expected, rtol=0, atol=0.02)


def test_exact_and_auto_honour_it():
    scene = _bar(0.5)
    ref = mb.render(scene, "analytic", error_estimate=False).rgba
    np.testing.assert_array_equal(mb.exact(scene).rgba, ref)
    auto = mb.render(scene, "auto", error_estimate=False)
    assert auto.stats["plan"]["kept"]["method"] == "analytic"
    np.testing.assert_array_equal(auto.rgba, ref)


@pytest.mark.parametrize("method", sorted(set(METHODS) - ROLLING_METHODS))
def test_methods_that_cannot_model_it_refuse_it(method):
    with pytest.raises(ValueError, match=r"^rolling: .*analytic, auto"):
        mb.render(_bar(0.5), method, error_estimate=False)


@pytest.mark.parametrize(
    ("kwargs", "error", "name"),
    [
        ({"rolling": -0.1}, ValueError, "rolling"),
        ({"rolling": 1.0}, ValueError, "rolling"),
        ({"rolling": float("nan")}, ValueError, "rolling"),
        ({"rolling": "0.5"}, TypeError, "rolling"),
        ({"direction": "left_to_right"}, ValueError, "rolling_direction"),
        ({"direction": 1}, TypeError, "rolling_direction"),
    ],
)
def test_bad_values_are_refused_naming_the_argument(kwargs, error, name):
    with pytest.raises(error, match=f"^{name}:"):
        _bar(**{"rolling": 0.5, **kwargs})


def test_the_settings_survive_with_and_pickling():
    scene = _bar(0.25, "bottom_to_top")
    for copy in (scene.with_(ambient=0.1), pickle.loads(pickle.dumps(scene))):
        assert (copy.rolling, copy.rolling_direction) == (0.25, "bottom_to_top")
    assert scene.with_(rolling=0.0).rolling == 0.0


@pytest.mark.parametrize(
    ("shutter", "readout", "direction"),
    [("box", 0.5, "top_to_bottom"), ("triangle", 0.3, "bottom_to_top")],
)
def test_accumulation_converges_to_the_analytic_frame_per_row(shutter, readout, direction):
    """Accumulation weighs each render by every row's own window (`rolling_accumulation`): its
    RMSE against the analytic frame falls as 1/N (measured: 6.4e-3 to 1.0e-2 at N = 16,
    3.8e-4 to 4.7e-4 at N = 256 on these two cases); bounds 2e-3 at N = 256 and a fall of at
    least 8x from N = 16."""
    scene = _bar(readout, direction, shutter=shutter)
    ref = mb.render(scene, "analytic", error_estimate=False).rgba.astype(np.float64)

    def rmse(n: int) -> float:
        frame = mb.render(scene, "accumulation", samples=n, error_estimate=False)
        return float(np.sqrt(np.mean((frame.rgba - ref) ** 2)))

    coarse, fine = rmse(16), rmse(256)
    assert fine < 2e-3
    assert fine < coarse / 8
    # the global shutter's accumulation is a different frame: the rows do not lean
    flat = mb.render(_bar(0.0, shutter=shutter), "accumulation", samples=256, error_estimate=False)
    assert float(np.sqrt(np.mean((flat.rgba - ref) ** 2))) > 10 * fine


def test_accumulation_leaves_a_still_scene_unchanged():
    still = mb.render(_bar(0.0, speed=0.0), "accumulation", samples=8, error_estimate=False)
    rolled = mb.render(_bar(0.7, speed=0.0), "accumulation", samples=8, error_estimate=False)
    np.testing.assert_allclose(rolled.rgba, still.rgba, rtol=0, atol=1e-6)  # weights sum to 1 in float64
    np.testing.assert_array_equal(rolled.ids, still.ids)


@pytest.mark.parametrize(("readout", "direction"), [(0.5, "top_to_bottom"), (0.3, "bottom_to_top")])
@pytest.mark.parametrize("samples", [1, 16])
def test_accumulation_carries_an_error_estimate_under_a_rolling_shutter(readout, direction, samples):
    """With the default error estimate (every frame carries one): its pilot's reference is the
    exact frame, which models the readout (accumulation's rolling frames have no halves; the
    pilot once asked them for an estimate and raised KeyError). Measured estimate / RMSE against
    `mb.exact`: 0.99-1.42 on these cases; bounds 0.5-2x, the calibration target."""
    scene = _bar(readout, direction)
    frame = mb.render(scene, "accumulation", samples=samples)
    measured = float(np.sqrt(np.mean((frame.rgba.astype(np.float64) - mb.exact(scene).rgba) ** 2)))
    assert 0.5 * measured <= frame.stats["error_estimate"] <= 2.0 * measured
