"""benches/fit_first_forecast.py is how `auto.FIRST_FIT` is refitted: on a few tuning scenes its
rows must be auto's own first renders and its fit must have the shape the forecast assumes.

Tuning scenes only (seeds < 100), 48x36."""

from __future__ import annotations

import json
import runpy
from pathlib import Path

import pytest

from motionblur.evaluation.random_scenes import random_scene
from motionblur.methods import auto as auto_mod

BENCH = Path(__file__).resolve().parents[2] / "benches" / "fit_first_forecast.py"


@pytest.fixture(scope="module")
def bench():
    return runpy.run_path(str(BENCH), run_name="bench_loaded")


@pytest.mark.parametrize("aa", [1, 2])
def test_the_fit_falls_with_samples_and_grows_with_the_sweep(bench, tmp_path, aa):
    """Error grows with the sweep (c1 > 0) and falls with the samples (c2 < 0, about as 1/N or
    faster), and the cross-fitted median of measured / forecast stays within 0.5x-2x."""
    result = bench["main"](["--aa", str(aa), "--sizes", "48x36:8", "--out", str(tmp_path)])
    c0, c1, c2 = result["fit"]
    assert c1 > 0.0 and -2.0 < c2 < -0.5, result
    assert 0.5 <= result["cross_fitted_ratio"]["median"] <= 2.0, result
    assert json.loads((tmp_path / "fit.json").read_text()) == result


def test_a_row_is_the_first_render_auto_reads(bench):
    """Each row's estimate is the one auto's first render of that count reads, to the bit."""
    rows = bench["scene_rows"](3, 48, 36, 1)
    assert [r["n"] for r in rows] == list(bench["COUNTS"])
    scene = random_scene(3, 48, 36)
    for r in rows[:2]:
        assert r["est"] == auto_mod._Trials(scene, 1).accumulate(r["n"]).stats["error_estimate"]
