"""benches/bench_auto_ceiling.py replays auto's own decisions on renders it records once, and its
ideal planners bound what a planner could pay. If its records or its replay drift from what
``auto`` and ``accumulation`` render, its ceiling figures (docs/validation.md) stop describing auto.

Tuning scenes only (seeds < 100), 64x48."""

from __future__ import annotations

import runpy
from pathlib import Path

import numpy as np
import pytest

import motionblur as mb
from motionblur.evaluation.random_scenes import random_scene
from motionblur.methods import _grids as grids
from motionblur.methods import auto as auto_mod

BENCH = Path(__file__).resolve().parents[2] / "benches" / "bench_auto_ceiling.py"
SEEDS = (3, 12, 14)  # auto refines on these at several tolerances


@pytest.fixture(scope="module")
def bench():
    return runpy.run_path(str(BENCH), run_name="bench_loaded")


@pytest.fixture(scope="module")
def recorded(bench):
    return {seed: bench["Recorded"](random_scene(seed, 64, 48), 1) for seed in SEEDS}


@pytest.mark.parametrize("seed", SEEDS)
def test_a_recorded_grid_is_the_render_auto_makes(recorded, seed):
    """The first render's estimate is the one ``auto`` reads (to the bit), and its measured
    error is the frame ``render`` returns against the exact integral (float32 frames: 1e-7).
    auto draws its samples in four parts by residue (it may refine them), accumulation in two
    halves: the same frame and estimate to float32 rounding of the sums (1e-5 relative)."""
    rec = recorded[seed]
    frame = mb.render(rec.scene, "auto", tolerance=0.01)
    first = [t for t in frame.stats["plan"]["tried"] if "pilot" not in t["options"]][0]
    n = first["options"]["samples"]
    est, err = rec.grid(n, grids.STRATIFIED)
    assert first["error_estimate"] == est
    acc = mb.render(rec.scene, "accumulation", samples=n)
    assert acc.stats["error_estimate"] == pytest.approx(est, rel=1e-5)
    measured = float(np.sqrt(np.mean(np.square(acc.rgba.astype(np.float64) - rec.ref))))
    assert abs(measured - err) <= 1e-7


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("tol", [0.01, 0.004])
def test_the_replayed_plan_draws_what_auto_draws(bench, recorded, seed, tol):
    """Where auto stays with accumulation, the replay asks for the same grids in the same order
    (the decisions read only the estimates, which are recorded to the bit)."""
    rec = recorded[seed]
    real = mb.render(rec.scene, "auto", tolerance=tol).stats["plan"]["tried"]
    if any(t["method"] != "accumulation" for t in real):
        pytest.fail(f"seed {seed} at {tol} went to the analytic frame; pick a scene that does not")
    trials = bench["Replay"](rec)
    auto_mod._for_tolerance(trials, tol)
    assert [t["options"] for t in trials.renders] == [
        t["options"] for t in real if "pilot" not in t["options"]
    ]


def test_perfect_next_finds_auto_last_grid_or_cheaper(bench, recorded):
    """Starting as auto does and knowing every render's error, the best next render costs no
    more than drawing auto's last grid in one step after the first render, whenever that grid
    met the tolerance (it is among the candidates); on the same time model."""
    checked = 0
    for seed, rec in recorded.items():
        for tol in (0.01, 0.004, 0.001):
            trials = bench["Replay"](rec)
            auto_mod._for_tolerance(trials, tol)
            last, first = trials.tried[-1], trials.renders[0]["options"]["samples"]
            best_err, best_ms = bench["plan_perfect_next"](rec, tol)
            if last["method"] != "accumulation" or last["err"] > tol or len(trials.renders) == 1:
                continue
            one_step = (
                rec.ms(first) + rec.ms(grids.draws(trials.grid, (first, grids.STRATIFIED))) + 2 * rec.overhead
            )
            one_step += rec.sweep_ms  # the forecast's pilot, charged to both
            assert best_err <= tol, (seed, tol)
            assert best_ms <= one_step * (1 + 1e-12), (seed, tol, trials.tried)
            checked += 1
    assert checked >= 3  # the scenes were chosen so that auto refines on several
