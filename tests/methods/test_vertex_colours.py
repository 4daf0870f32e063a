"""An object with a colour a vertex, through every method (auto raised a TypeError on one: its
forecast read one colour an object).

Each method that applies renders a lambert icosphere coloured by its vertices' positions, turning
while it moves, and the same sphere still under a moving camera: a finite frame with a finite
error estimate, and no worse than twice the unblurred frame against the exact integral (every
method's bound in the differential test is at most 2) unless the frame warns that it is.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import motionblur as mb
from motionblur.render import METHODS
from motionblur.scene import rotate, translate


def _rmse(a, b) -> float:
    return float(np.sqrt(np.mean(np.square(np.asarray(a, np.float64) - b))))


def _scene(camera_moves: bool) -> mb.Scene:
    v, f = mb.meshes.icosphere(2)
    v = np.asarray(v)
    colours = np.c_[(v + 1) / 2, np.ones(len(v))].astype(np.float32)
    motion = mb.Motion.linear(np.eye(4), rotate(0.6, (0, 1, 0)) @ translate((0.8, 0, 0)))
    obj = mb.Object(
        mb.Mesh(v * 0.6, f), color=colours, shading="lambert", motion=None if camera_moves else motion
    )
    cam = mb.Camera(mb.look_at((0.0, 0.3, 5.0), (0.0, 0.0, 0.0)), 0.7, 64, 48, znear=0.5, zfar=30.0)
    pan = {"camera_motion": mb.Motion.linear(np.eye(4), translate((0.3, 0.0, 0.0)))} if camera_moves else {}
    return mb.Scene([obj], cam, **pan)


# the methods that apply to each scene (camera_velocity to the moving camera only, velocity
# and opaque_image to the still one)
CASES = [(m, moves) for moves in (False, True) for m in sorted(METHODS) if METHODS[m].applies(_scene(moves))]


@pytest.mark.parametrize(("method", "camera_moves"), CASES)
def test_every_method_renders_a_colour_a_vertex(method, camera_moves):
    scene = _scene(camera_moves)
    exact = mb.exact(scene).rgba.astype(np.float64)
    sharp = mb.render(scene, "accumulation", samples=1, error_estimate=False).rgba
    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")
        frame = mb.render(scene, method)
    assert np.isfinite(frame.rgba).all() and np.isfinite(frame.stats["error_estimate"]), method
    warned = any(issubclass(w.category, mb.PoorBlurWarning) for w in said)
    assert warned or _rmse(frame.rgba, exact) <= 2.0 * _rmse(sharp, exact), method


@pytest.mark.parametrize("aa", [2, 4])
def test_accumulation_and_auto_read_a_colour_a_vertex_with_spatial_samples(aa):
    scene = _scene(False)
    exact = mb.exact(scene, aa=aa).rgba.astype(np.float64)
    frame = mb.render(scene, "accumulation", aa=aa)
    err = _rmse(frame.rgba, exact)
    assert 0.5 <= frame.stats["error_estimate"] / err <= 2.0, (frame.stats["error_estimate"], err)
    assert _rmse(mb.render(scene, "auto", tolerance=0.004, aa=aa).rgba, exact) <= 0.004
