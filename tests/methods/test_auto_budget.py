"""``auto`` with ``budget_ms``: the most accurate frame that fits, grown in steps that keep the
samples drawn, the analytic frame where it fits.

Budgets here are far from the times involved (a few ms of work against seconds of budget, or
the reverse), so that the plan, not the machine's load, decides each assertion; the bench
(``benches/bench_budget.py``) measures time against budget on the measuring scenes."""

from __future__ import annotations

import math

import numpy as np
import pytest

import motionblur as mb
from motionblur.evaluation.random_scenes import random_scene
from motionblur.methods import _grids as grids
from motionblur.methods import auto as auto_mod


def _rmse(a, b) -> float:
    return float(np.sqrt(np.mean(np.square(np.asarray(a, np.float64) - b))))


def _accumulations(frame) -> list[int]:
    return [t["options"]["samples"] for t in frame.stats["plan"]["tried"] if t["method"] == "accumulation"]


def test_a_budget_the_analytic_frame_fits_gets_the_analytic_frame():
    """Tuning seed 1 at 64x48: the analytic frame takes a few ms. With 5 s it is the frame kept,
    and it is nearer the exact integral than the first 4-sample render by far (factor 100)."""
    scene = random_scene(1, 64, 48)
    f = mb.render(scene, "auto", budget_ms=5000.0)
    plan = f.stats["plan"]
    assert plan["kept"]["method"] == "analytic", plan
    ref = mb.exact(scene).rgba
    first = mb.render(scene, "accumulation", samples=4)
    assert _rmse(f.rgba, ref) * 100 < _rmse(first.rgba, ref)


def _grids(frame) -> list[tuple[int, str]]:
    return [
        (
            t["options"]["samples"] - (t["options"].get("grid") == "trapezoid"),
            t["options"].get("grid", "stratified"),
        )
        for t in frame.stats["plan"]["tried"]
        if t["method"] == "accumulation"
    ]


def test_accumulation_grows_keeping_its_samples(monkeypatch):
    """With the analytic frame priced out, each step's grid holds the samples already drawn
    (an odd multiple, or a trapezoid grid) or is a fresh render at least 1.25x as large, and
    the frame is the same as a fresh render of that grid: to 1e-4, float32 rounding of a
    different summation order over hundreds of samples (4e-6 to 2e-5 seen), where a reused
    sample given a wrong weight would move an edge pixel by 1e-3 or more. Tuning seed 2 has a
    shutter other than the box (gaussian: the reuse must hold under it too) and seed 0 the box."""
    monkeypatch.setattr(auto_mod._Trials, "analytic_ms", lambda self, segments=None: float("inf"))
    for seed in (0, 2):
        scene = random_scene(seed, 64, 48)
        f = mb.render(scene, "auto", budget_ms=400.0)
        steps = _grids(f)
        assert steps[0] == (auto_mod.FIRST_SAMPLES, "stratified") and len(steps) >= 2, f.stats["plan"]
        for a, b in zip(steps, steps[1:], strict=False):
            grown = grids.holds(b, a) or (b[1] == "stratified" and b[0] >= 1.25 * a[0])
            assert grown and b[0] > a[0], steps
        fresh = auto_mod._Trials(scene, 1).accumulate(*steps[-1])
        assert np.abs(f.rgba - fresh.rgba).max() < 1e-4


def test_a_budget_smaller_than_the_first_render_returns_the_first_render():
    scene = random_scene(0, 64, 48)
    f = mb.render(scene, "auto", budget_ms=1e-3)
    assert _accumulations(f) == [auto_mod.FIRST_SAMPLES]
    assert f.stats["plan"]["kept"]["method"] == "accumulation"


def test_each_budget_step_draws_no_more_samples_than_fit():
    """`_budget_grid` over grids and rooms: the samples it draws (all of a fresh render's, the
    new ones of a grid that holds the drawn ones) are at most the room, it grows the frame, and
    it declines only where no grid or fresh render of 1.25x fits. A fresh render sized by the
    room plus the samples already drawn once overran 10 ms budgets by 1.2-1.6x."""
    cases = [
        (2, "stratified"),
        (4, "stratified"),
        (8, "stratified"),
        (12, "stratified"),
        (32, "trapezoid"),
        (24, "trapezoid"),
        (20, "stratified"),
        (2048, "trapezoid"),
        (4000, "stratified"),
    ]
    for grid in cases:
        have = grids.samples(grid)
        # rooms a hair under a whole count too: room + drawn once rounded up past it
        hairs = [math.nextafter(float(k), 0.0) for k in (4, 16, 49)]
        for room in [0.5, 1, 3, 7, 8, 9, 15, 21, 30, 47, 100, 333, 5000, *hairs]:
            nxt = auto_mod._budget_grid(grid, room)
            if nxt is None:
                least = grid[0] + (
                    grid[1] == "stratified"
                )  # the fewest new samples a grid that holds them draws
                most = grids.MAX_SAMPLES
                assert 2 * int(min(room, most) // 2) < 1.25 * have, (grid, room)
                assert min(room, most - have) < least, (grid, room)
                continue
            kept = grids.holds(nxt, grid)
            drawn = grids.samples(nxt) - (have if kept else 0)
            assert drawn <= room and grids.samples(nxt) > have, (grid, room, nxt)
            assert grids.samples(nxt) <= grids.MAX_SAMPLES + 1


def test_a_budget_under_a_rolling_shutter_raises_naming_budget_ms():
    """auto renders the exact analytic frame under a rolling shutter; it cannot plan a budget
    there, so it says so instead of returning a frame that may take many times the budget."""
    scene = random_scene(0, 32, 24).with_(rolling=0.5)
    with pytest.raises(ValueError, match=r"^budget_ms: .*rolling"):
        mb.render(scene, "auto", budget_ms=50.0)
