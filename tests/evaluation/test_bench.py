"""The speed-against-error report: Pareto front, equal-error interpolation, outputs of a tiny run."""

from __future__ import annotations

import csv
import math

import pytest

import motionblur as mb
from motionblur.evaluation import bench, compare, sweep


def _row(method, ms, rmse, options="-"):
    return {"scene": "s", "method": method, "options": options, "ms": ms, "rmse": rmse}


def test_pareto_front_keeps_the_undominated_rows():
    rows = [_row("a", 1, 0.5), _row("a", 2, 0.1), _row("b", 3, 0.2), _row("b", 0.5, 0.9), _row("a", 2, 0.1)]
    assert compare.pareto_front(rows) == [True, True, False, True, True]


def test_equal_error_interpolates_log_log_and_marks_bounds():
    rows = [
        _row("accumulation", 1.0, 0.1),
        _row("accumulation", 4.0, 0.01),
        _row("accumulation", 16.0, 0.001),
    ]
    rows += [_row("motion_volume", 0.5, math.sqrt(0.1 * 0.01), "mid")]  # halfway in log error
    rows += [_row("motion_volume", 0.5, 0.5, "worse"), _row("motion_volume", 2.0, 0.0001, "better")]
    out = {r["options"]: (t, bound, f) for r, t, bound, f in compare.equal_error(rows)}
    assert out["mid"][0] == pytest.approx(2.0) and out["mid"][1] == "" and out["mid"][2] == pytest.approx(4.0)
    assert out["worse"][:2] == (1.0, "<=")
    assert out["better"][:2] == (16.0, ">=")


@pytest.mark.mitsuba
def test_a_tiny_run_writes_the_table_csv_and_plot(tmp_path):
    sweeps = {
        "accumulation": [{"samples": 1}, {"samples": 4}],
        "motion_volume": [{"segments": 1, "filter": "box"}],
    }
    bench.run(tmp_path, scenes=["cube"], width=32, height=24, times=4, spp=2, repeat=1, methods=list(sweeps),
                    sweeps=sweeps, flip=False, pyrender_peer=False, log=lambda *a: None)  # fmt: skip
    assert (tmp_path / "pareto_cube.png").stat().st_size > 1000
    md = (tmp_path / "results.md").read_text()
    assert "## cube" in md and "motion_volume against accumulation" in md and "Re-timed in pairs" in md
    with open(tmp_path / "results.csv") as fh:
        rows = list(csv.DictReader(fh))
    assert [r["method"] for r in rows] == ["accumulation", "accumulation", "motion_volume"]
    assert all(float(r["rmse"]) >= 0 and float(r["ms"]) > 0 for r in rows)
    assert (
        len(list(tmp_path.glob("references/mitsuba_*.npy"))) == 1
        and len(list(tmp_path.glob("references/limit_*.npy"))) == 1
    )
    # the registered sweeps are restored
    assert len(mb.METHODS["accumulation"].sweep) == 9


def test_equal_time_interpolates_accumulations_error_at_each_methods_time():
    rows = [
        _row("accumulation", 1.0, 0.1),
        _row("accumulation", 4.0, 0.01),
        _row("accumulation", 8.0, 0.05),  # slower and worse: not on accumulation's envelope
        _row("accumulation", 16.0, 0.001),
    ]
    rows += [_row("motion_volume", 2.0, 0.002, "mid")]  # halfway in log time between 1 and 4 ms
    rows += [_row("blur_shell", 8.0, 0.01, "envelope")]  # between 4 and 16 ms: 0.01 -> 0.001
    rows += [_row("opaque_image", 0.5, 0.2, "fast"), _row("camera_velocity", 32.0, 0.0005, "slow")]
    out = {r["options"]: (eb, bound, ratio) for r, eb, bound, ratio in compare.equal_time(rows)}
    assert set(out) == {"mid", "envelope", "fast", "slow"}
    assert out["mid"][0] == pytest.approx(math.sqrt(0.1 * 0.01)) and out["mid"][1] == ""
    assert out["mid"][2] == pytest.approx(math.sqrt(0.1 * 0.01) / 0.002)
    assert out["envelope"][0] == pytest.approx(math.sqrt(0.01 * 0.001)) and out["envelope"][1] == ""
    assert out["fast"] == (0.1, ">=", pytest.approx(0.5))  # accumulation cannot run in 0.5 ms
    assert out["slow"][:2] == (0.001, "<=") and out["slow"][2] == pytest.approx(2.0)
    only = compare.equal_time(rows, methods=["blur_shell"])
    assert [r["method"] for r, *_ in only] == ["blur_shell"]
    assert compare.equal_time([_row("blur_shell", 1.0, 0.1)]) == []


@pytest.mark.mitsuba
def test_a_tiny_run_shows_every_method_beside_accumulation_at_equal_time(tmp_path):
    sweeps = {
        "accumulation": [{"samples": 1}, {"samples": 4}, {"samples": 16}],
        "motion_volume": [{"segments": 1, "filter": "box"}],
        "blur_shell": [{"subdivisions": 4}],
        "opaque_image": [{"aa": 1}],
        "camera_velocity": [{"samples": 4}],
    }
    res = bench.run(tmp_path, scenes=["cube", "pan"], width=32, height=24, times=4, spp=2, repeat=1,
                    methods=list(sweeps), sweeps=sweeps, flip=False, pyrender_peer=False, log=lambda *a: None)  # fmt: skip
    md = (tmp_path / "results.md").read_text()
    section = md[md.index("## Each method against accumulation at equal time") :]
    section = section[: section.index("\n## ")]
    for scene, methods in {
        "cube": ("motion_volume", "blur_shell", "opaque_image"),
        "pan": ("motion_volume", "blur_shell", "camera_velocity"),
    }.items():
        comp = res["equal_time"][scene]
        assert sorted(r["method"] for r, *_ in comp) == sorted(methods)
        for r, eb, bound, ratio in comp:
            # the same numbers as recomputed from the scene's rows, and in the table
            again = compare.equal_time([x for x in res["rows"] if x["scene"] == scene], methods=[r["method"]])
            assert again[0][1] == pytest.approx(eb) and again[0][2] == bound
            assert ratio == pytest.approx(eb / r["rmse"])
            assert (
                f"| {scene} | {r['method']} | {r['options']} | {r['ms']:.2f} | {r['rmse']:.5f} | {bound}{eb:.5f} |"
                in section
            )
    assert "at equal FLIP" not in md  # no FLIP comparison when FLIP was not computed


def test_the_paired_factor_re_times_the_option_set_a_user_would_pick():
    """Not the most accurate motion_volume row but the one with the best equal-error factor in the
    sweep; the most accurate one only when every factor is a bound."""
    scene = mb.SCENES["cube"](width=32, height=24)

    def row(method, ms, rmse, opts):
        return {**_row(method, ms, rmse, sweep._label(opts)), "_opts": opts}

    acc = [row("accumulation", 1.0, 0.1, {"samples": 1}), row("accumulation", 16.0, 0.001, {"samples": 16})]
    fast = row("motion_volume", 0.5, 0.01, {"segments": 1, "filter": "box"})  # factor 8
    exact = row("motion_volume", 8.0, 0.002, {"segments": 2, "filter": "box"})  # more accurate, factor ~1.5
    p = sweep.paired_factor(scene, acc + [exact, fast], rounds=1)
    assert p["options"] == fast["options"] and (p["n_lo"], p["n_hi"]) == (1, 16) and p["bound"] == ""
    assert p["factor"] == pytest.approx(p["acc_ms"] / p["mv_ms"])
    # every factor a bound (both more accurate than N = 16): the most accurate is re-timed
    a = row("motion_volume", 2.0, 0.0005, {"segments": 1, "filter": "box"})
    b = row("motion_volume", 1.0, 0.0002, {"segments": 2, "filter": "box"})
    p = sweep.paired_factor(scene, acc + [a, b], rounds=1)
    assert p["options"] == b["options"] and p["bound"] == ">=" and p["n_lo"] == 16 and p["n_hi"] is None


def test_the_sweep_leaves_out_option_sets_that_render_another_shutter():
    """The motion volume's ramp/triangle/gaussian looks on a box-shutter scene are not measured
    against references that integrate the box (and auto never chooses them there)."""
    cube = mb.SCENES["cube"](width=32, height=24)
    box = [o for m, o in bench._jobs(cube, ["motion_volume"], 2) if m == "motion_volume"]
    assert box and all(o.get("filter", "box") == "box" for o in box)
    tri = [o for m, o in bench._jobs(cube.with_(shutter="triangle"), ["motion_volume"], 2)]
    assert tri and all(o.get("filter", "triangle") == "triangle" for o in tri)
    assert {o["filter"] for o in tri if "filter" in o} == {"triangle"}


@pytest.mark.mitsuba
def test_the_report_runs_on_the_users_own_scenes(tmp_path):
    """``run(scenes=[my_scene])`` measures a Scene object at its own camera's size, and the
    command line's ``--scene file.glb`` reads a glTF file with Scene.from_gltf and measures it."""
    from _helpers import gltf_writer as gw

    mine = mb.SCENES["cube"](width=24, height=18)
    sweeps = {"accumulation": [{"samples": 1}, {"samples": 4}]}
    res = bench.run(tmp_path / "obj", scenes=[mine], times=4, spp=1, repeat=1, methods=list(sweeps), sweeps=sweeps,
                    flip=False, pyrender_peer=False, auto=False, write_html=False, log=lambda *a: None)  # fmt: skip
    assert {r["scene"] for r in res["rows"]} == {"scene_0"}
    assert res["references"]["scene_0"]["mitsuba"].shape == (18, 24, 4)
    assert [r["method"] for r in res["rows"]] == ["accumulation", "accumulation"]
    with pytest.raises(TypeError, match="frames"):
        bench.run(tmp_path / "bad", scenes=[mine], frames=3)
    with pytest.raises(TypeError, match="scenes"):
        bench.run(tmp_path / "bad", scenes=[3])
    gl, blob = gw.animated_asset(parts=("cube", "camera"))
    glb = gw.write(tmp_path, "glTF-Binary", gl, blob, name="my_asset")
    argv = ["--out", str(tmp_path / "glb"), "--scene", str(glb), "--scenes", "--size", "32x24",
            "--times", "4", "--spp", "1", "--repeat", "1", "--no-flip", "--no-pyrender"]  # fmt: skip
    assert bench.main(argv) == 0
    md = (tmp_path / "glb" / "results.md").read_text()
    assert "## my_asset" in md
