"""The keyframe engine (``_core._Keyframes``, ``src/motion/``) against its numpy twin and scipy's
slerp, its validation, vectorised sampling, resampling and the GIL."""

from __future__ import annotations

import numpy as np
import pytest
from _helpers.motion_twin import transform_at
from _helpers.threads import ticks_during
from scipy.spatial.transform import Rotation, Slerp

import motionblur as mb
from motionblur import _core


def _similarity(rot: Rotation, scale: float, t) -> np.ndarray:
    m = np.eye(4)
    m[:3, :3] = scale * rot.as_matrix()
    m[:3, 3] = t
    return m


def _random_keys(rng, k: int, spread: float):
    times = np.sort(rng.choice(np.linspace(0.0, 1.0, 33), k, replace=False))
    rots = Rotation.from_rotvec(rng.normal(size=(k, 3)) * spread)
    mats = np.stack([_similarity(rots[i], rng.uniform(0.3, 3.0), rng.normal(size=3)) for i in range(k)])
    return times, mats


@pytest.mark.parametrize("spread", [0.0, 0.003, 0.05, 1.0, 3.0])
def test_sampling_matches_the_numpy_twin(rng, spread):
    """Same splitting and interpolation as the twin, within 1e-14 relative (on x86-64 with
    OpenBLAS the two agree bit for bit: the engine sums in numpy's order)."""
    for _ in range(20):
        times, mats = _random_keys(rng, int(rng.integers(1, 6)), spread)
        keys = _core._Keyframes(times, mats)
        ts = np.concatenate([rng.uniform(0.0, 1.0, 16), times, [0.0, 1.0]])
        got = keys.transforms_at(ts)
        for t, g in zip(ts, got):
            want = transform_at(times, mats, t)
            np.testing.assert_allclose(g, want, rtol=1e-14, atol=1e-14 * np.abs(want).max())
            np.testing.assert_array_equal(g, keys.transform_at(t))  # one and many: the same
        for i, t in enumerate(times):  # keyframes are hit exactly
            np.testing.assert_array_equal(keys.transform_at(t), mats[i])


def test_small_rotations_are_slerped_not_approximated():
    """Keyframes 2 degrees apart: the rotation angle is linear in time to 1e-15 (a normalised
    linear interpolation would be up to 1e-6 rad off, scipy's slerp is the oracle)."""
    rots = Rotation.from_rotvec([[0.0, 0.0, 0.0], [0.01, 0.02, -0.03]])
    mats = np.stack([_similarity(rots[0], 1.0, [0, 0, 0]), _similarity(rots[1], 1.0, [1, 0, 0])])
    keys = _core._Keyframes(np.array([0.0, 1.0]), mats)
    slerp = Slerp([0.0, 1.0], rots)
    for t in np.linspace(0.0, 1.0, 41):
        np.testing.assert_allclose(keys.transform_at(t)[:3, :3], slerp([t])[0].as_matrix(), atol=2e-15)


def test_shorter_arc_scale_and_hold():
    a = _similarity(Rotation.from_euler("z", 170, degrees=True), 1.0, [0, 0, 0])
    b = _similarity(Rotation.from_euler("z", -170, degrees=True), 3.0, [2, 0, 0])
    keys = _core._Keyframes(np.array([0.25, 0.75]), np.stack([a, b]))
    mid = keys.transform_at(0.5)
    np.testing.assert_allclose(
        mid[:3, :3] / 2.0, Rotation.from_euler("z", 180, degrees=True).as_matrix(), atol=1e-14
    )
    np.testing.assert_allclose(mid[:3, 3], [1, 0, 0], atol=1e-15)
    np.testing.assert_array_equal(keys.transform_at(0.0), a)
    np.testing.assert_array_equal(keys.transform_at(1.0), b)
    np.testing.assert_array_equal(keys.scales(), [1.0, 3.0])


def test_deforming_keys_lerp_positions_exactly(rng):
    v = rng.normal(size=(3, 50, 3))
    times = np.array([0.0, 0.4, 1.0])
    keys = _core._Keyframes(times, None, v)
    assert keys.is_deforming
    for t in (0.0, 0.1, 0.4, 0.7, 1.0):
        j = min(max(int(np.searchsorted(times, t, side="right")) - 1, 0), 1)
        u = (t - times[j]) / (times[j + 1] - times[j])
        want = v[j].copy() if u == 0 else (1 - u) * v[j] + u * v[j + 1]
        if t == 1.0:
            want = v[2]
        np.testing.assert_array_equal(keys.vertices_at(t), want)
    np.testing.assert_array_equal(keys.transform_at(0.3), np.eye(4))


def test_resampled_keys_are_the_samples_at_linspace_times(rng):
    times, mats = _random_keys(rng, 4, 1.0)
    keys = _core._Keyframes(times, mats)
    for n in (1, 3, 8, 33):
        r = keys.resampled(n)
        np.testing.assert_array_equal(r.times(), np.linspace(0.0, 1.0, n + 1))
        np.testing.assert_array_equal(r.transforms(), keys.transforms_at(np.linspace(0.0, 1.0, n + 1)))
    with pytest.raises(ValueError, match="segments"):
        keys.resampled(_core.MAX_SEGMENTS + 1)


@pytest.mark.parametrize(
    "times, mats, match",
    [
        ([0.0, 1.0], np.eye(4)[None].repeat(3, 0), "transforms: expected 2 keyframes"),
        ([0.5, 0.2], np.eye(4)[None].repeat(2, 0), "times: must be strictly increasing"),
        ([0.0, 1.5], np.eye(4)[None].repeat(2, 0), r"times: .*\[0, 1\]"),
        ([0.0, np.nan], np.eye(4)[None].repeat(2, 0), "times: contains NaN"),
        ([0.0], np.diag([1.0, 2.0, 1.0, 1.0])[None], "keyframe 0 is not rigid .*shear"),
        ([0.0], np.diag([-1.0, 1.0, 1.0, 1.0])[None], r"keyframe 0 is not rigid \(determinant -1 <= 0"),
        ([0.0], np.full((1, 4, 4), np.inf), "keyframe 0 is NaN or inf"),
    ],
)
def test_bad_keyframes_raise_naming_the_argument(times, mats, match):
    with pytest.raises(ValueError, match=match):
        _core._Keyframes(np.array(times, dtype=float), mats)


def test_errors_name_the_callers_argument():
    bad = np.stack([np.eye(4), np.diag([-1.0, 1.0, 1.0, 1.0])])
    with pytest.raises(ValueError, match="^motion: keyframe 1"):
        mb.motion_volume(mb.Mesh(*mb.meshes.box()), bad)
    with pytest.raises(ValueError, match="^transforms: keyframe 1"):
        mb.Motion([0.0, 1.0], bad)
    with pytest.raises(ValueError, match="^motion: needs at least 2 keyframes"):
        mb.motion_volume(mb.Mesh(*mb.meshes.box()), np.eye(4)[None])


def test_vertex_sampling_releases_the_gil(rng):
    v = rng.normal(size=(2, 400_000, 3))
    keys = _core._Keyframes(np.array([0.0, 1.0]), None, v)
    assert ticks_during(lambda: [keys.vertices_at(0.37) for _ in range(10)]) > 0
