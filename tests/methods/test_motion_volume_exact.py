"""The motion volume against the exact frame, where it was weakest (issue #24: no silent wrong
frames).

Each case compares ``render(scene, "motion_volume")`` (default options unless named) with the
exact time integral ``render(scene, "analytic")`` and with the sharp frame at mid-shutter
(``accumulation`` with one sample: t = 0.5 of a box shutter):

    ratio = rmse(motion_volume, exact) / rmse(sharp mid-shutter, exact)

over premultiplied linear RGBA, all four channels. A useful blur has a ratio well below 1. For
the long translations the sharp frame is a poor yardstick (the object is on screen a tenth of
the shutter), so they are held to the blank frame instead. The alpha mass (sum of alpha over
the image) is compared with the exact one too.

Before the fix (commit 04ba5ae) these cases measured: the turning box 1.4-1.57 rad an EMPTY
frame (ratio 1.28-1.31, mass -100%, with segments=1 or 8), 3.0 rad mass -90%; long translations
at the default segments=1 +16% (10 units) to +309% (100 units) mass, 1.2-3.2x the error of a
blank frame; seeded random turning paths ratios up to 2.2 and mass off by up to 43%; a box
spinning side-on +40% mass, ratio 1.3. The bounds below are the measured values after the fix
with a margin of about 3x (never above 0.15: "well below 1"), noted per case.

Seeds: the piece limits of ``motionblur.methods._volume_pieces`` were tuned on seeds 0-11 of
``_random`` (TUNING_SEEDS are four of them) and the fixed cases here; HELD_OUT_SEEDS (1000-1003,
and 1000-1011 in the report of the fix) were only measured, after the constants were fixed.
"""

from __future__ import annotations

import numpy as np
import pytest

import motionblur as mb
from motionblur import meshes
from motionblur.evaluation.metrics import rmse
from motionblur.evaluation.random_scenes import hand_held_path
from motionblur.methods.motion_volume import _single
from motionblur.scene import rotate, translate

W, H = 64, 48

#: The seeds the piece limits were tuned on (with the fixed cases below).
TUNING_SEEDS = (0, 5, 8, 11)
#: Seeds measured only after the limits were fixed (never tuned on).
HELD_OUT_SEEDS = (1000, 1001, 1002, 1003)


def _cam(w=W, h=H, eye=(0.0, 0.0, 5.0)):
    return mb.Camera(mb.look_at(eye, (eye[0], eye[1], 0.0)), 0.7, w, h, znear=0.5, zfar=30.0)


def _turning_box(angle, w=W, h=H):
    """The issue's repro: a unit box moving 2 units while turning ``angle`` about +Y."""
    motion = mb.Motion.linear(
        translate((-1.0, 0.0, 0.0)), translate((1.0, 0.0, 0.0)) @ rotate(angle, (0, 1, 0))
    )
    return mb.Scene([mb.Object(meshes.box(), (0.9, 0.6, 0.2), motion=motion)], _cam(w, h))


def _long(dx, w=W, h=H):
    """A 0.6 box translating ``dx`` units across a view 3.5 units wide (as tests/peers/test_hard_cases.py)."""
    motion = mb.Motion.linear((-dx / 2, 0.0, 0.0), (dx / 2, 0.3, 0.0))
    return mb.Scene([mb.Object(meshes.box((0.6, 0.6, 0.6)), (0.9, 0.6, 0.2), motion=motion)], _cam(w, h))


def _curved(w=W, h=H):
    """A box on a half circle of 9 keyframes, turning with its path (pi over the shutter)."""
    ts = np.linspace(0.0, 1.0, 9)
    a = np.pi * (1.0 - ts)
    mats = [
        translate((1.3 * np.cos(x), 0.9 * np.sin(x) - 0.4, 0.0)) @ rotate(x - np.pi, (0, 0, 1)) for x in a
    ]
    obj = mb.Object(meshes.box((0.5, 0.3, 0.3)), (0.3, 0.8, 0.4), motion=mb.Motion(ts, np.stack(mats)))
    return mb.Scene([obj], _cam(w, h))


def _hand_held(w=W, h=H):
    """A box crossing the view while a hand-held camera shakes and turns (five keys) over a static wall."""
    ts = np.linspace(0.0, 1.0, 5)
    shake = [
        translate((0.1 * np.sin(7 * t), 0.08 * np.cos(5 * t), 0.0)) @ rotate(0.12 * t - 0.06, (0, 1, 0))
        for t in ts
    ]
    box = mb.Object(
        meshes.box((0.6, 0.6, 0.6)),
        (0.9, 0.5, 0.2),
        motion=mb.Motion.linear((-1.0, -0.2, 0.0), (1.0, 0.3, 0.0)),
    )
    v, f = meshes.box((5.0, 4.0, 0.1))
    wall = mb.Object((v + (0.0, 0.0, -1.0), f), (0.3, 0.3, 0.4))
    return mb.Scene([box, wall], _cam(w, h), camera_motion=mb.Motion(ts, np.stack(shake)))


def _side_on_spin(angle, w=W, h=H):
    """A flat box spinning in place about +Y, its axis across the view (seen side-on)."""
    ts = np.linspace(0.0, 1.0, 9)
    motion = mb.Motion(ts, np.stack([rotate(angle * t, (0, 1, 0)) for t in ts]))
    return mb.Scene([mb.Object(meshes.box((1.2, 0.5, 0.3)), (0.9, 0.6, 0.2), motion=motion)], _cam(w, h))


def _random(seed, w=W, h=H):
    """A seeded random case: a box of random proportions on a curved five-key path, turning by
    0.2 rad to a full turn about a random axis; for even seeds a hand-held camera too."""
    rng = np.random.default_rng(seed)
    eye = np.array([0.0, 0.6, 5.0]) + rng.normal(size=3) * [1.0, 0.5, 0.5]
    target = rng.normal(size=3) * 0.3
    cam = mb.Camera(
        mb.look_at(tuple(eye), tuple(target)), float(rng.uniform(0.55, 0.9)), w, h, znear=0.3, zfar=60.0
    )
    ts = np.linspace(0.0, 1.0, 5)
    mesh = meshes.box(tuple(rng.uniform(0.4, 1.0, 3)))
    axis = rng.normal(size=3)
    axis /= np.linalg.norm(axis)
    angle = rng.uniform(0.2, 2.0 * np.pi)
    pts = target + np.cumsum(rng.normal(size=(5, 3)) * 0.35, axis=0)
    pts -= pts.mean(0) - target
    mats = np.stack([translate(p) @ rotate(angle * t, axis) for t, p in zip(ts, pts)])
    obj = mb.Object(mesh, (0.8, 0.5, 0.3), motion=mb.Motion(ts, mats))
    camera_motion = None
    if seed % 2 == 0:
        camera_motion = hand_held_path(rng)
    return mb.Scene([obj], cam, camera_motion=camera_motion)


def _measure(scene, **options):
    """(ratio to the sharp mid-shutter frame, ratio to the blank frame, alpha mass error, frame)."""
    exact = mb.render(scene, "analytic").rgba
    sharp = mb.render(scene, "accumulation", samples=1).rgba
    got = mb.render(scene, "motion_volume", **options)
    e = rmse(got.rgba, exact)
    mass = float(got.rgba[..., 3].sum() / exact[..., 3].sum() - 1.0)
    return e / rmse(sharp, exact), e / rmse(np.zeros_like(exact), exact), mass, got


CASES = {
    # name: (scene, options, ratio bound, |mass| bound); measured after the fix in the comment
    # (before: ratio, mass), the bounds about 3x the measured ratio, at most 0.15
    "turn 1.4": (lambda: _turning_box(1.4), {}, 0.05, 0.02),  # 0.010, -0.0% (1.30, -100%)
    "turn 1.57": (lambda: _turning_box(1.57), {}, 0.05, 0.02),  # 0.017, -0.1% (1.29, -100%)
    "turn 1.57 segments=8": (lambda: _turning_box(1.57), {"segments": 8}, 0.05, 0.02),  # 0.007 (1.29, -100%)
    "turn 3.0": (lambda: _turning_box(3.0), {}, 0.05, 0.02),  # 0.007, +0.0% (1.23, -92%)
    "turn 1.4 160x120": (lambda: _turning_box(1.4, 160, 120), {}, 0.05, 0.02),  # 0.016, -0.2% (1.31, -100%)
    "curved path": (_curved, {}, 0.05, 0.02),  # 0.013, -0.2% (0.57, -22%)
    "hand-held camera": (_hand_held, {}, 0.15, 0.02),  # 0.068, -0.1% (0.72, +0.2%)
    "side-on spin 1.5": (lambda: _side_on_spin(1.5), {}, 0.05, 0.02),  # 0.012, +0.1% (1.22, +35%)
    "side-on spin 6 160x120": (
        lambda: _side_on_spin(6.0, 160, 120),
        {},
        0.15,
        0.04,
    ),  # 0.052, -1.6% (1.01, +36%)
    "random 1001 160x120": (lambda: _random(1001, 160, 120), {}, 0.15, 0.03),  # held out
}


@pytest.mark.parametrize("name", sorted(CASES))
def test_the_motion_volume_is_close_to_the_exact_frame(name):
    build, options, bound, mass_bound = CASES[name]
    ratio, _, mass, frame = _measure(build(), **options)
    assert ratio < bound, f"{name}: {ratio:.3f} of the sharp frame's error ({frame.stats['pieces']} pieces)"
    assert abs(mass) < mass_bound, f"{name}: alpha mass {mass:+.3f}"


@pytest.mark.parametrize("dx", [10.0, 40.0, 100.0])
def test_long_translations_at_the_default_segments(dx):
    """Measured 0.052, 0.073, 0.054 of the blank frame's error with -0.4%, -2.1%, -0.9% alpha
    mass (before: 0.24, 1.25, 3.2 with +16%, +120%, +309%); bounds 0.15 and 5%."""
    _, blank, mass, frame = _measure(_long(dx))
    assert blank < 0.15, f"{dx}: {blank:.3f} of the blank frame's error ({frame.stats['pieces']} pieces)"
    assert abs(mass) < 0.05, f"{dx}: alpha mass {mass:+.3f}"


@pytest.mark.parametrize("seed", TUNING_SEEDS + HELD_OUT_SEEDS)
def test_seeded_random_turning_paths(seed):
    """Measured: tuning seeds 0, 5, 8, 11 ratios 0.053, 0.021, 0.033, 0.009 (before 0.88, 0.65,
    1.51, 0.41), held-out 1000-1003 0.012, 0.011, 0.020, 0.012 (before 0.41, 0.96, 0.93, 0.40);
    every alpha mass within 1% (before -38% to +17%). Bounds 0.15 and 3%. A motion too fast for
    64 pieces may raise instead (none of these does)."""
    try:
        ratio, _, mass, frame = _measure(_random(seed))
    except ValueError as err:  # allowed: clearly, naming the option and the exact methods
        assert "pieces" in str(err) and "analytic" in str(err) and "accumulation" in str(err)
        return
    assert ratio < 0.15, f"seed {seed}: {ratio:.3f} ({frame.stats['pieces']} pieces)"
    assert abs(mass) < 0.03, f"seed {seed}: alpha mass {mass:+.3f}"


def test_too_few_pieces_or_too_fast_a_spin_raise_naming_what_to_use():
    msg = r"pieces.*analytic.*accumulation"
    with pytest.raises(ValueError, match=msg):  # one volume cannot follow a 1.4 rad turn
        mb.render(_turning_box(1.4), "motion_volume", pieces=1)
    with pytest.raises(ValueError, match=msg):  # 20 rad in place: more than 64 pieces of 4 px
        mb.render(_side_on_spin(20.0, 96, 72), "motion_volume")
    with pytest.raises(ValueError, match=r"filter.*ramp.*analytic.*accumulation"):
        mb.render(_turning_box(1.4), "motion_volume", filter="ramp")
    for bad in (0, 65, "many", 1.5):
        with pytest.raises((ValueError, TypeError), match="pieces"):
            mb.render(_turning_box(1.4), "motion_volume", pieces=bad)
    # a straight steady translation stays one volume: the paper's method, unchanged
    f = mb.render(_long(3.0), "motion_volume")
    assert f.stats["pieces"] == 1
    np.testing.assert_array_equal(f.rgba, _single(_long(3.0)).rgba)


def test_pieces_are_weighed_by_the_filter():
    """A triangle shutter over pieces: each piece's alphas weigh its time by the triangle (the
    volume's ``window``), the pieces by its weight; against the exact integral of the same
    shutter as close as the box shutter's case."""
    for shutter in ("triangle", "gaussian"):
        ratio, _, mass, frame = _measure(_turning_box(1.57).with_(shutter=shutter))
        assert frame.stats["pieces"] > 1
        assert ratio < 0.05 and abs(mass) < 0.02, (shutter, ratio, mass)  # measured 0.013, 0.018


def test_a_turning_volume_keeps_the_strips_the_camera_sees():
    """The one volume of the 1.4 rad turn with the camera's contour line: its strips face the
    camera although neither side of their edges does at close (leading) or open (trailing); it
    was empty, now it covers what the volume of every contour edge covers."""
    sc = _turning_box(1.4)
    obj = sc.objects[0]
    keys = obj.motion.transforms_at(np.array([0.0, 1.0]))
    eye = sc.camera.pose[:3, 3]
    line = mb.motion_volume(obj.mesh, keys, filter="box", colors=obj.rgba, camera_position=eye)
    every = mb.motion_volume(
        obj.mesh, keys, filter="box", colors=obj.rgba, camera_position=eye, contour_line=False
    )
    assert (line.part == mb.JOINING).sum() > 0

    def mass(vol):
        draw = mb.Draw(vol.vertices, vol.faces, vol.rgba, normals=vol.normals, cull_back=True)
        return mb.rasterize(sc.camera, draw, blend="exact").rgba[..., 3].sum()

    assert mass(line) == pytest.approx(mass(every), rel=0.01)


def test_the_window_is_checked():
    v, f = meshes.box()
    keys = np.stack([np.eye(4), translate((1.0, 0.0, 0.0))])
    for bad in ((0.5, 0.5), (-0.1, 0.5), (0.2, 1.5)):
        with pytest.raises(ValueError, match="window"):
            mb.motion_volume(mb.Mesh(v, f), keys, filter="box", window=bad)
