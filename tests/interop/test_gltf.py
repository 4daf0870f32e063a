"""Animated glTF in: ``Scene.from_gltf`` reads meshes, the node hierarchy, TRS keyframes, morph
targets and skins of a file the test writes itself with pygltflib, in the three layouts of the
Khronos samples, and the scene renders with every method that applies.

At each key time written, the scene equals the animation exactly (to float32 rounding of the
stored values); trimesh, which reads glTF meshes and node transforms but not animations, is the
peer for the rest pose.
"""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from _helpers import gltf_writer as gw

import motionblur as mb
from motionblur.interop._gltf_data import quat_to_matrix, sample_channel
from motionblur.render import methods_for

LAYOUTS = ("glTF", "glTF-Embedded", "glTF-Binary")
A = gw.ASSET
W, H = 80, 60


def _file(tmp_path, layout="glTF-Binary", **kw):
    gl, blob = gw.animated_asset(**kw)
    return gw.write(tmp_path, layout, gl, blob)


def _trs(t, q, s) -> np.ndarray:
    m = np.eye(4)
    m[:3, :3] = quat_to_matrix(np.float32(q)) * np.float32(s)
    m[:3, 3] = np.float32(t)
    return m


def _objects(scene: mb.Scene) -> dict[str, mb.Object]:
    return {o.name: o for o in scene.objects}


@pytest.mark.parametrize("layout", LAYOUTS)
def test_the_three_sample_layouts_read_the_same(tmp_path, layout):
    scene = mb.Scene.from_gltf(_file(tmp_path, layout), width=W, height=H)
    ref = mb.Scene.from_gltf(_file(tmp_path / "ref", "glTF-Binary"), width=W, height=H)
    assert [o.name for o in scene.objects] == ["cube", "morph", "skinned"]
    for a, b in zip(scene.objects, ref.objects):
        np.testing.assert_array_equal(a.mesh.vertices, b.mesh.vertices)
        np.testing.assert_array_equal(a.mesh.faces, b.mesh.faces)
        np.testing.assert_array_equal(a.color, b.color)
        for t in (0.0, 0.3, 1.0):
            np.testing.assert_array_equal(a.world_vertices(t), b.world_vertices(t))


def test_the_cube_follows_its_keyframes_through_the_hierarchy(tmp_path):
    scene = mb.Scene.from_gltf(_file(tmp_path), width=W, height=H)
    cube = _objects(scene)["cube"]
    assert not cube.motion.is_deforming
    np.testing.assert_allclose(cube.color, A["cube_color"], rtol=1e-6)
    parent = _trs(A["parent_translation"], [0, 0, 0, 1], 1.0)
    duration = A["cube_keys"][-1]
    for key, tr, q in zip(A["cube_keys"], A["cube_translation"], A["cube_rotation"]):
        s = A["step_scale"][1] if key >= A["step_keys"][1] else A["step_scale"][0]
        want = parent @ _trs(tr, q, s)
        np.testing.assert_allclose(cube.transform_at(key / duration), want, atol=1e-6)
        np.testing.assert_allclose(
            cube.world_vertices(key / duration), gw.CUBE_V @ want[:3, :3].T + want[:3, 3], atol=1e-6
        )


def test_a_step_key_jumps_at_its_time(tmp_path):
    cube = _objects(mb.Scene.from_gltf(_file(tmp_path), width=W, height=H))["cube"]
    u = A["step_keys"][1] / A["cube_keys"][-1]
    before, at = cube.transform_at(u - 1e-6), cube.transform_at(u)
    scale = lambda m: np.linalg.det(m[:3, :3]) ** (1 / 3)  # noqa: E731
    assert scale(before) == pytest.approx(1.0, abs=1e-4) and scale(at) == pytest.approx(1.25, abs=1e-6)


def test_morph_weights_move_the_target_vertex(tmp_path):
    morph = _objects(mb.Scene.from_gltf(_file(tmp_path), width=W, height=H))["morph"]
    assert morph.motion.is_deforming
    base = gw.CUBE_V.astype(np.float64) + [0.0, -1.5, 0.0]
    for u in (0.0, 0.5, 1.0):  # keys at 0 and 2 s, weight 0 -> 1, linear between
        want = base.copy()
        want[6] += u * np.asarray(A["morph_offset"])
        np.testing.assert_allclose(morph.world_vertices(u), want, atol=1e-6)


def test_the_skinned_half_turns_with_its_joint(tmp_path):
    skinned = _objects(mb.Scene.from_gltf(_file(tmp_path), width=W, height=H))["skinned"]
    v = gw.CUBE_V.astype(np.float64)
    right = v[:, 0] > 0
    for u in (0.0, 1.0):
        r = quat_to_matrix(np.float32(A["joint_rotation"][int(u)]))
        got = skinned.world_vertices(u)
        np.testing.assert_allclose(got[~right], v[~right] + [0, 1.5, 0], atol=1e-6)  # joint 0 is still
        np.testing.assert_allclose(got[right], v[right] @ r.T + [0, 1.5, 0], atol=1e-6)


def test_the_files_camera_is_used(tmp_path):
    scene = mb.Scene.from_gltf(_file(tmp_path), width=W, height=H)
    assert scene.camera.yfov == pytest.approx(A["camera_yfov"]) and (
        scene.camera.width,
        scene.camera.height,
    ) == (W, H)
    np.testing.assert_allclose(scene.camera.pose[:3, 3], A["camera_translation"])
    assert not scene.camera_moves


def test_the_rest_pose_is_what_trimesh_reads(tmp_path):
    path = _file(tmp_path, parts=("cube", "camera"), animated=False)
    scene = mb.Scene.from_gltf(path, width=W, height=H)
    (cube,) = scene.objects
    assert cube.motion is None
    (peer,) = trimesh.load(path, force="scene").dump()
    np.testing.assert_allclose(
        np.sort(cube.world_vertices(0.0), axis=0), np.sort(peer.vertices, axis=0), atol=1e-6
    )


def test_the_shutter_spans_part_of_the_animation(tmp_path):
    scene = mb.Scene.from_gltf(_file(tmp_path), shutter=(1.0, 2.0), width=W, height=H)
    cube = _objects(scene)["cube"]
    parent = _trs(A["parent_translation"], [0, 0, 0, 1], 1.0)
    np.testing.assert_allclose(
        cube.transform_at(0.0), parent @ _trs(A["cube_translation"][1], A["cube_rotation"][1], 1.0), atol=1e-6
    )
    assert cube.motion.times[0] == 0.0 and cube.motion.times[-1] == 1.0


def test_resample_adds_keyframes_and_keeps_the_written_ones(tmp_path):
    plain = _objects(mb.Scene.from_gltf(_file(tmp_path), width=W, height=H))["cube"]
    dense = _objects(mb.Scene.from_gltf(_file(tmp_path), resample=8, width=W, height=H))["cube"]
    want = set(np.round(plain.motion.times, 9)) | set(np.round(np.linspace(0.0, 1.0, 9), 9))
    assert set(np.round(dense.motion.times, 9)) == want
    for u in plain.motion.times:
        np.testing.assert_allclose(dense.transform_at(u), plain.transform_at(u), atol=1e-12)


@pytest.mark.parametrize(
    "parts", [("cube", "camera"), ("cube", "morph", "skin", "camera")], ids=["rigid", "deforming"]
)
def test_every_method_that_applies_renders_the_asset(tmp_path, parts):
    scene = mb.Scene.from_gltf(_file(tmp_path, parts=parts), width=W, height=H)
    methods = methods_for(scene)
    assert "accumulation" in methods and ("motion_volume" in methods) == (parts == ("cube", "camera"))
    for m in methods:
        frame = mb.render(scene, m)
        assert np.isfinite(frame.rgba).all() and frame.coverage.sum() > 50, m


@pytest.mark.mitsuba
def test_accumulation_of_the_asset_matches_mitsuba(tmp_path):
    scene = mb.Scene.from_gltf(_file(tmp_path, parts=("cube", "camera")), width=W, height=H)
    ref = mb.reference.mitsuba(scene, times=32, spp=4)
    acc = mb.render(scene, "accumulation", samples=64, aa=2)
    assert mb.metrics.rmse(acc, ref) < 0.02


@pytest.mark.parametrize(
    "interp, u, want",
    [("LINEAR", 0.25, 0.25), ("STEP", 0.99, 0.0), ("CUBICSPLINE", 0.5, 0.5), ("CUBICSPLINE", 0.25, 0.15625)],
)
def test_sampler_interpolation(interp, u, want):
    keys = np.array([0.0, 1.0])
    vals = (
        np.array([[0.0], [1.0]])
        if interp != "CUBICSPLINE"
        else np.array([[0.0], [0.0], [0.0], [0.0], [1.0], [0.0]])
    )
    # zero tangents: the Hermite curve is smoothstep 3u^2 - 2u^3
    assert sample_channel(keys, vals, interp, "translation", u)[0] == pytest.approx(want)


def test_bad_input_names_the_argument(tmp_path):
    with pytest.raises(FileNotFoundError, match="path: no such file"):
        mb.Scene.from_gltf(tmp_path / "missing.glb")
    bad = tmp_path / "bad.gltf"
    bad.write_text("not json")
    with pytest.raises(ValueError, match="path: .* is not a readable glTF 2.0 file"):
        mb.Scene.from_gltf(bad)
    with pytest.raises(ValueError, match="animation: no animation named 'run'"):
        mb.Scene.from_gltf(_file(tmp_path), animation="run")
    with pytest.raises(ValueError, match="shutter: expected finite start < end"):
        mb.Scene.from_gltf(_file(tmp_path), shutter=(2.0, 1.0))
    with pytest.raises(TypeError, match="camera: expected a motionblur.Camera"):
        mb.Scene.from_gltf(_file(tmp_path), camera="main")
