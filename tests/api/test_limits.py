"""Limits and name lists are the compiled core's: the Python layer re-exports them and checks
arguments against them, and no Python module repeats them as literals."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

import motionblur as mb
from motionblur import _core, geometry, image, raster, scene
from motionblur.methods import _volume_colors
from motionblur.methods import motion_volume as mv

PACKAGE = Path(mb.__file__).parent


def test_python_constants_are_the_cores():
    assert (raster.MAX_SIDE, raster.MAX_PIXELS) == (_core.MAX_SIDE, _core.MAX_PIXELS) == (16384, 1 << 25)
    assert geometry.FILTERS == mv.FILTERS == scene.SHUTTER_FILTERS == tuple(_core.FILTERS)
    assert set(_core.FILTERS) == {"ramp", "box", "triangle", "gaussian"}
    assert (_core.SHADINGS, _core.BLENDS, _core.SAMPLES) == (
        ("flat", "lambert"),
        ("exact", "unsorted"),
        (1, 2, 4),
    )
    assert _core.MAX_SEGMENTS == 4096
    for name in ("MAX_LENGTH", "MAX_FPS_RATIO", "MAX_LEVELS", "MAX_LAYERS", "MAX_SAMPLES", "MAX_VELOCITY"):
        assert getattr(image, name) == getattr(_core, name), name
    assert _volume_colors.MIN_ALPHA == _core.MIN_ALPHA and np.float32(_core.MIN_ALPHA) == np.float32(1e-3)


def _cam():
    return mb.Camera(mb.look_at((0.0, 0.0, 5.0), (0.0, 0.0, 0.0)), 0.7, 32, 24)


def test_segments_is_checked_against_the_core_limit_everywhere():
    mesh = mb.Mesh(*mb.meshes.box())
    over = _core.MAX_SEGMENTS + 1
    sc = mb.Scene([mb.Object(mesh, motion=mb.Motion.linear((0, 0, 0), (1, 0, 0)))], _cam())
    for call in (
        lambda s: mb.motion_volume(mesh, [1.0, 0.0, 0.0], segments=s),
        lambda s: mb.spin_volume(mesh, [0.0, 0.0, 1.0], 1.0, segments=s),
        lambda s: mb.render(sc, "motion_volume", segments=s),
    ):
        with pytest.raises(ValueError, match=f"segments: must be <= {_core.MAX_SEGMENTS}"):
            call(over)
        with pytest.raises(ValueError, match="segments: must be >= 1"):
            call(0)
        with pytest.raises(TypeError, match="segments"):
            call(2.0)
    # the core checks the total: keyframe intervals times segments
    keys = np.stack([mb.scene.translate((i, 0, 0)) for i in range(3)])
    with pytest.raises(
        ValueError, match=f"segments: must be in 1..={_core.MAX_SEGMENTS} \\(in total\\), got 4098"
    ):
        mb.motion_volume(mesh, keys, segments=2049)


def test_names_are_checked_against_the_cores_lists():
    cam = _cam()
    d = mb.Draw(*mb.meshes.box(), (1.0, 1.0, 1.0))
    with pytest.raises(ValueError, match="shading: expected one of flat, lambert"):
        mb.rasterize(cam, d, shading="phong")
    with pytest.raises(ValueError, match="blend: expected one of exact, unsorted"):
        mb.rasterize(cam, d, blend="add")
    with pytest.raises(ValueError, match="samples: must be one of 1, 2, 4"):
        mb.rasterize(cam, d, samples=3)
    with pytest.raises(ValueError, match="filter: expected one of ramp, box, triangle, gaussian"):
        mb.motion_volume(mb.Mesh(*mb.meshes.box()), [1.0, 0.0, 0.0], filter="hann")
    with pytest.raises(ValueError, match=f"width: must be <= {_core.MAX_SIDE}"):
        mb.Camera(np.eye(4), 0.7, _core.MAX_SIDE + 1, 10)


LITERALS = [r"\b4096\b", r"\b16384\b", r"\b32768\b", r"\b65000\b", r"maximum=255\b", r"1 << 25", r"65536\.0"]


def test_no_module_repeats_the_cores_limits():
    found = []
    for path in PACKAGE.rglob("*.py"):
        text = path.read_text()
        for pat in LITERALS:
            found += [f"{path.relative_to(PACKAGE)}: {m.group(0)}" for m in re.finditer(pat, text)]
    assert not found, found
