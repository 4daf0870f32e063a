"""Camera shake (motionblur.shake): seeded trajectories, and blur kernels against closed forms and
the exact integral.

Oracles: a pure rotation moves every pixel by the homography K R K^-1 whatever the depth (closed
form, independent of the kernel code's unprojection); the exact (analytic) frame of a small far
square is its footprint swept along the kernel's path, so their centroids agree.
"""

from __future__ import annotations

import numpy as np
import pytest

import motionblur as mb
from motionblur.shake import blur_kernels, camera_shake


def _scene(motion=None, near=True, width=120, height=90):
    pose = mb.look_at((0.0, 0.0, 4.0), (0.0, 0.0, 0.0))
    cam = mb.Camera(pose, 0.8, width, height, znear=0.1, zfar=1000.0)
    objects = []
    if near:
        objects.append(mb.Object(mb.Mesh(*mb.meshes.box((6.0, 6.0, 6.0))), color=(0.8, 0.6, 0.4, 1.0)))
    return mb.Scene(objects, cam, camera_motion=motion, background=(0.0, 0.0, 0.0, 0.0))


def test_same_seed_same_trajectory_and_longer_exposure_continues_it():
    pose = mb.look_at((1.0, 2.0, 5.0), (0.0, 0.0, 0.0))
    a = camera_shake(pose, exposure=0.04, seed=7)
    b = camera_shake(pose, exposure=0.04, seed=7)
    c = camera_shake(pose, exposure=0.04, seed=8)
    np.testing.assert_array_equal(a.transforms, b.transforms)
    assert np.abs(a.transforms - c.transforms).max() > 1e-6
    # the first 40 ms of an 80 ms shake are the 40 ms shake (one key per 1 ms step in both)
    long = camera_shake(pose, exposure=0.08, seed=7)
    np.testing.assert_allclose(long.transforms[:41], a.transforms, atol=1e-12)


def test_shake_is_rigid_and_about_the_camera_centre():
    pose = mb.look_at((1.0, 2.0, 5.0), (0.0, 0.0, 0.0))
    m = camera_shake(pose, exposure=0.1, intensity=5.0, translation=0.0, seed=3)
    eye = pose[:3, 3]
    for t in np.linspace(0, 1, 9):
        moved = m.transform_at(t) @ pose
        np.testing.assert_allclose(moved[:3, 3], eye, atol=1e-9)  # pure rotation: the eye stays
        r = moved[:3, :3]
        np.testing.assert_allclose(r.T @ r, np.eye(3), atol=1e-9)


def test_zero_intensity_is_still():
    pose = mb.look_at((0.0, 0.0, 5.0), (0.0, 0.0, 0.0))
    m = camera_shake(pose, intensity=0.0)
    assert m.is_static


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"exposure": 0.0}, "exposure"),
        ({"exposure": 11.0}, "exposure"),
        ({"intensity": -1.0}, "intensity"),
        ({"keys": 1}, "keys"),
        ({"seed": -1}, "seed"),
    ],
)
def test_bad_arguments_name_themselves(kwargs, name):
    with pytest.raises(ValueError, match=name):
        camera_shake(np.eye(4), **kwargs)


def _homography_path(scene, point, times):
    """Closed form for a rotating camera: pixel -> K R_t^T R_ref K^-1 pixel (R camera-to-world)."""
    cam = scene.camera
    f = cam.height / (2.0 * np.tan(cam.yfov / 2.0))
    k = np.array([[f, 0, cam.width / 2.0], [0, -f, cam.height / 2.0], [0, 0, 1.0]])
    flip = np.diag([1.0, 1.0, -1.0])  # the camera looks down -z: K maps (x, y, -z)
    ref = scene.camera_pose_at(scene.reference_t)[:3, :3]
    out = []
    for t in times:
        r = scene.camera_pose_at(t)[:3, :3]
        h = k @ flip @ r.T @ ref @ flip @ np.linalg.inv(k)
        p = h @ np.array([point[0], point[1], 1.0])
        out.append(p[:2] / p[2])
    return np.array(out)


def test_pure_rotation_kernel_is_the_rotation_homography_at_any_depth():
    pose = mb.look_at((0.0, 0.0, 4.0), (0.0, 0.0, 0.0))
    shake = camera_shake(pose, exposure=0.1, intensity=10.0, translation=0.0, seed=5)
    pts = np.array([[20.5, 30.5], [60.5, 45.5], [100.5, 70.5]])
    near = blur_kernels(_scene(shake, near=True), pts, samples=64)
    far = blur_kernels(_scene(shake, near=False), pts, samples=64)
    assert (near.ids == 0).all() and (far.ids == -1).all()
    for i, p in enumerate(pts):
        expected = _homography_path(_scene(shake), p, near.times)
        # far: 1e-6 px, the same projective map computed two ways in float64. near: 1e-3 px,
        # because Motion lerps the keys' translations while it slerps their rotations, so the
        # eye drifts by about 1e-6 scene units between two keys 1 ms apart.
        np.testing.assert_allclose(far.paths[i], expected, atol=1e-6)
        np.testing.assert_allclose(near.paths[i], expected, atol=1e-3)
    assert np.ptp(near.paths[:, :, 0]) > 2.0  # the shake is visible: a few pixels at least


def test_translation_makes_near_and_far_kernels_differ():
    pose = mb.look_at((0.0, 0.0, 4.0), (0.0, 0.0, 0.0))
    shake = camera_shake(pose, exposure=0.1, intensity=10.0, rotation=0.0, translation=0.2, seed=5)
    pts = np.array([[60.5, 45.5]])
    near = blur_kernels(_scene(shake, near=True), pts)
    far = blur_kernels(_scene(shake, near=False), pts)
    assert np.abs(far.paths - pts).max() < 1e-9  # translation does not move points at infinity
    assert np.abs(near.paths - pts).max() > 0.5


def test_longer_exposure_longer_kernel():
    pose = mb.look_at((0.0, 0.0, 4.0), (0.0, 0.0, 0.0))
    spreads = []
    for exposure in (0.02, 0.08, 0.32):
        s = []
        for seed in range(6):
            shake = camera_shake(pose, exposure=exposure, intensity=3.0, seed=seed)
            k = blur_kernels(_scene(shake), np.array([[60.5, 45.5]]), samples=512)
            s.append(np.ptp(k.paths[0], axis=0).max())
        spreads.append(np.array(s))
    # prefix property: per seed, never shorter (0.05 px: the kernels sample their own exposure)
    assert (spreads[1] >= spreads[0] - 0.05).all() and (spreads[2] >= spreads[1] - 0.05).all()
    assert spreads[1].mean() > 1.5 * spreads[0].mean() and spreads[2].mean() > 1.5 * spreads[1].mean()


def test_kernel_sums_to_one_and_reaches_its_path():
    pose = mb.look_at((0.0, 0.0, 4.0), (0.0, 0.0, 0.0))
    shake = camera_shake(pose, exposure=0.1, intensity=8.0, seed=2)
    k = blur_kernels(_scene(shake), grid=(3, 2))
    assert k.kernels.shape[0] == 6 and k.clipped.max() < 1e-9
    np.testing.assert_allclose(k.kernels.sum(axis=(1, 2)), 1.0, atol=1e-5)
    r = k.kernels.shape[1] // 2
    ys, xs = np.mgrid[-r : r + 1, -r : r + 1]
    for i in range(6):  # the kernel's centroid is the shutter-weighted mean of the path
        mean = (k.weights[:, None] * (k.paths[i] - k.points[i])).sum(0)
        cx = (k.kernels[i] * xs).sum()
        cy = (k.kernels[i] * ys).sum()
        np.testing.assert_allclose([cx, cy], mean, atol=1e-4)


def test_kernel_centroid_matches_the_exact_frame_of_a_small_square():
    """A 4-pixel square far away, shaken by a rotation: the exact frame's alpha centroid is the
    square's centre swept along the kernel's path. 0.03 px: the frame samples 4x4 points per
    pixel (a square's edge between them shifts its centroid by up to 1/32 px where the path is
    slow), and the homography is affine over the square to 1e-4 px."""
    pose = mb.look_at((0.0, 0.0, 4.0), (0.0, 0.0, 0.0))
    shake = camera_shake(pose, exposure=0.1, intensity=6.0, translation=0.0, seed=11)
    cam = mb.Camera(pose, 0.8, 120, 90, znear=0.1, zfar=1000.0)
    f = 90 / (2 * np.tan(0.4))
    half = 2.0 * 50.0 / f  # 4 px wide at distance 50
    v = np.array([[-half, -half, -46.0], [half, -half, -46.0], [half, half, -46.0], [-half, half, -46.0]])
    quad = mb.Object(mb.Mesh(v, [[0, 1, 2], [0, 2, 3]]), color=(1.0, 1.0, 1.0, 1.0), shading="flat")
    scene = mb.Scene([quad], cam, camera_motion=shake, background=(0.0, 0.0, 0.0, 0.0))
    frame = mb.render(scene, "analytic", aa=4, error_estimate=False)
    a = frame.rgba[..., 3].astype(np.float64)
    ys, xs = np.mgrid[0 : a.shape[0], 0 : a.shape[1]] + 0.5
    centroid = np.array([(a * xs).sum(), (a * ys).sum()]) / a.sum()
    # where the square's centre is seen at the reference time (shutter close)
    clip = scene.camera_at(scene.reference_t).view_projection @ np.array([0.0, 0.0, -46.0, 1.0])
    ndc = clip[:2] / clip[3]
    point = np.array([(ndc[0] + 1) * 60.0, (1 - ndc[1]) * 45.0])
    k = blur_kernels(scene, point[None], samples=1024)
    assert k.ids[0] == 0
    mean = (k.weights[:, None] * k.paths[0]).sum(0)
    assert np.ptp(k.paths[0], axis=0).max() > 3.0
    np.testing.assert_allclose(centroid, mean, atol=0.03)
