"""The trapezoid shutter curve (mb.Trapezoid): its weight function in Python and in the core
agree with the closed form, the analytic frame equals accumulation's limit under it, the image-
space methods and the motion volume refuse it by name, and (0, 0) is the box."""

from __future__ import annotations

import numpy as np
import pytest

import motionblur as mb
from motionblur.evaluation.random_scenes import random_scene


def _closed_form_cdf(o: float, c: float, t: np.ndarray) -> np.ndarray:
    """W(t) by integrating the density on a fine grid (an independent check of the formula)."""
    h = 1.0 / (1.0 - 0.5 * (o + c))
    x = np.linspace(0.0, 1.0, 200001)
    w = h * np.minimum.reduce(
        [x / o if o else np.ones_like(x), (1 - x) / c if c else np.ones_like(x), np.ones_like(x)]
    )
    cum = np.concatenate([[0.0], np.cumsum((w[1:] + w[:-1]) / 2 * np.diff(x))])
    return np.interp(t, x, cum)


@pytest.mark.parametrize(("o", "c"), [(0.1, 0.1), (0.3, 0.05), (0.0, 0.5), (0.5, 0.5), (0.0, 0.0)])
def test_the_cdf_is_the_integral_of_the_trapezoid(o, c):
    t = np.linspace(0.0, 1.0, 101)
    np.testing.assert_allclose(mb.shutter_cdf(mb.Trapezoid(o, c), t), _closed_form_cdf(o, c, t), atol=1e-9)


def _moving_scene(shutter):
    s = random_scene(1_000_004, 64, 48)
    return s.with_(shutter=shutter)


def test_the_analytic_frame_is_accumulations_limit_under_a_trapezoid():
    """1e-3: accumulation with 1024 stratified samples is about 1e-4 from its limit here, and a
    shutter misread by the core (a box, a ramp) moves the frame by more than 5e-3."""
    shutter = mb.Trapezoid(0.3, 0.2)
    scene = _moving_scene(shutter)
    exact = mb.exact(scene).rgba
    acc = mb.render(scene, "accumulation", samples=1024, error_estimate=False).rgba
    err = float(np.sqrt(np.mean((acc.astype(np.float64) - exact) ** 2)))
    assert err < 1e-3, err
    box = mb.exact(scene.with_(shutter="box")).rgba
    assert float(np.sqrt(np.mean((box.astype(np.float64) - exact) ** 2))) > 5 * err


def test_zero_ramps_are_the_box_bit_for_bit():
    scene = _moving_scene("box")
    np.testing.assert_array_equal(
        mb.exact(scene.with_(shutter=mb.Trapezoid(0.0, 0.0))).rgba, mb.exact(scene).rgba
    )


def test_methods_that_cannot_honour_it_refuse_by_name():
    scene = _moving_scene(mb.Trapezoid(0.2, 0.2))
    for method in ("velocity", "opaque_image"):
        if mb.METHODS[method].applies(scene):
            with pytest.raises(ValueError, match="shutter"):
                mb.render(scene, method)
    with pytest.raises(ValueError, match="Trapezoid"):
        mb.render(scene, "motion_volume")


@pytest.mark.parametrize(("o", "c"), [(-0.1, 0.1), (0.6, 0.5), (float("nan"), 0.1)])
def test_bad_ramps_name_themselves(o, c):
    with pytest.raises(ValueError, match="open, close|open|close"):
        mb.Trapezoid(o, c)
