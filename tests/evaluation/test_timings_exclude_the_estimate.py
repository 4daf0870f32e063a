"""The report's timings are each render's own cost: none of them runs the pilot error estimate
that ``render`` adds by default (it cost 3-9x the render of a pilot-estimated method at
320x240, and 5.6x the analytic frame's, so every such method was charged for it against
accumulation, whose halves are free)."""

from __future__ import annotations

import pytest

import motionblur as mb
from motionblur.evaluation.cluster import timed_task
from motionblur.evaluation.sweep import paired_times
from motionblur.render import ESTIMATOR


@pytest.fixture
def estimator_calls():
    calls = []
    real = ESTIMATOR[0]

    def counting(*args, **kwargs):
        calls.append(args[1])
        return real(*args, **kwargs)

    ESTIMATOR[0] = counting
    try:
        yield calls
    finally:
        ESTIMATOR[0] = real


def test_render_still_estimates_by_default(estimator_calls):
    mb.render(mb.SCENES["cube"](width=64, height=48), "opaque_image")
    assert estimator_calls == ["opaque_image"]  # the counter sees the estimate where it runs


@pytest.mark.parametrize("method", ["opaque_image", "motion_volume", "analytic"])
def test_timed_renders_run_no_estimate(estimator_calls, method):
    scene = mb.SCENES["cube"](width=64, height=48)
    ms, rgba, _ = timed_task(scene, method, {}, 2)
    assert ms > 0.0 and rgba.shape == (48, 64, 4)
    paired_times(scene, [(method, {}), ("accumulation", {"samples": 1})], rounds=1, burst=1)
    assert estimator_calls == []
