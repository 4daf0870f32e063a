"""Scene API: motion interpolation against independent twins, validation, shutter weights, registry."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation, Slerp

import motionblur as mb
from motionblur import meshes
from motionblur.scene import rotate, translate


def _cam(w=32, h=24, eye=(0.0, 0.0, 5.0)):
    return mb.Camera(mb.look_at(eye, (0.0, 0.0, 0.0)), 0.7, w, h, znear=0.5, zfar=30.0)


def _similarity(rot: Rotation, scale: float, t) -> np.ndarray:
    m = np.eye(4)
    m[:3, :3] = scale * rot.as_matrix()
    m[:3, 3] = t
    return m


def test_rigid_interpolation_matches_scipy_slerp_and_lerp():
    rng = np.random.default_rng(1)
    times = np.array([0.0, 0.3, 0.55, 1.0])
    rots = Rotation.random(4, random_state=2)
    scales = np.array([1.0, 1.5, 0.7, 1.2])
    trans = rng.normal(size=(4, 3))
    mats = np.stack([_similarity(rots[i], scales[i], trans[i]) for i in range(4)])
    motion = mb.Motion(times, mats)
    slerp = Slerp(times, rots)
    for t in np.linspace(0, 1, 23):
        got = motion.transform_at(t)
        j = min(max(np.searchsorted(times, t, side="right") - 1, 0), 2)
        u = (t - times[j]) / (times[j + 1] - times[j])
        want = _similarity(
            slerp([t])[0], (1 - u) * scales[j] + u * scales[j + 1], (1 - u) * trans[j] + u * trans[j + 1]
        )
        np.testing.assert_allclose(got, want, atol=1e-10, err_msg=f"t={t}")
    # keyframes are hit exactly and held outside
    np.testing.assert_allclose(motion.transform_at(0.3), mats[1], atol=1e-12)


def test_motion_holds_outside_its_keyframes_and_linear_takes_translations():
    m = mb.Motion([0.25, 0.75], np.stack([translate((0, 0, 0)), translate((2, 0, 0))]))
    np.testing.assert_allclose(m.transform_at(0.0)[:3, 3], [0, 0, 0])
    np.testing.assert_allclose(m.transform_at(0.5)[:3, 3], [1, 0, 0])
    np.testing.assert_allclose(m.transform_at(1.0)[:3, 3], [2, 0, 0])
    lin = mb.Motion.linear((0.0, 1.0, 0.0), (0.0, 3.0, 0.0))
    np.testing.assert_allclose(lin.transform_at(0.25)[:3, 3], [0, 1.5, 0])
    assert not lin.is_deforming and not lin.is_static


def test_slerp_takes_the_short_arc_about_the_axis():
    m = mb.Motion.linear(np.eye(4), rotate(np.radians(120), (0, 0, 1)))
    r = m.transform_at(0.5)[:3, :3]
    np.testing.assert_allclose(r, rotate(np.radians(60), (0, 0, 1))[:3, :3], atol=1e-12)


def test_deforming_interpolates_positions_linearly():
    v, f = meshes.icosphere(1)
    keys = np.stack([v, v * 2.0, v + 1.0])
    m = mb.Motion.deforming([0.0, 0.5, 1.0], keys)
    obj = mb.Object((v, f), motion=m)
    np.testing.assert_allclose(obj.world_vertices(0.25), v * 1.5)
    np.testing.assert_allclose(obj.world_vertices(0.75), 0.5 * (v * 2.0) + 0.5 * (v + 1.0))
    assert obj.is_moving and m.is_deforming
    with pytest.raises(ValueError, match="motion"):
        mb.Object(meshes.icosphere(0), motion=m)  # 12 vertices against 42


def test_world_vertices_of_rigid_and_static_objects():
    v, f = meshes.box()
    m = mb.Motion.linear(np.eye(4), translate((1, 2, 3)) @ rotate(0.4, (0, 1, 0)))
    obj = mb.Object((v, f), motion=m)
    tm = m.transform_at(0.6)
    np.testing.assert_allclose(obj.world_vertices(0.6), (tm[:3, :3] @ v.T).T + tm[:3, 3])
    still = mb.Object((v, f))
    np.testing.assert_array_equal(still.world_vertices(0.3), v)
    assert not still.is_moving


@pytest.mark.parametrize(
    "times, mats, match",
    [
        ([0.0, 1.0], np.eye(4)[None].repeat(3, 0), "transforms"),  # count mismatch
        ([0.0, 1.0], np.eye(3)[None].repeat(2, 0), "transforms"),  # wrong shape
        ([0.5, 0.2], np.eye(4)[None].repeat(2, 0), "increasing"),
        ([0.0, 1.5], np.eye(4)[None].repeat(2, 0), r"\[0, 1\]"),
        ([-0.1, 1.0], np.eye(4)[None].repeat(2, 0), r"\[0, 1\]"),
        ([], np.zeros((0, 4, 4)), "empty"),
        ([0.0, np.nan], np.eye(4)[None].repeat(2, 0), "NaN"),
    ],
)
def test_bad_motion_raises(times, mats, match):
    with pytest.raises(ValueError, match=match):
        mb.Motion(times, mats)


@pytest.mark.parametrize(
    "bad",
    [
        np.diag([1.0, 2.0, 1.0, 1.0]),  # non-uniform scale
        np.diag([-1.0, 1.0, 1.0, 1.0]),  # mirror
        np.array([[1, 0.5, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1.0]]),  # shear
        np.array([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0.1, 0, 0, 1.0]]),  # projective
        np.zeros((4, 4)),
    ],
)
def test_non_rigid_transform_is_rejected(bad):
    with pytest.raises(ValueError, match="transforms"):
        mb.Motion([0.0, 1.0], np.stack([np.eye(4), bad]))


def test_caller_arrays_are_not_modified():
    v, f = meshes.box()
    mats = np.stack([np.eye(4), translate((1, 0, 0))])
    times = np.array([0.0, 1.0])
    color = np.array([0.2, 0.5, 0.9], np.float32)
    keep = (v.copy(), f.copy(), mats.copy(), times.copy(), color.copy())
    obj = mb.Object((v, f), color=color, motion=mb.Motion(times, mats))
    sc = mb.Scene([obj], _cam())
    mb.render(sc, "accumulation", samples=3)
    mb.render(sc, "motion_volume")
    for a, b in zip((v, f, mats, times, color), keep):
        np.testing.assert_array_equal(a, b)
        assert a.flags.writeable  # the objects keep read-only views, not the caller's arrays


@pytest.mark.parametrize("name", ["box", "ramp", "triangle", "gaussian"])
def test_shutter_weights_integrate_the_filter(name):
    sc = mb.Scene([], _cam(), shutter=name)
    t = (np.arange(64) + 0.5) / 64
    w = sc.shutter_weights(t)
    assert w.shape == (64,) and abs(w.sum() - 1.0) < 1e-12 and (w >= 0).all()
    # cell integrals of the filter density, by midpoint quadrature of the density itself
    dens = {
        "box": lambda x: np.ones_like(x),
        "ramp": lambda x: 2 * x,
        "triangle": lambda x: np.where(x < 0.5, 4 * x, 4 * (1 - x)),
        "gaussian": lambda x: np.exp(-0.5 * ((x - 0.5) * 6) ** 2),
    }[name]
    fine = (np.arange(64 * 50) + 0.5) / (64 * 50)
    want = dens(fine).reshape(64, 50).sum(axis=1)
    np.testing.assert_allclose(w, want / want.sum(), rtol=2e-3, atol=1e-6)


def test_user_weights_and_bad_shutters():
    sc = mb.Scene([], _cam(), shutter=[0.0, 1.0, 3.0, 0.0])
    w = sc.shutter_weights((np.arange(4) + 0.5) / 4)
    np.testing.assert_allclose(w, [0, 0.25, 0.75, 0])
    with pytest.raises(ValueError, match="shutter"):
        mb.Scene([], _cam(), shutter="hann")
    with pytest.raises(ValueError, match="shutter"):
        mb.Scene([], _cam(), shutter=[-1.0, 2.0])
    with pytest.raises(ValueError, match="times"):
        sc.shutter_weights([0.5, 0.2])


def test_camera_at_moves_the_pose_and_reference_time():
    m = mb.Motion.linear(np.eye(4), translate((1.0, 0.0, 0.0)))
    sc = mb.Scene([], _cam(), camera_motion=m, reference_time="center")
    assert sc.reference_t == 0.5
    np.testing.assert_allclose(sc.camera_at(0.5).pose[:3, 3], [0.5, 0.0, 5.0])
    assert sc.camera_at(0.25).width == 32
    with pytest.raises(ValueError, match="camera_motion"):
        mb.Scene([], _cam(), camera_motion=mb.Motion.linear(np.eye(4), np.diag([2.0, 2.0, 2.0, 1.0])))
    with pytest.raises(ValueError, match="reference_time"):
        mb.Scene([], _cam(), reference_time=1.5)


def test_bad_scene_arguments_name_themselves():
    with pytest.raises(TypeError, match="objects"):
        mb.Scene([1], _cam())
    with pytest.raises(TypeError, match="camera"):
        mb.Scene([], None)
    with pytest.raises(ValueError, match="shading"):
        mb.Object(meshes.box(), shading="phong")
    with pytest.raises(ValueError, match="color"):
        mb.Object(meshes.box(), color=(1.0, -1.0, 0.0))
    with pytest.raises(ValueError, match="samples"):
        mb.render(mb.Scene([], _cam()), "accumulation", samples=0)
    with pytest.raises(ValueError, match="segments"):
        mb.render(mb.Scene([], _cam()), "motion_volume", segments=0)
    with pytest.raises(ValueError, match="method"):
        mb.render(mb.Scene([], _cam()), "raytrace")


def test_registry_has_the_methods_and_a_new_one_plugs_in():
    assert {"accumulation", "motion_volume"} <= set(mb.METHODS)
    for spec in mb.METHODS.values():
        assert spec.sweep and callable(spec.applies)
    assert all(n in mb.SCENES for n in ("cube", "airplane", "sphere80k", "curved", "pan"))

    @mb.register("test_blank", sweep=[{}])
    def blank(scene):
        c = scene.camera
        return mb.Frame(
            np.zeros((c.height, c.width, 4)),
            np.full((c.height, c.width), np.inf),
            np.full((c.height, c.width), -1),
            np.zeros((c.height, c.width, 2)),
        )

    try:
        f = mb.render(mb.Scene([], _cam(), background=(0.0, 0.0, 1.0, 1.0)), "test_blank")
        np.testing.assert_allclose(f.rgba[0, 0], [0, 0, 1, 1])
        assert f.stats["method"] == "test_blank"
    finally:
        del mb.METHODS["test_blank"]


def test_builtin_scenes_build_at_any_size():
    for name, fn in mb.SCENES.items():
        sc = fn(width=40, height=30)
        assert sc.camera.width == 40 and sc.camera.height == 30, name
        assert sc.moving_objects or sc.camera_moves, name
    assert abs(len(mb.SCENES["airplane"]().objects[0].mesh) - 2000) < 400
    assert len(mb.SCENES["sphere80k"]().objects[0].mesh) > 80000


def test_sequence_running_total_equals_fresh_mean_with_two_draws_per_frame(rng):
    table = {}

    def render_at(t):
        key = round(t, 9)
        if key not in table:
            table[key] = rng.random((4, 5, 4))
        return table[key]

    n = 5
    seq = mb.Sequence(render_at, samples=n, step=0.1)
    first = seq.next()
    assert seq.draws == n
    np.testing.assert_allclose(first, np.mean([render_at(j * 0.1) for j in range(n)], axis=0), atol=1e-6)
    for k in range(1, 30):
        frame = seq.next()
        assert seq.draws == n + 2 * k
        want = np.mean([render_at((k + j) * 0.1) for j in range(n)], axis=0)
        np.testing.assert_allclose(frame, want, atol=1e-6)
    kept = mb.Sequence(render_at, samples=n, step=0.1, keep_images=True)
    for _ in range(10):
        out = kept.next()
    assert kept.draws == n + 9
    np.testing.assert_allclose(out, np.mean([render_at((9 + j) * 0.1) for j in range(n)], axis=0), atol=1e-6)
    with pytest.raises(ValueError, match="samples"):
        mb.Sequence(render_at, samples=0)


def test_rotate_helper_is_right_handed():
    r = rotate(math.pi / 2, (0, 0, 1))
    np.testing.assert_allclose(r[:3, :3] @ [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], atol=1e-12)


def test_motion_samples_many_times_at_once_and_pickles():
    import pickle

    m = mb.Motion([0.0, 0.4, 1.0], np.stack([np.eye(4), rotate(1.0, (1, 1, 0)), translate((1, 2, 3))]))
    ts = np.linspace(0.0, 1.0, 17)
    many = m.transforms_at(ts)
    assert many.shape == (17, 4, 4)
    for t, got in zip(ts, many):
        np.testing.assert_array_equal(got, m.transform_at(t))
    for motion in (m, mb.Motion.deforming([0.0, 1.0], np.zeros((2, 5, 3)))):
        back = pickle.loads(pickle.dumps(motion))
        np.testing.assert_array_equal(back.transform_at(0.3), motion.transform_at(0.3))
        assert back.is_deforming == motion.is_deforming


def test_camera_poses_at_many_times_are_the_poses_at_each():
    m = mb.Motion.linear(np.eye(4), rotate(0.3, (0, 1, 0), (0, 0, 5)) @ translate((0.5, 0, 0)))
    for sc in (mb.Scene([], _cam(), camera_motion=m), mb.Scene([], _cam())):
        ts = np.linspace(0.0, 1.0, 9)
        poses = sc.camera_poses_at(ts)
        for t, p, v in zip(ts, poses, np.linalg.inv(poses)):
            np.testing.assert_array_equal(p, sc.camera_pose_at(t))
            np.testing.assert_array_equal(v, sc.camera_at(t).view)  # batched inverses: the same bits
