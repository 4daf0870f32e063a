"""motionblur.image kernels against their numpy twins (tests/_helpers/image_twins.py), and the properties
of Kraus 2013 and Chapman 2011 the issue lists. Tolerance: max abs error 1e-5."""

from __future__ import annotations

import math

import numpy as np
import pytest
from _helpers import image_twins as tw

import motionblur as mb
import motionblur.image as mi

TOL = 1e-5
DIRECTIONS = [
    (1, 0),
    (-3, 0),
    (0, 1),
    (0, -2),
    (1, 0.3),
    (-0.4, 1),
    (1, 1),
    (1, -math.tan(math.pi / 6)),
    (0.2, -1),
]


def rgba_image(h=48, w=64, seed=0, mask=True):
    """Premultiplied RGBA: a soft-edged blob of random colour over transparent black."""
    rng = np.random.default_rng(seed)
    y, x = np.mgrid[0:h, 0:w]
    a = np.clip(0.35 * min(h, w) - np.hypot(x - 0.45 * w, y - 0.55 * h), 0, 1) if mask else np.ones((h, w))
    a = a * rng.uniform(0.5, 1.0, (h, w)) if mask else a
    c = rng.random((h, w, 3))
    return np.concatenate([c * a[..., None], a[..., None]], -1).astype(np.float32)


def check(got, want, what=""):
    assert got.shape == want.shape, what
    assert np.isfinite(got).all(), what
    err = np.abs(got.astype(np.float64) - want).max()
    assert err <= TOL, f"{what}: max abs error {err:.3g}"


@pytest.mark.parametrize("direction", DIRECTIONS)
@pytest.mark.parametrize("length", [0, 1, 6, 21, 300])
def test_box_blur_matches_twin(direction, length):
    img = rgba_image(seed=1, mask=False) * np.float32(0.7)
    check(mi.box_blur(img, direction, length), tw.box_blur(img, direction, length), f"{direction} {length}")


@pytest.mark.parametrize("direction", DIRECTIONS)
@pytest.mark.parametrize("width", [0, 3, 10, 100])
def test_glow_matches_twin_and_never_lowers_alpha(direction, width):
    a = rgba_image(seed=2)[..., 3]
    g = mi.glow(a, direction, width)
    check(g, tw.glow(a, direction, width), f"{direction} {width}")
    assert (g >= a).all()


@pytest.mark.parametrize("direction", DIRECTIONS)
@pytest.mark.parametrize("length", [0, 5, 24, 200])
@pytest.mark.parametrize("mode", [None, "over", "under"])
def test_opaque_blur_matches_twin(direction, length, mode):
    img = rgba_image(seed=3)
    if mode is None:
        got = mi.opaque_blur(img, direction, length)
        base = None
    else:
        base = rgba_image(seed=4, mask=False) * np.float32(0.9)
        base = base if mode == "over" else base * (1 - img[..., 3:4])
        got = mi.opaque_motion_blur(img, direction, length, mode=mode, base=base)
    check(got, tw.opaque_blur(img, direction, length, mode, base), f"{direction} {length} {mode}")
    assert (got[..., 3] >= img[..., 3] - 1e-6).all() if mode != "under" else True


def test_opaque_motion_blur_default_base_is_the_input():
    img = rgba_image(seed=5)
    got = mi.opaque_motion_blur(img, (1, 0.2), 15)
    check(got, tw.opaque_blur(img, (1, 0.2), 15, "over", img))


@pytest.mark.parametrize("size", [(48, 64), (37, 23), (1, 17), (17, 1), (5, 3)])
@pytest.mark.parametrize("levels", [0, 1, 2, 4])
def test_pyramids_match_twins(size, levels):
    img = rgba_image(*size, seed=6)
    check(mi.pyramid_blur(img, levels), tw.pyramid_blur(img, levels), "blur")
    g = mi.pyramid_glow(img[..., 3], levels)
    check(g, tw.pyramid_glow(img[..., 3], levels), "glow")
    assert (g >= img[..., 3] - 1e-7).all()
    check(mi.pyramid_opaque_blur(img, levels), tw.pyramid_opaque_blur(img, levels), "opaque")


def dof_scene(h=48, w=64, seed=7):
    rng = np.random.default_rng(seed)
    img = rgba_image(h, w, seed=seed, mask=False)
    y, x = np.mgrid[0:h, 0:w]
    depth = (1.0 + 4.0 * x / w + rng.uniform(0, 0.2, (h, w))).astype(np.float32)
    depth[: h // 4] = np.inf  # sky
    return img, depth


@pytest.mark.parametrize("layers", [1, 3, 5, 7])
@pytest.mark.parametrize("f_number", [1.4, 8.0, 200.0])
def test_depth_of_field_matches_twin(layers, f_number):
    img, depth = dof_scene()
    args = dict(focal_depth=2.0, focal_length=0.05, f_number=f_number, yfov=0.8, layers=layers)
    got = mi.depth_of_field(img, depth, **args)
    check(got, tw.depth_of_field(img, depth, **args), str(args))


def test_depth_of_field_infinite_far_layers_are_handled():
    # r_inf small: eq. 4 turns negative for i >= 1 and 2 -> those depths become infinite.
    img, depth = dof_scene()
    h = img.shape[0]
    args = dict(focal_depth=2.0, focal_length=0.05, f_number=50.0, yfov=0.8, layers=7)
    r_inf = h / (2 * 2.0 * math.tan(0.4)) * 0.05 / (2 * 50.0)
    assert r_inf < tw.disc_radius(1)  # so z_1 = z_f / (1 - r_1 / r_inf) would be negative
    got = mi.depth_of_field(img, depth, **args)
    check(got, tw.depth_of_field(img, depth, **args))
    assert np.isfinite(got).all()


def test_depth_of_field_in_focus_plane_is_sharp():
    img, _ = dof_scene()
    depth = np.full(img.shape[:2], 2.0, np.float32)
    got = mi.depth_of_field(img, depth, 2.0, 0.05, 2.0, 0.8, layers=5)
    check(got, img.astype(np.float64))


@pytest.mark.parametrize("aperture", [0.005, 0.05, 0.3])
def test_lens_blur_matches_twin(aperture):
    img, depth = dof_scene()
    got = mi.lens_blur(img, depth, aperture, 2.0, 0.8)
    check(got, tw.lens_blur(img, depth, aperture, 2.0, 0.8), f"aperture {aperture}")


def test_lens_blur_in_focus_plane_is_unchanged():
    img, _ = dof_scene()
    depth = np.full(img.shape[:2], 2.0, np.float32)
    np.testing.assert_array_equal(mi.lens_blur(img, depth, 0.2, 2.0, 0.8), img)


def cameras(w=64, h=48, move=(0.0, 0.0, 0.0), turn=0.0):
    pose = mb.look_at((0, 0, 5), (0, 0, 0))
    cam = mb.Camera(pose, 0.8, w, h)
    c, s = math.cos(turn), math.sin(turn)
    rot = np.array([[c, 0, s, 0], [0, 1, 0, 0], [-s, 0, c, 0], [0, 0, 0, 1]])
    prev_pose = pose @ rot
    prev_pose[:3, 3] += move
    return cam, mb.Camera(prev_pose, 0.8, w, h)


@pytest.mark.parametrize("move,turn", [((0.3, 0.1, 0.0), 0.0), ((0, 0, 0.5), 0.05), ((0, 0, 0), -0.1)])
def test_camera_velocity_matches_twin(move, turn):
    cam, prev = cameras(move=move, turn=turn)
    _, depth = dof_scene()
    got = mi.camera_velocity(depth, cam, prev)
    want = tw.camera_velocity(depth, cam, prev)
    # float32 output of velocities up to ~17 px: rounding is ~1e-6, well inside TOL (the
    # float64 matrices are the same operations in another order).
    err = np.abs(got - want).max()
    assert err <= TOL, err


def test_sky_moves_only_with_rotation():
    _, depth = dof_scene()
    sky = np.isinf(depth)
    cam, prev = cameras(move=(2.0, 1.0, 3.0))
    v = mi.camera_velocity(depth, cam, prev)
    assert np.abs(v[sky]).max() < 1e-3 and np.abs(v[~sky]).max() > 1.0
    cam, prev = cameras(turn=0.05)
    v = mi.camera_velocity(depth, cam, prev)
    assert np.hypot(v[sky][:, 0], v[sky][:, 1]).min() > 1.0


@pytest.mark.parametrize("samples", [1, 2, 5, 16])
def test_velocity_blur_matches_twin(samples):
    img = rgba_image(seed=8, mask=False)
    rng = np.random.default_rng(9)
    vel = rng.uniform(-20, 20, img.shape[:2] + (2,)).astype(np.float32)
    vel[:5] = 0
    check(mi.velocity_blur(img, vel, samples), tw.velocity_blur(img, vel, samples))


def test_camera_motion_blur_is_velocity_blur_of_camera_velocity_with_fps_scale():
    img, depth = dof_scene()
    cam, prev = cameras(move=(0.3, 0.0, 0.2), turn=0.02)
    vel = tw.camera_velocity(depth, cam, prev) * (30.0 / 60.0)
    got = mi.camera_motion_blur(img, depth, cam, prev, samples=8, target_fps=60, fps=30)
    want = tw.velocity_blur(img, vel.astype(np.float32), 8)
    assert np.abs(got - want).max() <= TOL
    full = mi.camera_motion_blur(img, depth, cam, prev, samples=8)
    assert np.abs(full - got).max() > 1e-3  # the fps scale changed the blur


def test_static_camera_leaves_the_image_unchanged():
    img, depth = dof_scene()
    cam, _ = cameras()
    out = mi.camera_motion_blur(img, depth, cam, cam, samples=16)
    assert np.array_equal(out, img)


# --- properties


@pytest.mark.parametrize("direction", [(1, 0), (0, 1), (1, 0.45)])
def test_blur_of_a_constant_is_the_constant(direction):
    img = np.full((40, 50, 4), 0.25, np.float32)
    img[..., 3] = 1.0
    r = 6
    box = mi.box_blur(img, direction, 2 * r + 1)
    inner = box[r + 2 : -r - 2, r + 2 : -r - 2]
    assert np.abs(inner - img[0, 0]).max() < 1e-6
    opq = mi.opaque_blur(img, direction, 2 * r + 1)
    assert np.abs(opq - img[0, 0]).max() < 1e-6  # eq. 7 restores the colour up to the border
    assert np.abs(mi.pyramid_opaque_blur(img, 3) - img[0, 0]).max() < 1e-6


@pytest.mark.parametrize("direction", DIRECTIONS)
def test_box_blur_conserves_the_sum_away_from_borders(direction):
    img = np.zeros((64, 80, 4), np.float32)
    img[24:40, 30:50] = rgba_image(16, 20, seed=10, mask=False)
    out = mi.box_blur(img, direction, 15)
    assert np.allclose(out.sum((0, 1)), img.sum((0, 1)), rtol=1e-5)
    assert np.allclose(mi.pyramid_blur(img, 2).sum((0, 1)), img.sum((0, 1)), rtol=1e-5)


@pytest.mark.parametrize("direction", [(1, 0), (0.3, 1), (1, -0.5)])
def test_no_dark_halo(direction):
    h, w = 40, 60
    y, x = np.mgrid[0:h, 0:w]
    a = (np.hypot(x - 30, y - 20) < 10).astype(np.float32)
    colour = np.array([0.9, 0.5, 0.2], np.float32)
    img = np.concatenate([colour * a[..., None], a[..., None]], -1)
    out = mi.opaque_blur(img, direction, 17)
    box = mi.box_blur(img, direction, 17)
    grown = out[..., 3] > 1e-3
    assert (out[..., 3] >= a).all() and (out[..., 3] > box[..., 3] + 0.1).any()
    straight = out[..., :3][grown] / out[..., 3][grown][:, None]
    assert np.abs(straight - colour).max() < 1e-5
    # Without the rescale the glow opacity would darken the silhouette: the test can fail.
    naive = box[..., :3][grown] / out[..., 3][grown][:, None]
    assert np.abs(naive - colour).max() > 0.1


@pytest.mark.parametrize("direction", [(1, 0), (0, 1), (1, 0.6)])
def test_one_pixel_transparent_border_avoids_viewport_artifacts(direction):
    # An opaque image with a one-pixel transparent border keeps its colour and stays opaque
    # right up to the border, and equals the blur of the same image in a larger framebuffer.
    colour = np.array([0.2, 0.7, 0.4, 1.0], np.float32)
    img = np.zeros((30, 40, 4), np.float32)
    img[1:-1, 1:-1] = colour
    out = mi.opaque_blur(img, direction, 9)
    inner = out[1:-1, 1:-1]
    assert np.abs(inner - colour).max() < 1e-5
    big = np.zeros((50, 70, 4), np.float32)
    big[10:40, 15:55] = img
    check(out, mi.opaque_blur(big, direction, 9)[10:40, 15:55].astype(np.float64))


# --- hard cases


def test_near_zero_alpha_gives_no_nan():
    img = rgba_image(seed=11)
    img *= np.float32(1e-30)
    img[0, 0] = [1e-38, 0, 0, 1e-38]
    for d in [(1, 0), (0, 1), (1, 0.3)]:
        for out in (mi.opaque_blur(img, d, 31), mi.opaque_motion_blur(img, d, 31), mi.box_blur(img, d, 31)):
            assert np.isfinite(out).all()
            assert (out[..., 3] >= 0).all()
    for lv in (1, 3):
        assert np.isfinite(mi.pyramid_opaque_blur(img, lv)).all()


def test_zero_direction_and_zero_length_are_the_identity():
    img = rgba_image(seed=12)
    for d, n in [((0, 0), 30), ((1, 0), 0), ((0.3, 1), 1)]:
        assert np.array_equal(mi.box_blur(img, d, n), img)
        assert np.array_equal(mi.glow(img[..., 3], d, n / 2), img[..., 3])
        check(mi.opaque_blur(img, d, n), tw.opaque_blur(img, d, n))


def test_length_longer_than_the_image():
    img = rgba_image(12, 9, seed=13)
    for d in DIRECTIONS:
        check(mi.opaque_motion_blur(img, d, 1000), tw.opaque_blur(img, d, 1000, "over", img), str(d))


@pytest.mark.parametrize("shape", [(1, 31), (31, 1), (1, 1)])
def test_one_pixel_wide_images(shape):
    img = rgba_image(*shape, seed=14, mask=False)
    for d in [(1, 0), (0, 1), (1, 0.5), (0.5, 1)]:
        check(mi.box_blur(img, d, 9), tw.box_blur(img, d, 9), f"box {shape} {d}")
        check(mi.opaque_blur(img, d, 9), tw.opaque_blur(img, d, 9), f"opaque {shape} {d}")
        check(mi.glow(img[..., 3], d, 4), tw.glow(img[..., 3], d, 4), f"glow {shape} {d}")
    check(mi.pyramid_opaque_blur(img, 3), tw.pyramid_opaque_blur(img, 3))
    depth = np.full(shape, 3.0, np.float32)
    check(
        mi.depth_of_field(img, depth, 2.0, 0.05, 1.4, 0.8), tw.depth_of_field(img, depth, 2.0, 0.05, 1.4, 0.8)
    )
    vel = np.full(shape + (2,), 3.0, np.float32)
    check(mi.velocity_blur(img, vel, 4), tw.velocity_blur(img, vel, 4))


def test_nan_depth_raises():
    img, depth = dof_scene()
    depth[3, 4] = np.nan
    cam, prev = cameras()
    with pytest.raises(ValueError, match="depth"):
        mi.depth_of_field(img, depth, 2.0, 0.05, 2.0, 0.8)
    with pytest.raises(ValueError, match="depth"):
        mi.camera_velocity(depth, cam, prev)
    with pytest.raises(ValueError, match="depth"):
        mi.camera_motion_blur(img, depth, cam, prev)
