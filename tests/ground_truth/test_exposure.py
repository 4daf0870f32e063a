"""The exposure channel (motionblur.ground_truth.exposure) against closed forms: a square
translating parallel to the image plane is visible at a pixel centre for the time interval its
swept extent covers it, a still object behind it for the rest; the fractions of a pixel sum to
1; a ramp shutter weights them by its integral; accumulation of the frontmost id at N times
agrees within about 1/N; and asking for it changes no bit of the render."""

from __future__ import annotations

import numpy as np
import pytest

import motionblur as mb
from motionblur.analytic import MovingDraw, rasterize_motion
from motionblur.ground_truth import Exposure, exposure, sharp_frames
from motionblur.methods.analytic import analytic

W, H = 80, 60
TAN = np.tan(0.4)
SHIFT = 1.5  # the square's centre moves from x = 0 to x = SHIFT over the shutter


def _camera():
    return mb.Camera(mb.look_at((0.0, 0.0, 5.0), (0.0, 0.0, 0.0)), 0.8, W, H, znear=0.1, zfar=100.0)


def _quad(half: float, z: float = 0.0) -> mb.Mesh:
    v = np.array([[-half, -half, z], [half, -half, z], [half, half, z], [-half, half, z]], float)
    return mb.Mesh(v, [[0, 1, 2], [0, 2, 3]])


def _scene(shutter="box", square_z: float = 0.0, alpha: float = 1.0, still=None) -> mb.Scene:
    """Object 0: a square of half-size 1 at depth ``square_z`` translating by SHIFT along x;
    object 1: a still wall at z = -2 filling the view (or ``still``)."""
    square = mb.Object(
        _quad(1.0, square_z),
        color=(1, 0, 0, alpha),
        motion=mb.Motion.linear(np.zeros(3), np.array([SHIFT, 0.0, 0.0])),
    )
    wall = still if still is not None else mb.Object(_quad(20.0, -2.0), color=(0, 0, 1))
    return mb.Scene([square, wall], _camera(), shutter=shutter, background=(0, 0, 0, 0))


def _on_plane(z: float):
    """(H,W) x and y of the points of the plane at depth ``z`` seen at the pixel centres."""
    y, x = np.mgrid[0:H, 0:W] + 0.5
    d = 5.0 - z
    return (2.0 * x / W - 1.0) * TAN * d * W / H, (1.0 - 2.0 * y / H) * TAN * d


def _interval(z: float = 0.0):
    """(H,W) start and end of the times the square covers each pixel centre (a = b: never), and
    the pixels whose centre lies within 1e-4 of its top or bottom edge (ambiguous)."""
    x, y = _on_plane(z)
    a = np.clip((x - 1.0) / SHIFT, 0.0, 1.0)
    b = np.clip((x + 1.0) / SHIFT, 0.0, 1.0)
    inside = np.abs(y) < 1.0
    b = np.where(inside, b, a)
    return a, b, np.abs(np.abs(y) - 1.0) < 1e-4


def test_the_result_is_a_read_only_exposure_of_documented_shapes():
    e = exposure(_scene())
    assert isinstance(e, Exposure)
    assert e.fraction.shape == e.first.shape == e.last.shape == (H, W, 3)
    assert e.fraction.dtype == e.first.dtype == e.last.dtype == np.float32
    assert e.ids.tolist() == [0, 1, -1] and e.ids.dtype == np.int32
    assert not e.fraction.flags.writeable and not e.first.flags.writeable
    # the wall fills the view: nothing (id -1) is never visible
    assert (e.fraction[..., 2] == 0).all() and np.isnan(e.first[..., 2]).all()


def test_translating_square_is_visible_for_the_closed_form_interval():
    a, b, edge = _interval()
    e = exposure(_scene())
    seen = (b > a) & ~edge
    # 1e-5: the kernel finds the covered times from float64 edge functions, kept in float32
    np.testing.assert_allclose(e.fraction[..., 0][~edge], (b - a)[~edge], atol=1e-5)
    np.testing.assert_allclose(e.first[..., 0][seen], a[seen], atol=1e-5)
    np.testing.assert_allclose(e.last[..., 0][seen], b[seen], atol=1e-5)
    assert np.isnan(e.first[..., 0][(b == a) & ~edge]).all()
    # the still wall is visible the rest of the time (it is behind the square throughout)
    np.testing.assert_allclose(e.fraction[..., 1][~edge], 1.0 - (b - a)[~edge], atol=1e-5)
    whole = (b == a) & ~edge  # never covered: the wall over the whole shutter
    assert (e.first[..., 1][whole] == 0.0).all() and (e.last[..., 1][whole] == 1.0).all()


@pytest.mark.parametrize("aa", [1, 2])
def test_fractions_of_all_objects_and_nothing_sum_to_one(aa):
    # a half-transparent square over a wall that covers only part of the view: three ids
    # visible somewhere, the square whatever its alpha
    scene = _scene(alpha=0.5, still=mb.Object(_quad(1.5, -1.0), color=(0, 0, 1)))
    e = exposure(scene, aa=aa)
    # 1e-5: float32 planes summed over 3 objects and aa*aa samples
    np.testing.assert_allclose(e.fraction.sum(axis=-1), 1.0, atol=1e-5)
    assert (e.fraction >= 0).all() and (e.fraction <= 1 + 1e-6).all()
    for k in range(3):
        assert e.fraction[..., k].max() > 0.5
    # first <= last wherever visible, both in [0, 1]
    v = ~np.isnan(e.first)
    assert (v == ~np.isnan(e.last)).all() and (v == (e.fraction > 0) | v).all()
    assert (e.first[v] <= e.last[v]).all() and (e.first[v] >= 0).all() and (e.last[v] <= 1).all()


def test_transparent_square_in_front_is_the_visible_object():
    a, b, edge = _interval()
    e = exposure(_scene(alpha=0.25))
    np.testing.assert_allclose(e.fraction[..., 0][~edge], (b - a)[~edge], atol=1e-5)


def test_still_object_is_hidden_while_a_moving_one_passes_in_front():
    # object 1: a still square of half-size 0.8 at z = 0; object 0: the moving square, nearer
    # the camera (z = 1), passes over it; the background (-1) around
    scene = _scene(square_z=1.0, still=mb.Object(_quad(0.8, 0.0), color=(0, 0, 1)))
    a, b, edge = _interval(z=1.0)
    xs, ys = _on_plane(0.0)
    on_still = (np.abs(xs) < 0.8) & (np.abs(ys) < 0.8)
    ok = ~edge & (np.abs(np.abs(xs) - 0.8) > 1e-4) & (np.abs(np.abs(ys) - 0.8) > 1e-4)
    e = exposure(scene)
    cover = b - a
    # 1e-5 as above
    np.testing.assert_allclose(e.fraction[..., 0][ok], cover[ok], atol=1e-5)
    want_still = np.where(on_still, 1.0 - cover, 0.0)
    np.testing.assert_allclose(e.fraction[..., 1][ok], want_still[ok], atol=1e-5)
    want_none = np.where(on_still, 0.0, 1.0 - cover)
    np.testing.assert_allclose(e.fraction[..., 2][ok], want_none[ok], atol=1e-5)
    # hidden part of the shutter: where the moving square leaves it at b < 1, the still
    # square is visible from b until the close (1e-5 as above)
    left = ok & on_still & (b > a) & (b < 0.99)
    assert left.sum() > 20
    np.testing.assert_allclose(e.first[..., 1][left], b[left], atol=1e-5)
    np.testing.assert_allclose(e.last[..., 1][left], 1.0, atol=1e-6)
    np.testing.assert_allclose(e.last[..., 0][left], b[left], atol=1e-5)


def test_ramp_shutter_weights_the_fraction_by_its_integral():
    a, b, edge = _interval()
    box, ramp = exposure(_scene("box")), exposure(_scene("ramp"))
    # the ramp's density is 2t, its integral t^2; 1e-5 as above
    np.testing.assert_allclose(ramp.fraction[..., 0][~edge], (b**2 - a**2)[~edge], atol=1e-5)
    np.testing.assert_allclose(ramp.fraction.sum(axis=-1), 1.0, atol=1e-5)
    # the times it is visible do not depend on the weights
    np.testing.assert_array_equal(ramp.first, box.first)
    np.testing.assert_array_equal(ramp.last, box.last)


def test_times_the_filter_gives_no_weight_still_count_as_visible():
    # weights (1, 0): the second half of the shutter weighs nothing
    a, b, edge = _interval()
    box, half = exposure(_scene("box")), exposure(_scene(np.array([1.0, 0.0])))
    want = mb.shutter_cdf(np.array([1.0, 0.0]), b.ravel()) - mb.shutter_cdf(np.array([1.0, 0.0]), a.ravel())
    # 1e-5 as above
    np.testing.assert_allclose(half.fraction[..., 0][~edge], want.reshape(H, W)[~edge], atol=1e-5)
    late = ~edge & (a > 0.55) & (b > a)  # visible only in the weightless half
    assert late.sum() > 20 and (half.fraction[..., 0][late] == 0).all()
    np.testing.assert_array_equal(half.first, box.first)
    np.testing.assert_array_equal(half.last, box.last)


def test_accumulating_the_frontmost_id_at_many_times_agrees_within_one_over_n():
    n = 128
    turn = mb.rotate(np.pi / 3, (0.0, 0.0, 1.0), (0.0, 0.0, 0.5))
    spin = mb.Object(_quad(0.7, 0.5), color=(0, 1, 0), motion=mb.Motion.linear(np.eye(4), turn))
    base = _scene()
    scene = mb.Scene([base.objects[0], base.objects[1], spin], _camera(), background=(0, 0, 0, 0))
    e = exposure(scene)
    times = (np.arange(n) + 0.5) / n  # stratified: the middles of n equal strata
    ids = np.stack([f.ids for f in sharp_frames(scene, times)])  # (n,H,W)
    for k, obj in enumerate([0, 1, 2, -1]):
        count = (ids == obj).mean(axis=0)
        err = np.abs(e.fraction[..., k] - count)
        # an interval of visible time holds its length times n middles, give or take one, and
        # an object is visible over at most two intervals here (the square splits the wall's
        # time); the spinning square's arc is cut into chords within 0.01 px: 0.002 more. Most
        # pixels see no edge at all: the mean is far smaller.
        assert err.max() <= 2.0 / n + 0.002, (obj, err.max())
        assert err.mean() < 0.1 / n, (obj, err.mean())


def test_asking_for_the_exposure_changes_no_bit_of_the_render():
    scene = _scene(alpha=0.5)
    for aa in (1, 2):
        off = mb.render(scene, "analytic", aa=aa)
        on = analytic(scene, aa, exposure=True)
        for name in ("rgba", "depth", "ids", "velocity"):
            np.testing.assert_array_equal(getattr(on, name), getattr(off, name), err_msg=name)
        assert "exposure" in on.stats and "exposure" not in off.stats


def test_a_scene_with_nothing_moving_is_exposed_through_the_same_kernel():
    still = mb.Scene([mb.Object(_quad(1.0), color=(1, 1, 1))], _camera(), background=(0, 0, 0, 0))
    e = exposure(still)
    sharp = sharp_frames(still, [1.0])[0].ids
    np.testing.assert_array_equal(e.fraction[..., 0], (sharp == 0).astype(np.float32))
    np.testing.assert_array_equal(e.fraction[..., 1], (sharp == -1).astype(np.float32))
    assert (e.first[sharp == 0, 0] == 0).all() and (e.last[sharp == 0, 0] == 1).all()


def test_bad_arguments_name_themselves():
    with pytest.raises(TypeError, match="scene"):
        exposure("scene")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="aa"):
        exposure(_scene(), aa=3)
    with pytest.raises(TypeError, match="exposure"):
        analytic(_scene(), exposure="yes")
    pos = np.zeros((2, 3, 3))
    pos[:, 1, 0] = pos[:, 2, 1] = 1.0
    draw = MovingDraw(pos, [[0, 1, 2]], object_id=3)
    with pytest.raises(ValueError, match="object_id"):
        rasterize_motion(_camera(), [draw], [0.0, 1.0], exposure=2)
    with pytest.raises(ValueError, match="exposure"):
        rasterize_motion(_camera(), [draw], [0.0, 1.0], exposure=-1)
    # the planes are checked against the memory budget before anything is allocated
    old = mb.set_memory_budget(1 << 20)
    try:
        with pytest.raises(MemoryError, match="exposure"):
            rasterize_motion(_camera(), [draw], [0.0, 1.0], exposure=1000)
    finally:
        mb.set_memory_budget(old)
