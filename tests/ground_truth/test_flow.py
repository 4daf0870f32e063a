"""Optical flow, mean motion, sharp frames and trajectories (motionblur.ground_truth) against
closed forms: a square translating parallel to the image plane (flow is its displacement in
pixels), a disc spinning about the view axis (flow is the rotation of the pixel about the
centre), a still camera's background (no flow), and the forward-backward round trip."""

from __future__ import annotations

import numpy as np
import pytest

import motionblur as mb
from motionblur.ground_truth import flow, mean_motion, sharp_frames, surface_paths, trajectories

W, H = 80, 60


def _camera():
    return mb.Camera(mb.look_at((0.0, 0.0, 5.0), (0.0, 0.0, 0.0)), 0.8, W, H, znear=0.1, zfar=100.0)


def _focal() -> float:
    return H / (2.0 * np.tan(0.4))


def _square(motion, reference_time="close"):
    v = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], float)
    obj = mb.Object(mb.Mesh(v, [[0, 1, 2], [0, 2, 3]]), color=(1, 1, 1), motion=motion)
    return mb.Scene([obj], _camera(), reference_time=reference_time, background=(0, 0, 0, 0))


def test_translating_square_flows_by_its_displacement():
    shift = np.array([0.6, -0.3, 0.0])
    scene = _square(mb.Motion.linear(np.zeros(3), shift))
    f = flow(scene, [0.0, 0.25, 1.0])  # from close (t = 1)
    ids = sharp_frames(scene, ["close"])[0].ids
    px = _focal() / 5.0  # pixels per scene unit on the plane z = 0, 5 units away
    for j, t in enumerate([0.0, 0.25, 1.0]):
        expected = (t - 1.0) * np.array([shift[0] * px, -shift[1] * px])
        # 1e-4 px: float32 depth read back, then float64 geometry
        np.testing.assert_allclose(f[j][ids == 0], np.broadcast_to(expected, f[j][ids == 0].shape), atol=1e-4)
        assert np.abs(f[j][ids == -1]).max() < 1e-9  # still camera: the background does not move


def test_spinning_disc_flow_is_the_rotation_about_its_centre():
    angle = 0.7
    keys = np.stack([mb.rotate(angle * t, (0, 0, 1)) for t in (0.0, 0.5, 1.0)])
    scene = _square(mb.Motion([0.0, 0.5, 1.0], keys), reference_time="center")
    f = flow(scene, [1.0])[0]  # from the middle of the shutter to its close: a turn by angle / 2
    ids = sharp_frames(scene, ["center"])[0].ids
    y, x = np.mgrid[0:H, 0:W] + 0.5
    dx, dy = x - W / 2, y - H / 2
    a = angle / 2  # counter-clockwise in the world is clockwise on screen (y down)
    ex = np.cos(a) * dx + np.sin(a) * dy - dx
    ey = -np.sin(a) * dx + np.cos(a) * dy - dy
    sel = ids == 0
    np.testing.assert_allclose(f[..., 0][sel], ex[sel], atol=1e-3)
    np.testing.assert_allclose(f[..., 1][sel], ey[sel], atol=1e-3)


def test_forward_then_backward_returns_to_the_pixel():
    rng = np.random.default_rng(3)
    m = mb.rotate(0.4, (0.3, 1.0, 0.2)) @ mb.translate((0.3, 0.1, 0.5))
    cam_motion = mb.Motion.linear(np.eye(4), mb.rotate(0.05, (0, 1, 0)))
    scene = _square(mb.Motion.linear(np.eye(4), m))
    scene = mb.Scene(scene.objects, scene.camera, camera_motion=cam_motion, background=(0, 0, 0, 0))
    pts = rng.uniform([20, 15], [60, 45], size=(40, 2))
    fwd = surface_paths(scene, pts, [0.3])
    seen = fwd.ids == 0
    back = surface_paths(scene, np.clip(fwd.paths[seen, 0], 0, [W - 1e-6, H - 1e-6]), ["close"], source=0.3)
    ok = back.ids == 0  # still on the square at 0.3 (a forward point can land off its edge pixel)
    assert ok.mean() > 0.8
    # 1e-6 px: off pixel centres the depth is cast onto the triangles in float64
    np.testing.assert_allclose(back.paths[ok, 0], pts[seen][ok], atol=1e-6)


def test_mean_motion_of_a_uniform_translation_is_half_the_shift_back():
    shift = np.array([0.8, 0.0, 0.0])
    scene = _square(mb.Motion.linear(np.zeros(3), shift))
    mm = mean_motion(scene, samples=32)
    ids = sharp_frames(scene, ["close"])[0].ids
    # box shutter, reference at close: the mean position is the middle of the shutter
    np.testing.assert_allclose(mm[ids == 0][:, 0], -0.5 * 0.8 * _focal() / 5.0, atol=1e-3)
    np.testing.assert_allclose(mm[ids == 0][:, 1], 0.0, atol=1e-3)


def test_sharp_frames_match_one_sample_accumulation_at_its_time():
    scene = _square(mb.Motion.linear(np.zeros(3), (1.0, 0.0, 0.0)))
    (mid,) = sharp_frames(scene, [0.5])
    acc = mb.render(scene, "accumulation", samples=1, error_estimate=False)  # its one time is 0.5
    np.testing.assert_array_equal(mid.ids, acc.ids)
    np.testing.assert_allclose(mid.rgba, acc.rgba, atol=1e-6)
    assert mid.stats["time"] == 0.5


def test_trajectories_follow_the_origin_and_hold_every_vertex():
    shift = np.array([1.0, 0.5, 0.0])
    scene = _square(mb.Motion.linear(np.zeros(3), shift))
    (tr,) = trajectories(scene, samples=8)
    px = _focal() / 5.0
    expected = np.stack([W / 2 + tr["times"] * shift[0] * px, H / 2 - tr["times"] * shift[1] * px], axis=1)
    np.testing.assert_allclose(tr["origin"], expected, atol=1e-9)
    np.testing.assert_allclose(tr["bbox"][:, 2] - tr["bbox"][:, 0], 2 * px, atol=1e-9)


def test_deforming_objects_are_refused_by_name():
    v = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], float)
    motion = mb.Motion.deforming([0.0, 1.0], np.stack([v, v + [0.5, 0, 0]]))
    obj = mb.Object(mb.Mesh(v, [[0, 1, 2], [0, 2, 3]]), motion=motion)
    scene = mb.Scene([obj], _camera())
    with pytest.raises(ValueError, match="object 0 deforms"):
        flow(scene)


def test_bad_times_name_themselves():
    scene = _square(None)
    with pytest.raises(ValueError, match="times"):
        flow(scene, [1.5])
    with pytest.raises(ValueError, match="points"):
        surface_paths(scene, [[W + 1.0, 0.0]], [0.0])


@pytest.mark.parametrize("camera_turns", [False, True])
def test_flow_equals_the_rasterizers_motion_of_its_sample_at_close(camera_turns):
    """An independent implementation: the rasterizer's velocity buffer of the sample at shutter
    close, drawn with each vertex's position at the open (the camera's motion folded in), is
    minus the flow from close to open. 1e-4 px: float32 buffers over motions of about 60 px."""
    from motionblur.methods._sharp import sharp_frame

    v, f = mb.meshes.icosphere(3)
    m = mb.Motion.linear(
        mb.translate((-0.5, 0, 0)), mb.translate((0.5, 0.2, 0.3)) @ mb.rotate(0.8, (0.3, 1, 0))
    )
    obj = mb.Object((v, f), color=(1, 1, 1), motion=m)
    turn = mb.Motion.linear(np.eye(4), mb.rotate(0.05, (0, 1, 0))) if camera_turns else None
    scene = mb.Scene([obj], _camera(), camera_motion=turn)
    to_open = flow(scene, [0.0])[0]
    close = sharp_frame(scene, 1.0, velocity="since_open")
    seen = close.ids == 0
    assert np.abs(to_open[seen]).max() > 30.0
    np.testing.assert_allclose(to_open[seen], -close.velocity[seen], atol=1e-4)
