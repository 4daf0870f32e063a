"""Every method as ``render`` runs it by default (its error estimate on) under every kind of
shutter the scene can have: a finite ``stats["error_estimate"]`` and a finite frame, or a clear
ValueError (a method that cannot model the motion refuses it). Every other test of rolling
shutters passed ``error_estimate=False``, and accumulation's default estimate under one raised
KeyError (its pilot asked a rolling accumulation, which has no halves, for an estimate)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import motionblur as mb

SHUTTERS = {
    "rolling top to bottom": {"rolling": 0.4},
    "rolling bottom to top": {"rolling": 0.4, "rolling_direction": "bottom_to_top"},
    "weights closed at first": {"shutter": np.array([0.0, 0.0, 1.0, 1.0])},
    "triangle": {"shutter": "triangle"},
}


@pytest.mark.parametrize("shutter", SHUTTERS)
@pytest.mark.parametrize("name", ["cube", "pan"])
def test_every_method_estimates_its_error_or_refuses(name, shutter):
    scene = mb.SCENES[name](width=64, height=48).with_(**SHUTTERS[shutter])
    rendered = 0
    for method in mb.METHODS:
        if not mb.METHODS[method].applies(scene):
            continue
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", mb.PoorBlurWarning)
                frame = mb.render(scene, method)
        except ValueError as exc:
            assert str(exc), method  # refused, saying why
            continue
        est = frame.stats["error_estimate"]
        assert np.isfinite(est) and est >= 0.0, (method, est)
        assert np.all(np.isfinite(frame.rgba)), method
        rendered += 1
    assert rendered >= 3  # accumulation, analytic and auto model every shutter
