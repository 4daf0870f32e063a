"""``to_mitsuba_dict(scene, t)``: the scene at one shutter time as Mitsuba 3 renders it through
``mi.load_dict``: the same image as the time-sampled reference at that time, and as our
rasterizer within the anti-aliasing noise."""

from __future__ import annotations

import numpy as np
import pytest

import motionblur as mb
from motionblur.evaluation.reference import _mi

pytestmark = pytest.mark.mitsuba
W, H = 64, 48


def _scene(shading="flat", camera_motion=None, color=(0.9, 0.35, 0.1)) -> mb.Scene:
    """A ball moving over a floor; lit scenes leave the floor out (Mitsuba casts shadows, the
    rasterizer does not)."""
    cam = mb.Camera(mb.look_at((0, 0.5, 4), (0, 0, 0)), 0.7, W, H, znear=0.5, zfar=30.0)
    v, f = mb.meshes.icosphere(3)
    ball = mb.Object((v * 0.6, f), color=color, shading=shading,
                     motion=mb.Motion.linear([-0.8, 0, 0], [0.8, 0, 0]))  # fmt: skip
    fv, ff = mb.meshes.box((3.0, 0.1, 2.0))
    floor = mb.Object((fv - [0.0, 0.7, 0.0], ff), color=(0.3, 0.6, 0.3), shading=shading)
    light = [mb.DirectionalLight((-0.3, -1.0, -0.5), 1.0)] if shading == "lambert" else []
    objects = [ball] if shading == "lambert" else [ball, floor]
    return mb.Scene(objects, cam, lights=light, camera_motion=camera_motion)


def _render(d: dict, spp: int = 16, seed: int = 0) -> np.ndarray:
    mi = _mi()
    return np.array(mi.render(mi.load_dict(d), spp=spp, seed=seed), dtype=np.float32)


def test_it_renders_what_the_reference_renders_at_that_time():
    scene = _scene()
    ref = mb.reference.mitsuba(scene, times=1, spp=8, seed=0)  # one time: the middle of the shutter
    ours = _render(mb.to_mitsuba_dict(scene, 0.5, spp=8), spp=8, seed=0)
    np.testing.assert_allclose(ours, ref.rgba, atol=1e-6)


@pytest.mark.parametrize("shading", ["flat", "lambert"])
@pytest.mark.parametrize("t", [0.0, 0.7])
def test_it_matches_the_rasterizer_at_that_time(shading, t):
    scene = _scene(shading)
    still = scene.with_(
        objects=[mb.Object((o.world_vertices(t), o.mesh.faces), o.color, o.shading) for o in scene.objects]
    )
    ras = mb.render(still, "accumulation", samples=1, aa=4)
    img = _render(mb.to_mitsuba_dict(scene, t))
    err = mb.metrics.rmse(img, ras)
    assert err < 0.03, err
    moved = mb.render(_scene(shading).with_(objects=[mb.Object((o.world_vertices(1.0 - t), o.mesh.faces), o.color, o.shading)
                                                      for o in scene.objects]), "accumulation", samples=1, aa=4)  # fmt: skip
    assert mb.metrics.rmse(img, moved) > 2 * err  # the time matters


def test_a_moving_camera_is_placed_at_t():
    pan = mb.Motion.linear(mb.rotate(-0.2, (0, 1, 0)), mb.rotate(0.2, (0, 1, 0)))
    scene = _scene(camera_motion=pan)
    d = mb.to_mitsuba_dict(scene, 0.25)
    want = scene.camera_pose_at(0.25) @ np.diag([-1.0, 1.0, -1.0, 1.0])
    np.testing.assert_allclose(np.array(d["sensor"]["to_world"].matrix), want, atol=1e-6)


def test_per_vertex_colours_render():
    scene = _scene()
    v = scene.objects[0].mesh.vertices
    colours = np.c_[(v[:, 0] > 0) * 0.9 + 0.05, np.full(len(v), 0.2), (v[:, 0] <= 0) * 0.9 + 0.05]
    ball = mb.Object(scene.objects[0].mesh, colours)
    scene = scene.with_(objects=[ball])
    img = _render(mb.to_mitsuba_dict(scene, 1.0))
    ras = mb.render(scene.with_(objects=[mb.Object((ball.world_vertices(1.0), ball.mesh.faces), colours)]),
                    "accumulation", samples=1, aa=4)  # fmt: skip
    assert mb.metrics.rmse(img, ras) < 0.03


def test_bad_arguments_are_named():
    with pytest.raises(TypeError, match="scene: expected a motionblur.Scene"):
        mb.to_mitsuba_dict("scene", 0.5)
    with pytest.raises(ValueError, match=r"t: must be in the shutter interval \[0, 1\]"):
        mb.to_mitsuba_dict(_scene(), 1.5)
