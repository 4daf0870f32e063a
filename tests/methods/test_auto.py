"""The auto planner: what it draws sharp, what it picks for a tolerance or a budget, how it
composes groups planned apart, and the fit of its model."""

from __future__ import annotations

import numpy as np
import pytest

import motionblur as mb
from motionblur.evaluation import autofit
from motionblur.methods import auto as auto_mod
from motionblur.methods._auto_model import Model, error_terms, time_terms
from motionblur.methods._features import FEATURES, group_features

W, H = 64, 48


def _model(cands, margin=0.0) -> Model:
    """Candidates given as (method, options, predicted rmse, predicted ms): constant models."""
    out = []
    for method, opts, e, t in cands:
        out.append({"method": method, "options": opts, "n": 9, "error_coef": [float(np.log(e))] + [0.0] * 9,
                    "error_sigma": 0.5, "time_coef": [float(np.log(t))] + [0.0] * 7, "time_sigma": 0.5})  # fmt: skip
    return Model({"version": 1, "aa": 1, "margin": margin, "size": [W, H], "candidates": out})


CANDS = [
    ("accumulation", {"samples": 4}, 0.02, 2.0),
    ("accumulation", {"samples": 64}, 0.002, 30.0),
    ("motion_volume", {"segments": 2}, 0.008, 3.0),
    ("analytic", {}, 0.001, 200.0),
]


def _cube(motion=(1.0, 0.0, 0.0), x=0.0, color=(0.9, 0.3, 0.1)):
    return mb.Object(mb.meshes.box((0.4, 0.4, 0.4)), color,
                     motion=mb.Motion.linear([x - motion[0] / 2, 0, 0], [x + motion[0] / 2, motion[1], motion[2]]))  # fmt: skip


def _scene(*objects):
    cam = mb.Camera(mb.look_at((0, 0, 4), (0, 0, 0)), 0.8, W, H)
    v, f = mb.meshes.box((6, 0.1, 3))
    return mb.Scene([*objects, mb.Object((v + (0, -0.6, -1), f), (0.3, 0.3, 0.3))], cam)


def test_the_cheapest_candidate_meeting_the_tolerance_and_the_most_accurate_within_a_budget():
    sc = _scene(_cube())
    m = _model(CANDS)
    pick = lambda **kw: auto_mod.plan(sc, model=m, **kw)[1][0][:2]  # noqa: E731
    assert pick(tolerance=0.01) == ("motion_volume", {"segments": 2})
    assert pick(tolerance=0.005) == ("accumulation", {"samples": 64})
    assert pick(tolerance=1e-4) == ("analytic", {})  # none meets it: the most accurate
    assert pick(budget_ms=2.5) == ("accumulation", {"samples": 4})
    assert pick(budget_ms=50.0) == ("accumulation", {"samples": 64})
    assert pick(budget_ms=0.1) == ("accumulation", {"samples": 4})  # nothing fits: the fastest
    # the margin (residual sds) makes the planner careful: 0.008 * e^0.5 > 0.01
    careful = auto_mod.plan(sc, tolerance=0.01, model=_model(CANDS, margin=1.0))[1][0][:2]
    assert careful == ("accumulation", {"samples": 64})
    # a method that does not apply is never chosen: motion_volume on a deforming object
    pos = np.stack([sc.objects[0].world_vertices(t) * (1 + t) for t in (0.0, 1.0)])
    deforming = sc.with_(objects=[mb.Object((pos[0], sc.objects[0].mesh.faces), motion=mb.Motion.deforming([0, 1], pos)),
                                  sc.objects[1]])  # fmt: skip
    assert auto_mod.plan(deforming, tolerance=0.01, model=m)[1][0][0] == "accumulation"
    with pytest.raises(ValueError, match="not both"):
        auto_mod.plan(sc, tolerance=0.01, budget_ms=3.0, model=m)


def test_still_and_sub_pixel_objects_are_drawn_sharp_once_and_the_plan_says_why():
    slow = _cube(motion=(1e-4, 0.0, 0.0), x=-0.8)
    sc = _scene(slow, _cube(x=0.8))
    prepared, choices, plan = auto_mod.plan(sc, tolerance=0.01, model=_model(CANDS))
    objs = plan["objects"]
    assert objs["object0"]["method"] == "static" and "px" in objs["object0"]["reason"]
    assert objs["object2"]["method"] == "static" and "does not move" in objs["object2"]["reason"]
    assert objs["object1"]["method"] == "motion_volume" and "cheapest" in objs["object1"]["reason"]
    assert (
        set(objs["object1"]["features"]) == {*FEATURES, "probe_ms"}
        and objs["object1"]["features"]["motion_px"] > 5
    )
    assert not prepared.objects[0].is_moving and [k for _, _, ks in choices for k in ks] == [1]
    np.testing.assert_allclose(prepared.objects[0].mesh.vertices, slow.world_vertices(sc.reference_t))


def test_a_tolerance_plan_times_nothing_and_a_budget_plan_probes_the_scene(monkeypatch):
    """A plan for a tolerance must not depend on the machine's load (the report compares runs in
    different processes): it uses the fit's median probe; a time budget measures one sample."""
    sc = _scene(_cube(x=0.0))
    m = _model(CANDS)
    m.data["probe_ms"] = 7.5
    timed = []
    real = auto_mod._probe_ms
    monkeypatch.setattr(auto_mod, "_probe_ms", lambda scene, aa: timed.append(real(scene, aa)) or timed[-1])
    plan = auto_mod.plan(sc, tolerance=0.01, model=m)[2]
    assert not timed and plan["objects"]["object0"]["features"]["probe_ms"] == 7.5
    plan = auto_mod.plan(sc, budget_ms=50.0, model=m)[2]
    assert len(timed) == 1 and plan["objects"]["object0"]["features"]["probe_ms"] == round(timed[0], 4) > 0


def test_groups_planned_apart_compose_like_each_rendered_alone(monkeypatch):
    """Two movers far apart, one planned for accumulation and one for motion volume: the frame is
    the static frame plus each group's difference, so each region equals that method's render."""
    left, right = _cube(motion=(0.3, 0, 0), x=-1.1), _cube(motion=(0.3, 0, 0), x=1.1, color=(0.1, 0.4, 0.9))
    sc = _scene(left, right)
    m = _model(CANDS)
    real_choose = Model.choose

    def by_side(self, f, *a):
        pick = real_choose(self, f, *a)
        if f["coverage_px"] and by_side.calls == 0:
            pick = {**pick, "method": "accumulation", "options": {"samples": 8}}
        by_side.calls += 1
        return pick

    by_side.calls = 0
    monkeypatch.setattr(Model, "choose", by_side)
    monkeypatch.setattr(auto_mod, "load_model", lambda: m)
    frame = mb.render(sc, "auto", tolerance=0.01)
    chosen = {k: v["method"] for k, v in frame.stats["plan"]["objects"].items()}
    assert sorted(chosen.values()) == ["accumulation", "motion_volume", "static"]
    acc_only = mb.render(sc.with_(objects=[left, sc.objects[2]]), "accumulation", samples=8)
    mv_only = mb.render(sc.with_(objects=[right, sc.objects[2]]), "motion_volume", segments=2)
    half = W // 2
    np.testing.assert_allclose(frame.rgba[:, :half], acc_only.rgba[:, :half], atol=1e-6)
    np.testing.assert_allclose(frame.rgba[:, half:], mv_only.rgba[:, half:], atol=1e-6)
    assert set(np.unique(frame.ids[:, :half])) <= {-1, 0, 2} and 1 in frame.ids[:, half:]


def test_the_fit_recovers_a_known_model_and_its_leave_one_out_spread(rng):
    feats, rows = {}, []
    true_e = np.array([-6.0, 0.8, 0.0, 0.3, 0.0, 0.5, 1.5, 0.0, 0.0, 0.0])
    true_t = np.array([0.5, 1.0, 0.4, 0.1, 0.0, 0.0, 0.0, 0.0])
    for i in range(30):
        f = {"motion_px": rng.uniform(5, 300), "tri_px": rng.uniform(0.5, 50), "faces": rng.uniform(10, 1e5),
             "rotation": rng.uniform(0, 2), "spread": rng.uniform(0, 1), "concavity": rng.uniform(0, 0.5),
             "hollowness": rng.uniform(0, 0.8), "probe_ms": rng.uniform(0.5, 20),
             "coverage_px": rng.uniform(1e3, 5e4), "deforming": 0.0, "camera_moves": 0.0}  # fmt: skip
        feats[f"s{i}"] = f
        noise = rng.normal(0, 0.05, 2)
        rows.append({"scene": f"s{i}", "method": "accumulation", "_opts": {"samples": 8, "aa": 2},
                     "ms": float(np.exp(true_t @ time_terms(f) + noise[0])),
                     "rmse_limit": float(np.exp(true_e @ error_terms(f) + noise[1]))})  # fmt: skip
    model = autofit.fit(rows, feats, aa=2, size=(W, H))
    (c,) = model.candidates
    assert c["options"] == {"samples": 8} and c["n"] == 30  # the run's aa left out
    f = feats["s3"]
    _, le, lt = model.predict(f)[0]
    assert le == pytest.approx(true_e @ error_terms(f), abs=0.15)
    assert lt == pytest.approx(true_t @ time_terms(f), abs=0.15)
    assert 0.03 < c["error_sigma"] < 0.2 and 0.03 < c["time_sigma"] < 0.2


def test_auto_renders_with_the_packaged_model_and_keeps_its_plan_with_the_scene():
    sc = mb.SCENES["cube"](W, H)
    a = mb.render(sc, "auto", aa=1)
    plan = a.stats["plan"]
    assert plan["goal"] == "tolerance" and plan["tolerance"] == auto_mod.DEFAULT_TOLERANCE
    chosen = plan["objects"]["cube"]
    assert chosen["method"] in mb.METHODS and chosen["predicted_ms"] > 0
    again = mb.render(sc, "auto", aa=1)
    assert again.stats["plan"] is plan  # planned once for this scene object
    np.testing.assert_array_equal(a.rgba, again.rgba)
    direct = mb.render(sc, chosen["method"], **{**chosen["options"], "aa": 1})
    np.testing.assert_array_equal(a.rgba, direct.rgba)
    assert group_features(sc, [(0, sc.objects[0])])["motion_px"] == pytest.approx(
        chosen["features"]["motion_px"], rel=1e-3
    )


def test_the_margin_is_the_smallest_that_meets_the_tolerance_when_each_scene_is_left_out(rng):
    """Two candidates: a cheap one whose error wanders around 0.008 from scene to scene and an
    accurate dear one; with no margin the planner trusts the cheap one and misses 0.01 on the
    scenes where it wanders up, and the calibrated margin is the least that fixes that."""
    feats, rows, applies = {}, [], {}
    for i in range(20):
        f = {"motion_px": rng.uniform(20, 200), "tri_px": 4.0, "faces": 1000.0, "rotation": 0.0, "spread": 0.1,
             "concavity": 0.0, "hollowness": 0.0, "coverage_px": 1e4, "deforming": 0.0, "camera_moves": 0.0,
             "probe_ms": 1.0}  # fmt: skip
        feats[f"s{i}"], applies[f"s{i}"] = f, {"accumulation": True}
        cheap = 0.008 * float(np.exp(rng.normal(0, 0.3)))
        rows += [{"scene": f"s{i}", "method": "accumulation", "_opts": {"samples": 4}, "ms": 1.0, "rmse_limit": cheap},
                 {"scene": f"s{i}", "method": "accumulation", "_opts": {"samples": 64}, "ms": 10.0, "rmse_limit": 0.001}]  # fmt: skip
    margin, met = autofit.calibrate_margin(rows, feats, 2, (W, H), applies)
    assert met[0.0] < 0.95 <= met[margin]
    assert all(met[m] < 0.95 for m in met if m < margin)
    loo = autofit.leave_one_out(rows, feats, 2, (W, H), 0.01, applies, margin=margin)
    assert sum(x["meets"] for x in loo.values()) >= 0.95 * len(loo)


def test_the_plan_renders_the_scene_shutter_never_another_filter():
    """The model holds motion-volume candidates with other filters (the report's looks): a plan
    for a box-shutter scene never picks one, nor any filter for a scene with custom weights."""
    for shutter in ("box", "triangle", [1.0, 3.0, 1.0]):
        sc = mb.SCENES["cube"](64, 48).with_(shutter=shutter)
        for goal in ({"tolerance": 0.05}, {"tolerance": 0.001}, {"budget_ms": 1.0}, {"budget_ms": 1e4}):
            for method, opts, _ in auto_mod.plan(sc, **goal)[1]:
                want = shutter if isinstance(shutter, str) else None
                assert opts.get("filter", want) == want, (shutter, goal, method, opts)
