"""Import paths from before the evaluation package and the methods' shared layers keep working."""

from __future__ import annotations

import importlib
import subprocess
import sys

import pytest

import motionblur as mb
from motionblur import evaluation  # noqa: F401  (the package, for the identity checks)
from motionblur.methods import _layers


@pytest.mark.parametrize(
    "name",
    ["Layer", "composite", "raster_layer", "raw_layer", "window_projection", "supersampled", "downsample",
     "resolve_arrays", "resolve", "static_layer", "clear_static_cache", "aligned_window", "paste"],
)  # fmt: skip
def test_the_layer_helpers_are_still_reached_from_render(name):
    render = importlib.import_module("motionblur.render")  # mb.render is the function

    assert getattr(render, name) is getattr(_layers, name)
    assert name in dir(render)
    exec(f"from motionblur.render import {name}", {})


def test_render_still_raises_attribute_error_for_unknown_names():
    render = importlib.import_module("motionblur.render")

    with pytest.raises(AttributeError, match="no_such_name"):
        render.no_such_name  # noqa: B018


@pytest.mark.parametrize("name", ["metrics", "reference", "demo"])
def test_the_moved_evaluation_modules_are_the_same_module_at_the_old_path(name):
    old = importlib.import_module(f"motionblur.{name}")
    assert old is importlib.import_module(f"motionblur.evaluation.{name}")


def test_the_package_attributes_are_the_evaluation_modules():
    assert mb.metrics is mb.evaluation.metrics and mb.reference is mb.evaluation.reference
    from motionblur.metrics import rmse

    assert rmse is mb.evaluation.metrics.rmse


def test_the_old_bench_module_keeps_its_names():
    from motionblur import bench
    from motionblur.evaluation import bench as new_bench
    from motionblur.evaluation import compare, sweep

    assert bench.run is new_bench.run and bench.main is new_bench.main
    assert bench.pareto_front is compare.pareto_front and bench.equal_time is compare.equal_time
    assert bench.sweep_scene is sweep.sweep_scene and bench.paired_factor is sweep.paired_factor
    assert bench.METHODS is mb.METHODS and bench.SCENES is mb.SCENES


def test_the_command_line_still_lists_demo_and_bench():
    out = subprocess.run(
        [sys.executable, "-m", "motionblur", "--help"], capture_output=True, text=True, check=True
    ).stdout
    assert "demo" in out and "bench" in out
    out = subprocess.run(
        [sys.executable, "-m", "motionblur", "bench", "--help"], capture_output=True, text=True, check=True
    ).stdout
    assert "--quick" in out and "speed-against-error" in out
