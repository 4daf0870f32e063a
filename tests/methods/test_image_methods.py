"""The image-space render methods (``opaque_image``, ``camera_velocity``) against real Mitsuba
3.9.1 and against accumulation, on the built-in moving-cube and camera-pan scenes.

The property: each method's error against the reference is lower than the error of the
unblurred frame (the scene rasterized sharp at mid-shutter). Kraus's opaque blur keeps the
object's own footprint opaque (it never disoccludes), so on the cube its gain comes from the
streak the object sweeps outside that footprint; it is checked there too. Images are 96x72;
Mitsuba uses 32 shutter times and 4 spp (two seeds differ by far less than the margins).
A diff image goes to out/test-failures/ on failure.
"""

from __future__ import annotations

import numpy as np
import pytest
from _helpers import pyrender_peer as peer

import motionblur as mb
from motionblur import metrics, reference
from motionblur.methods.image_space import sharp_frame, shutter_centroid
from motionblur.render import METHODS

W, H = 96, 72


def _check(name, ok, ours, ref, message):
    if not ok:
        path = peer.write_diff(name, ours.rgba, ref.rgba)
        pytest.fail(f"{message}; see {path}")


@pytest.fixture(scope="module")
def cube():
    sc = mb.SCENES["cube"](width=W, height=H)
    return sc, reference.mitsuba(sc, times=32, spp=4), mb.render(sc, "accumulation", samples=64)


@pytest.fixture(scope="module")
def pan():
    sc = mb.SCENES["pan"](width=W, height=H)
    return sc, reference.mitsuba(sc, times=32, spp=4), mb.render(sc, "accumulation", samples=64)


@pytest.mark.mitsuba
def test_methods_are_registered_with_sweeps_and_predicates(cube, pan):
    for name in ("opaque_image", "camera_velocity"):
        assert name in METHODS and len(METHODS[name].sweep) >= 3
    assert METHODS["opaque_image"].applies(cube[0]) and not METHODS["opaque_image"].applies(pan[0])
    assert METHODS["camera_velocity"].applies(pan[0]) and not METHODS["camera_velocity"].applies(cube[0])
    for sc in (cube[0], pan[0]):
        for name, spec in METHODS.items():
            if name in ("opaque_image", "camera_velocity") and spec.applies(sc):
                for options in spec.sweep:
                    f = mb.render(sc, name, **options)
                    assert f.rgba.shape == (H, W, 4) and np.isfinite(f.rgba).all()


@pytest.mark.mitsuba
def test_opaque_image_beats_the_unblurred_frame_on_the_moving_cube(cube):
    sc, ref, acc = cube
    ours = mb.render(sc, "opaque_image")
    sharp = mb.render(sc, "accumulation", samples=1)  # one sample: the sharp frame at t = 0.5
    for name, r in (("mitsuba", ref), ("accumulation", acc)):
        e, e0 = metrics.rmse(ours, r), metrics.rmse(sharp, r)
        _check(
            f"opaque_image_cube_{name}", e < e0, ours, r, f"{name}: opaque_image {e:.4f} >= sharp {e0:.4f}"
        )
    # The streak: pixels the object covers in the reference but not in the sharp frame.
    frame = sharp_frame(sc, shutter_centroid(sc))
    streak = (frame.ids != 0) & (np.abs(acc.rgba - sharp.rgba).max(-1) > 0.02)
    assert streak.sum() > 50
    e = np.sqrt(np.mean((ours.rgba[streak] - ref.rgba[streak]) ** 2))
    e0 = np.sqrt(np.mean((sharp.rgba[streak] - ref.rgba[streak]) ** 2))
    _check("opaque_image_cube_streak", e < e0, ours, ref, f"streak: {e:.4f} vs sharp {e0:.4f}")


@pytest.mark.mitsuba
def test_camera_velocity_beats_the_unblurred_frame_on_the_pan(pan):
    sc, ref, acc = pan
    for samples in (8, 32):
        ours = mb.render(sc, "camera_velocity", samples=samples)
        sharp = mb.render(sc, "accumulation", samples=1)
        for name, r in (("mitsuba", ref), ("accumulation", acc)):
            e, e0 = metrics.rmse(ours, r), metrics.rmse(sharp, r)
            _check(
                f"camera_velocity_pan_{name}",
                e < 0.5 * e0,
                ours,
                r,
                f"{name}, {samples} samples: camera_velocity {e:.4f} vs sharp {e0:.4f}",
            )


@pytest.mark.parametrize("glow", ["opaque", "coverage"])
def test_opaque_image_blurs_along_the_motion(glow):
    # A lone cube moving along +x over a transparent background: the coverage grows along x only.
    sc = mb.SCENES["cube"](width=W, height=H)
    sc = sc.with_(objects=[sc.objects[0]])
    sharp = sharp_frame(sc, 0.5)
    ours = mb.render(sc, "opaque_image", glow=glow)
    cols = lambda a: np.flatnonzero(a[..., 3].max(0) > 1e-3)  # noqa: E731
    rows = lambda a: np.flatnonzero(a[..., 3].max(1) > 1e-3)  # noqa: E731
    assert len(cols(ours.rgba)) > len(cols(sharp.rgba)) + 20
    assert abs(len(rows(ours.rgba)) - len(rows(sharp.rgba))) <= 2
    assert ours.stats["lengths"][0] > 20
    if glow == "opaque":
        assert (ours.rgba[..., 3] >= sharp.rgba[..., 3] - 1e-6).all()  # opaque: nothing disoccluded
    else:
        # the coverage glow keeps the object's total opacity (its time-averaged coverage) and
        # uncovers where it was: the sharp frame's middle is no longer opaque
        assert abs(ours.rgba[..., 3].sum() / sharp.rgba[..., 3].sum() - 1) < 0.01
        assert ours.rgba[..., 3].max() < 0.9


def test_still_scene_and_still_camera_are_left_sharp():
    sc = mb.SCENES["cube"](width=W, height=H)
    still = sc.with_(objects=[mb.Object(o.mesh, o.color, o.shading, None, o.name) for o in sc.objects])
    sharp = sharp_frame(still, 0.5)
    assert np.array_equal(
        mb.render(still, "opaque_image").rgba, mb.render(still, "accumulation", samples=1).rgba
    )
    assert np.array_equal(mb.render(still, "camera_velocity").rgba, sharp.rgba)


def test_bad_options_raise():
    sc = mb.SCENES["cube"](width=32, height=24)
    with pytest.raises(ValueError, match="aa"):
        mb.render(sc, "opaque_image", aa=3)
    with pytest.raises(ValueError, match="samples"):
        mb.render(sc, "camera_velocity", samples=0)
    with pytest.raises(TypeError):
        mb.render(sc, "opaque_image", length=3)
