"""``Camera.from_pyrender``: pyrender's perspective camera and node pose give the same projection,
and the same image of a trimesh scene (pyrender under OSMesa is the peer); ``zfar`` defaults to
pyrender's (infinite)."""

from __future__ import annotations

import os

os.environ.setdefault("PYOPENGL_PLATFORM", "osmesa")

import numpy as np  # noqa: E402
import pyrender  # noqa: E402
import pytest  # noqa: E402
import trimesh  # noqa: E402

import motionblur as mb  # noqa: E402

pytestmark = pytest.mark.pyrender
W, H = 96, 72


@pytest.mark.parametrize("zfar", [None, 40.0])
def test_the_projection_is_pyrenders(zfar):
    pc = pyrender.PerspectiveCamera(yfov=0.9, znear=0.2, zfar=zfar)
    pose = mb.look_at((1.0, 2.0, 5.0), (0.0, 0.0, 0.0))
    cam = mb.Camera.from_pyrender(pc, pose, W, H)
    np.testing.assert_array_equal(cam.projection, pc.get_projection_matrix(W, H))
    np.testing.assert_array_equal(cam.pose, pose)
    assert cam.zfar == (np.inf if zfar is None else zfar)


def test_the_defaults_are_pyrenders():
    pc = pyrender.PerspectiveCamera(yfov=0.8)
    cam = mb.Camera(np.eye(4), 0.8, W, H)
    assert (cam.znear, cam.zfar) == (pc.znear, np.inf) and pc.zfar is None
    np.testing.assert_array_equal(cam.projection, pc.get_projection_matrix(W, H))


def test_far_objects_are_not_clipped_by_default():
    cam = mb.Camera(mb.look_at((0, 0, 500.0), (0, 0, 0)), 0.05, W, H)  # 500 units away
    frame = mb.rasterize(cam, mb.Draw(*mb.meshes.box((10.0, 10.0, 10.0)), (1, 0, 0)))
    assert frame.coverage.sum() > 100


def test_a_trimesh_scene_renders_as_pyrender_renders_it():
    box = trimesh.creation.box((1.0, 1.0, 1.0))
    box.visual.face_colors = [255, 0, 0, 255]
    pose = mb.look_at((1.2, 0.9, 3.0), (0.0, 0.0, 0.0))
    pc = pyrender.PerspectiveCamera(yfov=0.8, aspectRatio=W / H)
    prs = pyrender.Scene(bg_color=[0, 0, 0, 0])
    prs.add(pyrender.Mesh.from_trimesh(box, smooth=False))
    prs.add(pc, pose=pose)
    r = pyrender.OffscreenRenderer(W, H)
    try:
        colour, depth = r.render(prs, flags=pyrender.RenderFlags.FLAT)
    finally:
        r.delete()
    cam = mb.Camera.from_pyrender(pc, pose, W, H)
    frame = mb.render(mb.Scene.from_trimesh(box, camera=cam), "accumulation", samples=1)
    ours, theirs = frame.coverage > 0.5, depth > 0
    iou = (ours & theirs).sum() / (ours | theirs).sum()
    assert iou > 0.98, iou
    both = ours & theirs
    np.testing.assert_allclose(frame.rgba[both, :3], colour[both] / 255.0, atol=1.5 / 255)
    np.testing.assert_allclose(frame.depth[both], depth[both], rtol=1e-4)


def test_other_cameras_and_a_stretched_aspect_are_refused():
    with pytest.raises(
        TypeError, match="camera: expected a pyrender.PerspectiveCamera, got OrthographicCamera"
    ):
        mb.Camera.from_pyrender(pyrender.OrthographicCamera(1.0, 1.0), np.eye(4), W, H)
    with pytest.raises(TypeError, match="IntrinsicsCamera"):
        mb.Camera.from_pyrender(pyrender.IntrinsicsCamera(50, 50, 48, 36), np.eye(4), W, H)
    with pytest.raises(ValueError, match="camera: its aspectRatio 2 differs from width / height"):
        mb.Camera.from_pyrender(pyrender.PerspectiveCamera(0.8, aspectRatio=2.0), np.eye(4), W, H)
    with pytest.raises(ValueError, match="pose: expected shape"):
        mb.Camera.from_pyrender(pyrender.PerspectiveCamera(0.8), np.eye(3), W, H)


@pytest.mark.parametrize("zfar", [np.inf, 25.0])
def test_to_pyrender_gives_the_same_projection_back(zfar):
    cam = mb.Camera(mb.look_at((0, 1, 4), (0, 0, 0)), 0.75, W, H, znear=0.3, zfar=zfar)
    pc = cam.to_pyrender()
    assert pc.zfar == (None if np.isinf(zfar) else zfar)
    np.testing.assert_array_equal(pc.get_projection_matrix(W, H), cam.projection)
    np.testing.assert_array_equal(mb.Camera.from_pyrender(pc, cam.pose, W, H).projection, cam.projection)
