"""The analytic method's segment rule (``segment_times``, run by the compiled core): its limits
come from the core, and the boundaries it returns satisfy the documented rule, measured here
independently in numpy."""

from __future__ import annotations

import numpy as np
import pytest

import motionblur as mb
from motionblur import _core, meshes
from motionblur.methods import _segments, analytic
from motionblur.scene import rotate, translate


def test_the_limits_are_the_cores():
    for mod in (analytic, _segments):
        assert mod.MAX_SEGMENTS == _core.ANALYTIC_MAX_SEGMENTS == 256
        assert mod.MIN_PIECE == _core.ANALYTIC_MIN_PIECE == 1.0 / 1024.0
        assert mod.NORMAL_TOLERANCE == _core.ANALYTIC_NORMAL_TOLERANCE == 2e-4
        assert mod.segment_times is _segments.segment_times


def _turning_scene(turn: float) -> mb.Scene:
    """A box turning by ``turn`` radians about +Y in front of a panning camera."""
    v, f = meshes.box((0.6, 0.4, 0.3))
    place = translate((0.0, 0.0, -4.0))
    times = np.linspace(0.0, 1.0, 3)
    spin = mb.Motion(times, np.stack([place @ rotate(turn * t, (0.0, 1.0, 0.0)) for t in times]))
    pan = mb.Motion(times, np.stack([rotate(0.2 * t, (0.0, 1.0, 0.0)) for t in times]))
    cam = mb.Camera(np.eye(4), 0.8, 96, 72)
    return mb.Scene([mb.Object((v, f), motion=spin)], cam, camera_motion=pan)


def _off(scene: mb.Scene, obj: mb.Object, a: float, b: float) -> float:
    """The rule's measure of [a, b] in pixels: the bounding box's corners at the middle against
    the middle of their clip-space chords, as the visible image sees them."""
    v = obj.mesh.vertices
    lo, hi = v.min(axis=0), v.max(axis=0)
    corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])

    def clip(t):
        m, vp = obj.transform_at(t), scene.camera_at(t).view_projection
        p = corners @ m[:3, :3].T + m[:3, 3]
        return np.c_[p, np.ones(len(p))] @ vp.T

    ca, cb, cm = clip(a), clip(b), clip(0.5 * (a + b))
    chord = 0.5 * (ca + cb)
    d, dw = chord - cm, chord[:, 3] - cm[:, 3]
    p = np.clip(cm[:, :2] / cm[:, 3:4], -1.0, 1.0)
    wl = np.maximum(chord[:, 3], scene.camera.znear)
    size = np.array([scene.camera.width, scene.camera.height]) * 0.5
    e = np.abs(d[:, :2] - p * dw[:, None]) / wl[:, None] * size
    return float(np.hypot(e[:, 0], e[:, 1]).max())


@pytest.mark.parametrize("tolerance", [1.0, 0.05, 0.01])
def test_every_piece_left_whole_is_within_the_tolerance(tolerance):
    scene = _turning_scene(1.5)
    obj = scene.objects[0]
    times = _segments.segment_times(scene, [obj], scene.camera, tolerance)
    assert times[0] == 0.0 and times[-1] == 1.0 and 0.5 in times.tolist()
    assert (np.diff(times) > 0).all() and len(times) - 1 < _segments.MAX_SEGMENTS
    offs = [_off(scene, obj, a, b) for a, b in zip(times[:-1], times[1:])]
    # the numpy measure differs from the core's by rounding only
    assert max(offs) <= tolerance * (1 + 1e-9)
    # and the rule stops as soon as it may: some piece's halves would each be within it
    assert max(offs) > 0.1 * tolerance


def test_a_translation_needs_one_segment_and_the_cap_holds():
    scene = _turning_scene(0.0).with_(camera_motion=None)
    obj = scene.objects[0]
    slide = mb.Motion.linear((0.0, 0.0, -4.0), (1.0, 0.5, -3.0))
    moved = mb.Object(obj.mesh, motion=slide)
    assert _segments.segment_times(scene, [moved], scene.camera, 1e-6).tolist() == [0.0, 1.0]
    spun = _turning_scene(6.0)
    times = _segments.segment_times(spun, spun.objects, spun.camera, 1e-9)
    assert len(times) - 1 == _segments.MAX_SEGMENTS
    assert np.diff(times).min() >= _segments.MIN_PIECE / 2
    with pytest.raises(ValueError, match="tolerance: must be > 0"):
        _segments.segment_times(spun, spun.objects, spun.camera, 0.0)
