"""The motion_volume method: folding, the kept static layer, the window, against plain rasterization.

The method's output is checked against ``motionblur.rasterize`` of the same geometry in one call
(static objects plus the volumes built by ``motionblur.motion_volume`` from the folded keyframes),
which has exact transparency everywhere; tolerance 1e-5.
"""

from __future__ import annotations

import numpy as np
import pytest

import motionblur as mb
from motionblur import meshes
from motionblur.methods._layers import downsample, supersampled
from motionblur.methods.motion_volume import _single, apparent_keyframes
from motionblur.scene import rotate


def _plain(scene: mb.Scene, segments: int, filt: str, aa: int = 1) -> np.ndarray:
    cam = supersampled(scene.camera_at(scene.reference_t), aa)
    draws = []
    for k, o in enumerate(scene.objects):
        keys = apparent_keyframes(scene, o, segments)
        if np.allclose(keys, keys[-1], atol=1e-12):
            v = o.mesh.vertices @ keys[-1][:3, :3].T + keys[-1][:3, 3]
            draws.append(mb.Draw(v, o.mesh.faces, o.rgba, object_id=k))
        else:
            vol = mb.motion_volume(o.mesh, keys, filter=filt, colors=o.rgba, camera_position=cam.pose[:3, 3])
            draws.append(mb.Draw(vol.vertices, vol.faces, vol.rgba, normals=vol.normals, object_id=k))
    shading = scene.objects[0].shading
    f = mb.rasterize(cam, draws, shading=shading, lights=scene.lights, ambient=scene.ambient)
    return downsample(f.rgba, aa)


@pytest.mark.parametrize("name", ["cube", "curved", "pan", "airplane"])
def test_method_equals_one_plain_rasterization(name):
    """One volume per object over the whole shutter (``_single``, what the method draws for each
    piece of the shutter); for the scenes that need one piece only, the method itself."""
    sc = mb.SCENES[name](width=80, height=60)
    for aa in (1, 2):
        got = _single(sc, segments=3, filter="box", aa=aa, colors="contour")
        np.testing.assert_allclose(got.rgba, _plain(sc, 3, "box", aa), atol=1e-5, err_msg=f"aa={aa}")
        exact = _single(sc, segments=3, filter="box", aa=aa, exact_static=True, colors="contour")
        np.testing.assert_allclose(exact.rgba, got.rgba, atol=1e-5)
        method = mb.render(sc, "motion_volume", segments=3, filter="box", aa=aa, colors="contour")
        if method.stats["pieces"] == 1:
            np.testing.assert_array_equal(method.rgba, got.rgba)
    # a translation and a slow fly-by are one piece; the half-circle arc and the pan are not
    assert (mb.render(sc, "motion_volume").stats["pieces"] == 1) == (name in ("cube", "airplane"))


def test_static_layer_is_kept_across_frames_and_never_stale():
    sc = mb.SCENES["cube"](width=64, height=48)
    first = mb.render(sc, "motion_volume", segments=2)
    again = mb.render(sc, "motion_volume", segments=2)
    assert again.stats["static_cached"]
    np.testing.assert_array_equal(first.rgba, again.rgba)
    acc = mb.render(sc, "accumulation", samples=4)
    assert acc.stats["static_cached"] and acc.stats["static_draws"] == 0
    # a new wall colour is a new static layer
    wall = sc.objects[2]
    recoloured = sc.with_(
        objects=[sc.objects[0], sc.objects[1], mb.Object(wall.mesh, (0.1, 0.9, 0.1), name="wall")]
    )
    other = mb.render(recoloured, "accumulation", samples=4)
    assert not other.stats["static_cached"]
    assert np.abs(other.rgba - acc.rgba).max() > 0.3


def test_camera_motion_is_folded_into_the_objects():
    # a pan to the right (rotation by -0.1 about +y) makes a still object sweep to the left
    cam = mb.Camera(mb.look_at((0, 0, 5), (0, 0, 0)), 0.7, 64, 48, znear=0.5, zfar=30.0)
    ball = mb.Object(meshes.icosphere(2, 0.4), (0.9, 0.5, 0.2))
    pan = mb.Motion.linear(np.eye(4), rotate(-0.1, (0, 1, 0), (0, 0, 5)))
    panned = mb.Scene([ball], cam, camera_motion=pan)
    keys = apparent_keyframes(panned, ball, 1)
    centre_open = keys[0][:3, 3]
    centre_close = keys[1][:3, 3]
    assert centre_open[0] > centre_close[0] + 0.3  # it moves left on screen
    f = mb.render(panned, "motion_volume")
    assert f.stats["volumes"] == f.stats["pieces"]  # one volume per piece of the shutter
    cols = np.nonzero(f.rgba[..., 3].sum(axis=0) > 0)[0]
    sharp = mb.render(mb.Scene([ball], panned.camera_at(1.0)), "motion_volume")
    sharp_cols = np.nonzero(sharp.rgba[..., 3].sum(axis=0) > 0)[0]
    assert cols.max() > sharp_cols.max() + 3 and cols.min() >= sharp_cols.min() - 1  # trail to the right


def test_deforming_objects_are_refused():
    v, f = meshes.icosphere(1)
    blob = mb.Object((v, f), motion=mb.Motion.deforming([0, 1], np.stack([v, v * 1.5])))
    sc = mb.Scene([blob], mb.Camera(mb.look_at((0, 0, 5), (0, 0, 0)), 0.7, 32, 24))
    assert not mb.METHODS["motion_volume"].applies(sc)
    with pytest.raises(ValueError, match="deforms") as err:
        mb.render(sc, "motion_volume")
    for method in ("opaque_image", "velocity", "blur_shell", "accumulation"):  # what to use instead
        assert method in str(err.value) and mb.METHODS[method].applies(sc)
    # the geometry call names them too, for vertex keyframes given as a Motion or as positions
    for motion in (blob.motion, np.stack([v, v * 1.5])):
        with pytest.raises(ValueError, match="deforming mesh.*BlurShell.*blur_shell"):
            mb.motion_volume(mb.Mesh(v, f), motion)
    with pytest.raises(ValueError, match="filter"):
        mb.render(mb.Scene([], sc.camera), "motion_volume", filter="hann")
