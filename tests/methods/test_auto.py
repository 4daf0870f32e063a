"""The planner controls its error by measurement: what it returns meets the tolerance against the
exact integral, a tighter tolerance gives a smaller error, the plan says what was tried, and a
budget is measured against the clock.

The scenes here are the built-in ones and seeded random scenes of the *tuning* set (seeds < 100):
auto's constants were chosen on that set, so these tests pin its behaviour there; the figures
on the measuring set are the README's (``benches/bench_error_control.py``) and the differential
test's (``tests/robustness/test_differential.py``)."""

from __future__ import annotations

import numpy as np
import pytest

import motionblur as mb
from motionblur.evaluation.random_scenes import random_scene
from motionblur.methods import auto as auto_mod
from motionblur.methods._sweep import sweep_scale
from motionblur.scene import rotate, translate

W, H = 64, 48


def _rmse(a, b) -> float:
    return float(np.sqrt(np.mean(np.square(np.asarray(a, np.float64) - b))))


def test_auto_meets_its_tolerance_on_built_in_scenes_at_sizes_it_was_not_fitted_at():
    """The old model-based planner missed 0.01 on 10 of 11 built-in scenes at 64x48 and 160x120
    (airplane 0.041, curved 0.033). Now, on 4 built-in scenes at both sizes and 2 tolerances:
    every frame within 1.5x its tolerance (the bound auto holds on every scene), its estimate
    under the tolerance (what auto stops on), and at least 15 of the 16 under the tolerance
    (auto aims its estimate at the tolerance itself at ``aa`` 1: the estimate's spread lets a
    few frames in a hundred over; curved at 160x120 and 0.003 reads 1.01x)."""
    met, cases = 0, 0
    for name in ("cube", "airplane", "curved", "pan"):
        for size in ((64, 48), (160, 120)):
            scene = mb.SCENES[name](*size)
            ref = mb.exact(scene).rgba
            for tol in (0.01, 0.003):
                f = mb.render(scene, "auto", tolerance=tol)
                err = _rmse(f.rgba, ref)
                assert err <= 1.5 * tol, (name, size, tol, f.stats["plan"])
                assert f.stats["error_estimate"] <= tol
                met, cases = met + (err <= tol), cases + 1
    assert cases == 16 and met >= 15, (met, cases)


def test_a_tighter_tolerance_gives_a_measurably_smaller_error():
    scene = random_scene(3, W, H)
    ref = mb.exact(scene).rgba
    errs = [_rmse(mb.render(scene, "auto", tolerance=t).rgba, ref) for t in (0.01, 0.0025, 0.0006)]
    # (at 0.0006 the analytic frame may be predicted cheaper: 0 off mb.exact on this scene)
    assert errs[0] > 2 * errs[1] > 4 * errs[2] >= 0 and errs[2] <= 0.0006, errs


def test_shutter_weights_are_honoured_not_collapsed_to_one_sample():
    """Weights [0, 0, 1, 1] once gave exactly the sharp frame at t = 0.75 (2 samples, the first
    weighing 0). Now the frame is the integral over the open half, within the tolerance."""
    scene = mb.SCENES["cube"](W, H).with_(shutter=np.array([0.0, 0.0, 1.0, 1.0]))
    ref = mb.exact(scene).rgba
    f = mb.render(scene, "auto", tolerance=0.004)
    sharp = mb.render(scene.with_(shutter="box", camera_motion=None), "accumulation", samples=1).rgba
    assert _rmse(f.rgba, ref) <= 0.004
    assert _rmse(sharp, ref) > 3 * _rmse(f.rgba, ref)


def test_the_plan_lists_every_render_and_why_the_last_was_kept():
    scene = random_scene(5, W, H)
    f = mb.render(scene, "auto", tolerance=0.002)
    plan = f.stats["plan"]
    assert plan["goal"] == "tolerance" and plan["tolerance"] == 0.002
    sweep = sweep_scale(scene)
    first = auto_mod.first_samples(0.002, sweep)
    forecast = {"pilot": f"forecast: sweep {sweep:.3g}, {first} samples"}
    assert plan["tried"][0] == {**plan["tried"][0], "method": "accumulation", "options": forecast}
    assert plan["tried"][1] == {**plan["tried"][1], "method": "accumulation", "options": {"samples": first}}
    assert plan["kept"]["method"] == plan["tried"][-1]["method"]
    assert plan["why"] and f.stats["error_estimate"] == plan["tried"][-1]["error_estimate"]
    assert all(t["ms"] >= 0 for t in plan["tried"])


def test_refined_samples_are_the_same_frame_as_rendering_them_at_once():
    """Under a box shutter auto keeps the samples it drew when it goes to an odd multiple of the
    count: the frame equals accumulation with that count (to float32 rounding of the sums)."""
    scene = random_scene(1, W, H)
    trials = auto_mod._Trials(scene, 1)
    trials.accumulate(4)
    kept = trials.accumulate(12)
    fresh = mb.METHODS["accumulation"].fn(scene, samples=12)
    np.testing.assert_allclose(kept.rgba, fresh.rgba, atol=2e-6)
    assert kept.stats["error_estimate"] == pytest.approx(fresh.stats["error_estimate"], rel=1e-4)
    assert kept.stats["draw_calls"] == 12


def test_nothing_moving_is_one_sharp_frame_with_no_error():
    scene = mb.SCENES["cube"](W, H)
    still = scene.with_(
        objects=[mb.Object((o.world_vertices(0.0), o.mesh.faces), o.color) for o in scene.objects]
    )
    f = mb.render(still, "auto", tolerance=1e-3)
    assert f.stats["plan"]["tried"] == [{**f.stats["plan"]["tried"][0], "options": {"samples": 1}}]
    assert f.stats["error_estimate"] == 0.0
    assert _rmse(f.rgba, mb.exact(still).rgba) < 1e-6


def test_a_tolerance_below_accumulations_reach_is_the_exact_integral():
    scene = mb.SCENES["cube"](W, H)
    f = mb.render(scene, "auto", tolerance=1e-4)
    assert f.stats["plan"]["kept"]["method"] == "analytic"
    assert _rmse(f.rgba, mb.exact(scene).rgba) < 1e-4


def test_a_budget_is_measured_against_the_clock_and_more_time_buys_accuracy():
    scene = random_scene(7, W, H)
    ref = mb.exact(scene).rgba
    mb.render(scene, "auto", budget_ms=5.0)  # warm the static layer
    small = mb.render(scene, "auto", budget_ms=5.0)
    large = mb.render(scene, "auto", budget_ms=200.0)
    assert small.stats["plan"]["goal"] == "budget"
    assert _rmse(large.rgba, ref) < _rmse(small.rgba, ref)
    assert (
        large.stats["plan"]["kept"]["options"].get("samples", 10**9)
        > small.stats["plan"]["kept"]["options"]["samples"]
    )


@pytest.mark.parametrize(
    "kw, msg",
    [
        ({"tolerance": 0.01, "budget_ms": 5.0}, "one of them"),
        ({"tolerance": 0.0}, "tolerance"),
        ({"tolerance": float("nan")}, "tolerance"),
        ({"budget_ms": -1.0}, "budget_ms"),
    ],
)
def test_bad_options_name_the_argument(kw, msg):
    with pytest.raises(ValueError, match=msg):
        mb.render(mb.SCENES["cube"](W, H), "auto", **kw)


def test_the_model_option_is_gone_and_says_so():
    with pytest.raises(TypeError, match="model"):
        mb.render(mb.SCENES["cube"](W, H), "auto", model="x.json")


@pytest.mark.parametrize("seed", [0, 69])
def test_translucent_layered_scenes_keep_accumulation_and_meet_the_tolerance(seed):
    """Accumulation once merged shading modes (and static and moving objects) as layers with
    one depth a pixel, a bias its halves could not see, so auto took the analytic frame there
    (22-160x the cheapest render's time). It now draws such scenes exactly
    (tests/methods/test_accumulation_translucency.py): auto keeps accumulation, within its
    tolerance, on these tuning scenes where the old limit was 5.9e-4 and 6.7e-4 off."""
    scene = random_scene(seed, W, H)
    assert auto_mod.layered_translucency(scene)
    ref = mb.exact(scene).rgba
    for tol in (0.004, 0.001):
        f = mb.render(scene, "auto", tolerance=tol)
        assert f.stats["plan"]["kept"]["method"] == "accumulation", f.stats["plan"]
        assert _rmse(f.rgba, ref) <= tol, (tol, f.stats["plan"])


def test_refinement_draws_only_the_new_samples():
    """From 6 samples to 18 (an odd multiple: the 6 are on its grid, `_grids.next_grid`), drawing
    12 more: the frame is accumulation's with 18 samples (to float32 rounding of the sums) and
    so is its estimate."""
    scene = random_scene(1, W, H)
    trials = auto_mod._Trials(scene, 1)
    trials.accumulate(6)
    kept = trials.accumulate(18)
    fresh = mb.METHODS["accumulation"].fn(scene, samples=18)
    assert kept.stats["draw_calls"] == 18 and kept.stats["samples"] == 18
    np.testing.assert_allclose(kept.rgba, fresh.rgba, atol=2e-6)
    assert kept.stats["error_estimate"] == pytest.approx(fresh.stats["error_estimate"], rel=1e-4)


@pytest.mark.parametrize("shutter", ["box", "triangle", np.array([0.0, 0.0, 1.0, 1.0])], ids=str)
def test_the_trapezoid_grid_keeps_the_drawn_samples_and_is_the_trapezoid_rule(shutter):
    """12 stratified samples, then the trapezoid grid of 24 strata (25 samples: 13 drawn), then
    of 72 (73: 48 drawn): the frame is the trapezoid rule over the shutter's mass (times
    W^-1(k / 72), weights 1/72, the ends 1/144), rendered at once, and its error against the
    exact integral falls as the samples grow."""
    from motionblur.methods._accumulate import HalfSums, shutter_quantiles

    scene = random_scene(1, W, H).with_(shutter=shutter)
    trials = auto_mod._Trials(scene, 1)
    trials.accumulate(12)
    mid = trials.accumulate(24, "trapezoid")
    assert mid.stats["draw_calls"] == 25 and trials.tried[-1]["options"] == {
        "samples": 25,
        "grid": "trapezoid",
    }
    kept = trials.accumulate(72, "trapezoid")
    assert kept.stats["draw_calls"] == 73 and kept.stats["samples"] == 73
    k = np.arange(73)
    times, weights = shutter_quantiles(scene.shutter, k / 72), np.full(73, 1 / 72)
    weights[[0, -1]] = 1 / 144
    once = HalfSums(scene, 1, "trapezoid")
    for half in (0, 1):
        once.add(times[half::2], weights[half::2], half)
    want = once.frame()
    np.testing.assert_allclose(kept.rgba, want.rgba, atol=2e-6)
    assert kept.stats["error_estimate"] == pytest.approx(want.stats["error_estimate"], rel=1e-4)
    ref = mb.exact(scene).rgba
    first = mb.METHODS["accumulation"].fn(scene, samples=12)
    bg = np.asarray(scene.background)
    over = lambda f: f.rgba + (1 - f.rgba[..., 3:]) * np.r_[bg[:3] * bg[3], bg[3]]  # noqa: E731
    errs = [_rmse(over(f), ref) for f in (first, mid, kept)]
    assert errs[0] > errs[1] > errs[2], errs


@pytest.mark.parametrize("seed", [8, 11, 15])
def test_auto_under_a_shutter_closed_in_the_middle_meets_its_tolerance(seed):
    """A weights shutter [1, 0, 0, 1] (two exposures): auto's refinements on the trapezoid grid
    split the node at the gap (above), so their halves see the jump and the frame meets the
    tolerance; a tighter tolerance gives a smaller error. (With the gap's left end alone these
    tuning scenes missed: 1.11x, 1.15x at 0.001, 1.15x at 0.004; 8 of 60 calls on seeds 0-29.)"""
    scene = random_scene(seed, W, H).with_(shutter=np.array([1.0, 0.0, 0.0, 1.0]))
    ref = mb.exact(scene).rgba
    frames = {tol: mb.render(scene, "auto", tolerance=tol) for tol in (0.004, 0.001)}
    err = {tol: _rmse(f.rgba, ref) for tol, f in frames.items()}
    assert all(err[tol] <= tol for tol in err), err
    assert err[0.001] < err[0.004], err


def test_without_a_forecast_the_first_render_is_sized_by_the_tolerance():
    """The rule before the forecast (kept for comparison in the benches) follows the tolerance."""
    assert [auto_mod.first_samples(t) for t in (0.03, 0.0133, 0.01, 0.004, 0.001)] == [4, 6, 8, 8, 8]


@pytest.mark.parametrize("aa", [1, 2, 4])
@pytest.mark.parametrize("sweep", [0.0, 1e-3, 0.05, 0.4, 3.0, 1e3])
def test_the_forecast_picks_the_fewest_samples_it_expects_to_meet_its_aim(sweep, aa):
    """The count is the fewest even one whose forecast error at ``aa`` is at most FIRST_AIM x the
    tolerance, times sqrt(N / SURE_SAMPLES) under SURE_SAMPLES (the share auto holds so few
    samples' estimate to), 2 to FIRST_MOST, and never falls as the tolerance tightens or the
    sweep grows."""
    c0, c1, c2 = auto_mod.FIRST_FIT[aa]

    def fits(n, tol):
        aim = auto_mod.FIRST_AIM * tol * min(1.0, np.sqrt(n / auto_mod.SURE_SAMPLES))
        return np.exp(c0) * sweep**c1 * n**c2 <= aim

    last = 0
    for tol in (0.03, 0.01, 0.004, 0.001, 1e-4):
        n = auto_mod.first_samples(tol, sweep, aa)
        assert n % 2 == 0 and 2 <= n <= auto_mod.FIRST_MOST and n >= last, (tol, n)
        if 2 < n < auto_mod.FIRST_MOST:
            assert fits(n, tol) and not fits(n - 2, tol), (tol, n)
        last = n
    assert auto_mod.first_samples(0.004, sweep, aa) <= auto_mod.first_samples(0.004, 2 * sweep + 1e-3, aa)


@pytest.mark.parametrize("aa", [2, 4])
def test_auto_at_aa_2_and_4_sizes_its_first_render_from_the_forecast_at_that_aa(aa):
    scene = random_scene(5, W, H)
    plan = mb.render(scene, "auto", tolerance=0.004, aa=aa).stats["plan"]
    first = auto_mod.first_samples(0.004, sweep_scale(scene), aa)
    assert plan["tried"][0]["options"]["pilot"].endswith(f", {first} samples")
    assert plan["tried"][1]["options"] == {"samples": first}


@pytest.mark.parametrize("tol", [0.01, 0.002])
def test_at_aa_4_the_plan_certifies_by_the_halves_reading_and_the_frame_states_the_estimate(monkeypatch, tol):
    # Tuning seed 9: outlines travelling about 8 pixels, where the reading at aa 4 over-reads
    # (`_accumulate.RESONANCE`). auto's aims were chosen on the reading, so its plan is the one
    # it makes without the resonance, and the frame carries the estimate, the reading over it.
    from motionblur.methods import _accumulate
    from motionblur.methods._sweep import sweep_path

    scene = random_scene(9, W, H)
    frame = mb.render(scene, "auto", tolerance=tol, aa=4)
    tried = [t for t in frame.stats["plan"]["tried"] if "samples" in t["options"]]
    for t in tried:  # the stratified grids (the trapezoid's estimate is its reading)
        stratified = "grid" not in t["options"]
        bump = _accumulate.resonance(t["options"]["samples"], sweep_path(scene), 4) if stratified else 1.0
        assert t["error_estimate"] == pytest.approx(t["halves_reading"] / bump, rel=1e-12)
    assert frame.stats["error_estimate"] == tried[-1]["error_estimate"] < tried[-1]["halves_reading"]
    monkeypatch.setattr(_accumulate, "RESONANCE", {})
    read = mb.render(scene, "auto", tolerance=tol, aa=4)
    assert [t["options"] for t in read.stats["plan"]["tried"]] == [
        t["options"] for t in frame.stats["plan"]["tried"]
    ]
    assert np.array_equal(read.rgba, frame.rgba)


@pytest.mark.parametrize(
    "shutter", ["triangle", "gaussian", np.array([0.0, 0.0, 1.0, 1.0]), mb.Trapezoid(0.3, 0.2)]
)
def test_refinement_keeps_the_drawn_samples_under_any_shutter(shutter):
    """Accumulation's samples cut the shutter's mass into equal strata, so under a shutter other
    than the box too an odd multiple of the count keeps the samples drawn (once such a shutter
    rendered afresh at every step): 8 then 24 draws 24 times in all, and the frame is
    accumulation's with 24 samples."""
    scene = random_scene(1, W, H).with_(shutter=shutter)
    trials = auto_mod._Trials(scene, 1)
    trials.accumulate(8)
    kept = trials.accumulate(24)
    assert kept.stats["draw_calls"] == 24 and kept.stats["samples"] == 24
    fresh = mb.METHODS["accumulation"].fn(scene, samples=24)
    np.testing.assert_allclose(kept.rgba, fresh.rgba, atol=2e-6)
    assert kept.stats["error_estimate"] == pytest.approx(fresh.stats["error_estimate"], rel=1e-4)
    ref = mb.exact(scene).rgba
    err = [_rmse(mb.render(scene, "auto", tolerance=tol).rgba, ref) for tol in (0.01, 0.002)]
    assert err[1] <= 0.002 and err[0] <= 0.01 and err[1] < err[0], err


@pytest.mark.parametrize("seed, aa", [(0, 1), (3, 2), (6, 1), (11, 4)])
def test_accumulations_never_write_into_the_kept_static_layer_nor_share_a_frame(monkeypatch, seed, aa):
    """Accumulation's pieces read the static layer kept across frames (read-only by contract)
    and paste a frame only when one is returned: with that layer's arrays made read-only, plain
    accumulation and auto's refinements render (a write would raise), their frames are
    writeable, share no memory with the layer, and two frames of one refinement share none
    with each other. Tuning seeds 0-11 hold still and moving cameras, static objects and not."""
    from motionblur.methods import _accumulate, clear_static_cache

    kept = []
    layer_of = _accumulate.static_layer

    def read_only(*args, **kwargs):
        st = layer_of(*args, **kwargs)
        for a in (st.rgba, st.depth, st.ids, st.layer.rgba, st.layer.depth, st.layer.ids):
            a.flags.writeable = False
            kept.append(a)
        return st

    clear_static_cache()
    monkeypatch.setattr(_accumulate, "static_layer", read_only)
    try:
        scene = random_scene(seed, 48, 36)
        frames = [mb.render(scene, "accumulation", samples=6, aa=aa)]
        trials = auto_mod._Trials(scene, aa)
        frames += [trials.accumulate(8), trials.accumulate(16, "trapezoid")]
        for f in frames:
            for a in (f.rgba, f.depth, f.ids):
                assert a.flags.writeable
                assert not any(np.shares_memory(a, k) for k in kept)
        for a, b in zip(*[(f.rgba, f.depth, f.ids) for f in frames[1:]], strict=True):
            assert not np.shares_memory(a, b)
    finally:
        clear_static_cache()


@pytest.mark.parametrize("aa", [0, 3, 8])
def test_auto_names_aa_when_it_is_not_1_2_or_4(aa):
    """``aa`` is checked before the forecast reads its fit (a KeyError there, unchecked)."""
    scene = random_scene(5, W, H)
    for goal in ({"tolerance": 0.01}, {"budget_ms": 50.0}):
        with pytest.raises(ValueError, match="aa"):
            mb.render(scene, "auto", aa=aa, **goal)
    with pytest.raises(ValueError, match="aa"):
        auto_mod.first_samples(0.01, 0.1, aa)


@pytest.mark.parametrize("first, m", [(6, 12), (6, 24), (10, 20)])
def test_keeping_samples_at_a_closed_gap_gives_the_trapezoid_grid_rendered_afresh(first, m):
    """Under a weights shutter closed in the middle ([1, 2, 0, 1]: the mass reaches the gap at
    0.75), a stratified midpoint of 6 or 10 samples lands on the gap's node, which the trapezoid
    grid splits into two samples of half its weight. Its part, summed with equal weights, cannot
    give one sample half the weight of the others: the trials render the trapezoid grid afresh
    instead, so the frame is the one a fresh render gives (float32 sums: 2e-6; keeping the
    sample had put 0.014-0.028 on a pixel)."""
    scene = random_scene(1, W, H).with_(shutter=np.array([1.0, 2.0, 0.0, 1.0]))
    trials = auto_mod._Trials(scene, 1)
    trials.accumulate(first)
    kept = trials.accumulate(m, "trapezoid")
    fresh = auto_mod._Trials(scene, 1).accumulate(m, "trapezoid")
    np.testing.assert_allclose(kept.rgba, fresh.rgba, atol=2e-6)
    assert kept.stats["error_estimate"] == pytest.approx(fresh.stats["error_estimate"], rel=1e-4)


def test_auto_renders_an_object_with_a_colour_a_vertex():
    # the forecast's contrast reads one colour an object or one a vertex (it took one colour
    # only, and auto raised a TypeError on per-vertex colours); the frame meets its tolerance
    v, f = mb.meshes.icosphere(2)
    v = np.asarray(v)
    colours = np.c_[(v + 1) / 2, np.ones(len(v))].astype(np.float32)
    motion = mb.Motion.linear(np.eye(4), rotate(0.6, (0, 1, 0)) @ translate((0.8, 0, 0)))
    cam = mb.Camera(mb.look_at((0.0, 0.3, 5.0), (0.0, 0.0, 0.0)), 0.7, W, H, znear=0.5, zfar=30.0)
    scene = mb.Scene([mb.Object(mb.Mesh(v * 0.6, f), color=colours, motion=motion)], cam)
    for aa in (1, 4):
        frame = mb.render(scene, "auto", tolerance=0.004, aa=aa)
        assert _rmse(frame.rgba, mb.exact(scene, aa=aa).rgba) <= 0.004
