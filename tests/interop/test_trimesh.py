"""trimesh in and out: ``Scene.from_trimesh`` keeps the graph's transforms and the colours
(one, per vertex, per face), frames a camera when none is given, and ``Mesh.to_trimesh`` gives
the same mesh back. trimesh itself is the peer: its ``Scene.dump`` applies the graph."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

import motionblur as mb

W, H = 96, 72


def _red_box() -> trimesh.Trimesh:
    box = trimesh.creation.box((1.0, 1.0, 1.0))
    box.visual.face_colors = [255, 0, 0, 255]
    return box


def test_a_red_trimesh_renders_red():
    scene = mb.Scene.from_trimesh(_red_box(), width=W, height=H)
    frame = mb.render(scene, "accumulation", samples=1)
    inside = frame.coverage == 1.0
    assert inside.mean() > 0.05
    np.testing.assert_array_equal(frame.rgba[inside], np.tile([1.0, 0.0, 0.0, 1.0], (int(inside.sum()), 1)))


def test_graph_transforms_place_the_meshes_as_trimesh_does():
    tm = trimesh.Scene()
    base = trimesh.transformations.rotation_matrix(0.7, [0, 1, 0])
    base[:3, 3] = [1.0, 0.2, -0.5]
    tm.add_geometry(_red_box(), node_name="a", transform=base)
    sphere = trimesh.creation.icosphere(1, radius=0.4)
    child = trimesh.transformations.scale_and_translate(0.5, [0.0, 2.0, 0.0])
    tm.add_geometry(sphere, node_name="b", parent_node_name="a", transform=child)
    before = {k: g.vertices.copy() for k, g in tm.geometry.items()}
    scene = mb.Scene.from_trimesh(tm, width=W, height=H)
    want = {g.metadata["node"]: g for g in tm.dump()}  # trimesh applies its own graph
    got = {o.name: o for o in scene.objects}
    assert set(got) == {"a", "b"}
    for node in ("a", "b"):
        np.testing.assert_allclose(got[node].world_vertices(0.0), want[node].vertices, atol=1e-12)
        np.testing.assert_array_equal(got[node].mesh.faces, want[node].faces)
    for k, g in tm.geometry.items():  # the caller's meshes are not modified
        np.testing.assert_array_equal(g.vertices, before[k])
    assert not tm.has_camera, "reading the scene added a camera to it"


def test_vertex_colours_stay_per_vertex_and_face_colours_do_not_bleed():
    sphere = trimesh.creation.icosphere(2)
    vc = np.zeros((len(sphere.vertices), 4), np.uint8)
    vc[:, 0] = np.linspace(0, 255, len(vc)).astype(np.uint8)
    vc[:, 3] = 255
    sphere.visual.vertex_colors = vc
    (obj,) = mb.Scene.from_trimesh(sphere, width=W, height=H).objects
    np.testing.assert_array_equal(obj.rgba, vc.astype(np.float32) / 255.0)

    box = trimesh.creation.box((1.0, 1.0, 1.0))
    fc = np.zeros((12, 4), np.uint8)
    fc[:, 3] = 255
    fc[:, 1] = 255  # green...
    fc[box.face_normals[:, 2] > 0.5] = [0, 0, 255, 255]  # ...but the +z side (facing the camera) blue
    box.visual.face_colors = fc
    scene = mb.Scene.from_trimesh(box, width=W, height=H)
    (obj,) = scene.objects
    assert len(obj.mesh.vertices) == 36  # each face has its own three vertices
    np.testing.assert_array_equal(obj.rgba.reshape(12, 3, 4), np.repeat(fc[:, None] / 255.0, 3, axis=1))
    frame = mb.render(scene, "accumulation", samples=1)
    inside = frame.coverage == 1.0
    # the default camera looks down -Z: the +z face fills the middle, blue, with no green blended in
    np.testing.assert_array_equal(frame.rgba[inside], np.tile([0.0, 0.0, 1.0, 1.0], (int(inside.sum()), 1)))


def test_the_default_camera_frames_the_whole_scene():
    tm = trimesh.Scene()
    for i, x in enumerate((-300.0, 0.0, 450.0)):  # a wide scene in millimetres
        box = trimesh.creation.box((80.0, 80.0, 80.0))
        tm.add_geometry(
            box, node_name=f"box{i}", transform=trimesh.transformations.translation_matrix([x, 0, 0])
        )
    scene = mb.Scene.from_trimesh(tm, width=W, height=H)
    cam = scene.camera
    pts = np.concatenate([o.world_vertices(0.0) for o in scene.objects])
    clip = np.c_[pts, np.ones(len(pts))] @ cam.view_projection.T
    ndc = clip[:, :3] / clip[:, 3:]
    assert (np.abs(ndc[:, :2]) < 1.0).all() and (clip[:, 3] > cam.znear).all()
    frame = mb.render(scene, "accumulation", samples=1)
    cols = np.flatnonzero(frame.coverage.max(axis=0) > 0)
    assert cols.min() > 0 and cols.max() < W - 1 and cols.max() - cols.min() > 0.6 * W


def test_the_trimesh_scenes_own_camera_is_used():
    tm = trimesh.Scene(_red_box())
    tm.set_camera(angles=(0.3, 0.2, 0.0), distance=4.0, fov=(60.0, 45.0))
    scene = mb.Scene.from_trimesh(tm, width=W, height=H)
    np.testing.assert_allclose(scene.camera.pose, tm.camera_transform)
    assert scene.camera.yfov == pytest.approx(np.radians(45.0))


def test_mesh_to_trimesh_round_trips():
    v, f = mb.meshes.torus()
    mesh = mb.Mesh(v, f)
    tm = mesh.to_trimesh()
    np.testing.assert_array_equal(tm.vertices, mesh.vertices)
    np.testing.assert_array_equal(tm.faces, mesh.faces)
    back = mb.Mesh(tm)
    np.testing.assert_array_equal(back.vertices, mesh.vertices)
    assert tm.is_watertight and tm.is_winding_consistent and tm.volume > 0


def test_bad_input_names_the_argument():
    with pytest.raises(TypeError, match="scene: expected a trimesh.Scene"):
        mb.Scene.from_trimesh(np.zeros((3, 3)))
    with pytest.raises(ValueError, match="scene: holds no triangle mesh"):
        mb.Scene.from_trimesh(trimesh.Scene([trimesh.PointCloud(np.random.default_rng(0).random((5, 3)))]))
    with pytest.raises(TypeError, match="camera: expected a motionblur.Camera"):
        mb.Scene.from_trimesh(_red_box(), camera="front")
