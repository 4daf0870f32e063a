"""auto's refined grids (`motionblur.methods._refine`): N stratified samples with a quarter or a
half of their strata's boundaries added, each sample weighted by its nearest-time cell, drawn
by keeping the N samples and reweighting them part by part.

Oracles: the nearest-time cells computed afresh from the sorted sample positions; a one-step
pixel's error in closed form; the same times and weights rendered at once; the trapezoid grid
of 2N strata rendered at once. Scenes: tuning seeds (< 100) of the random scene generator."""

from __future__ import annotations

import numpy as np
import pytest

import motionblur as mb
from motionblur.evaluation.random_scenes import random_scene
from motionblur.methods import _refine
from motionblur.methods import auto as auto_mod
from motionblur.methods._accumulate import HalfSums, shutter_quantiles

W, H = 64, 48
KINDS = list(_refine.KINDS)


def _grid_u(n: int, kind: str) -> tuple[np.ndarray, np.ndarray]:
    """(u, weights) of the refined grid's samples in shutter mass, sorted, from `_refine._nodes`."""
    weights, _ = _refine._nodes(n, kind)
    k = np.flatnonzero(weights > 0)  # the grid's samples: a node it lacks weighs 0
    return k / (2 * n), weights[k]


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("n", [8, 10, 12, 16, 30, 64])
def test_each_sample_weighs_its_nearest_time_cell(n, kind):
    """Every weight is the length of the samples' Voronoi cell in [0, 1] (half-way to each
    neighbour, the ends to 0 and 1), computed afresh; they sum to 1 and the sample count is
    `_refine.samples`."""
    u, w = _grid_u(n, kind)
    edges = np.concatenate([[0.0], 0.5 * (u[1:] + u[:-1]), [1.0]])
    np.testing.assert_allclose(w, np.diff(edges), atol=1e-15)
    assert len(u) == _refine.samples(n, kind) and abs(w.sum() - 1.0) < 1e-12


@pytest.mark.parametrize("kind", KINDS)
def test_a_pixel_that_steps_once_has_the_error_the_module_states(kind):
    """A pixel stepping from 0 to 1 at a uniformly random time s: a grid's value is the mass of
    its samples after s, the exact one 1 - s. RMS error over s (dense, exact to 1e-4) of the
    refined grid over the N-sample grid's: 0.90 (1/4) and 0.79 (1/2), as the module says; and
    the plain weights 1/count on the same times would be worse than the N-sample grid (why
    the weights are unequal)."""
    n = 16
    s = (np.arange(200_000) + 0.5) / 200_000

    def rms(u, w):
        after = np.searchsorted(u, s, side="right")
        tail = np.concatenate([np.cumsum(w[::-1])[::-1], [0.0]])
        return float(np.sqrt(np.mean(np.square(tail[after] - (1.0 - s)))))

    plain = rms((np.arange(n) + 0.5) / n, np.full(n, 1.0 / n))
    u, w = _grid_u(n, kind)
    ratio = rms(u, w) / plain
    assert ratio == pytest.approx({"refined 1/4": 0.90, "refined 1/2": 0.79}[kind], abs=0.01)
    assert rms(u, np.full(len(u), 1.0 / len(u))) > 1.02 * rms(u, w)


@pytest.mark.parametrize("n", [8, 12, 14, 16])
def test_a_refined_frame_is_its_times_and_weights_rendered_at_once(n):
    """auto's trials: N samples by residue, then 1/4, then 1/2 (drawing only the boundaries):
    each frame is the weighted mean of the grid's times rendered in one call (float32 rounding
    of different sums: 2e-6), draws only the new samples, and its estimate is the halves'
    (even cells with the 4i + 1 boundaries, odd cells with 4i + 3) at the grid's factor."""
    scene = random_scene(1, W, H).with_(shutter="box")
    trials = auto_mod._Trials(scene, 1)
    trials.accumulate(n)
    for kind in KINDS:
        before, parts = trials.sums.samples, len(trials.sums.parts)
        frame = trials.accumulate(n, kind)
        assert frame.stats["samples"] == _refine.samples(n, kind)
        assert trials.tried[-1]["options"] == {"samples": _refine.samples(n, kind), "grid": kind}
        weights, half = _refine._nodes(n, kind)
        k = np.flatnonzero(weights > 0)
        times = shutter_quantiles(scene.shutter, k / (2 * n))
        once = HalfSums(scene, 1, kind)
        for h in (0, 1):
            sel = half[k] == h
            for value in np.unique(weights[k][sel]):  # a part's samples weigh alike
                pick = sel & (weights[k] == value)
                once.add(times[pick], weights[k][pick], h)
        want = once.frame()
        np.testing.assert_allclose(frame.rgba, want.rgba, atol=2e-6)
        assert frame.stats["error_estimate"] == pytest.approx(want.stats["error_estimate"], rel=1e-4)
        # only the boundaries the grid lacked were drawn: each new part's times are boundaries
        drawn = np.concatenate([p.times for p in trials.sums.parts[parts:]])
        assert len(drawn) == _refine.samples(n, kind) - before
        bounds = shutter_quantiles(scene.shutter, np.arange(1, n) / n)
        assert np.isin(drawn, bounds).all()


def test_the_half_grid_completes_to_the_trapezoid_grid_of_twice_the_strata():
    """From 16 refined by half, the trapezoid grid of 32 strata keeps all 24 samples and draws
    the 9 others; the frame is the trapezoid grid rendered afresh (float32 rounding: 2e-6)."""
    scene = random_scene(3, W, H).with_(shutter="box")
    trials = auto_mod._Trials(scene, 1)
    trials.accumulate(16)
    trials.accumulate(16, "refined 1/2")
    kept = trials.accumulate(32, "trapezoid")
    assert kept.stats["samples"] == 33 and trials.sums.samples == 33
    fresh = auto_mod._Trials(scene, 1).accumulate(32, "trapezoid")
    np.testing.assert_allclose(kept.rgba, fresh.rgba, atol=2e-6)
    assert kept.stats["error_estimate"] == pytest.approx(fresh.stats["error_estimate"], rel=1e-4)


def test_a_grid_not_drawn_by_residue_refuses_to_be_refined():
    """accumulation's own halves (every other sample in one part) cannot be reweighted by
    residue: `refine` raises naming ``sums`` instead of weighting a part's samples wrongly."""
    scene = random_scene(1, W, H)
    sums = HalfSums(scene, 1)
    times = (np.arange(16) + 0.5) / 16
    sums.add_all([(times[h::2], np.full(8, 1 / 16), h) for h in (0, 1)])
    with pytest.raises(ValueError, match="sums"):
        _refine.refine(sums, scene, 16, "refined 1/4")


def test_an_odd_count_refuses_to_be_refined():
    # its last midpoint would weigh unlike its residue class
    with pytest.raises(ValueError, match="even"):
        _refine.refine(HalfSums(random_scene(1, W, H), 1), random_scene(1, W, H), 13, "refined 1/4")


def test_auto_refines_only_where_it_is_calibrated():
    """The trials draw by residue (and offer the refined grids) at aa 1 under the box shutter;
    at aa 2 and 4 and under any other shutter (where the refined grids' estimate read low on
    the tuning scenes) they do not, and auto keeps the doubling there."""
    scene = random_scene(1, W, H).with_(shutter="box")
    assert auto_mod._Trials(scene, 1).refines
    assert not auto_mod._Trials(scene, 2).refines and not auto_mod._Trials(scene, 4).refines
    for shutter in ("triangle", "ramp", "gaussian", np.array([1.0, 0.0, 1.0])):
        assert not auto_mod._Trials(scene.with_(shutter=shutter), 1).refines, shutter
    f = mb.render(scene.with_(shutter="triangle"), "auto", tolerance=0.002)
    assert not any("refined" in t["options"].get("grid", "") for t in f.stats["plan"]["tried"])


@pytest.mark.parametrize("seed", [11, 20, 26])
def test_a_refined_frame_meets_the_tolerance_auto_kept_it_for(seed):
    """Where auto keeps a refined grid on a tuning scene, its measured error against the exact
    integral is under the tolerance (auto aims its estimate at 0.95 of it)."""
    scene = random_scene(seed, 96, 72)
    ref = mb.exact(scene).rgba.astype(np.float64)
    bg = np.asarray(scene.background)
    kept = 0
    for tol in (0.01, 0.004, 0.002):
        f = mb.render(scene, "auto", tolerance=tol)
        if f.stats["plan"]["kept"]["options"].get("grid", "") not in _refine.KINDS:
            continue
        kept += 1
        over = f.rgba + (1 - f.rgba[..., 3:]) * np.r_[bg[:3] * bg[3], bg[3]]
        assert np.sqrt(np.mean(np.square(over - ref))) <= tol, f.stats["plan"]
    assert kept, f"seed {seed}: no refined frame kept at 0.01, 0.004 or 0.002; pick another seed"
