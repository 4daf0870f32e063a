"""The motion volume's time-averaged colours (``colors="pixel"``, the default, and
``"averaged"``, per vertex) against the paper's surface colours (``colors="contour"``), all
measured against accumulation with many samples, which converges to the time-averaged image."""

from __future__ import annotations

import numpy as np
import pytest

import motionblur as mb
from motionblur import meshes
from motionblur.evaluation.metrics import rmse
from motionblur.scene import translate


def _sphere_scene(shading="lambert", color=(0.2, 0.5, 0.9), move=(1.6, 0.5, 0.0), width=96, height=72):
    cam = mb.Camera(mb.look_at((0.0, 0.0, 5.0), (0.0, 0.0, 0.0)), 0.7, width, height, znear=0.5, zfar=30.0)
    v, f = meshes.icosphere(3, 0.6)
    half = np.asarray(move) / 2
    obj = mb.Object(
        (v, f), color=color, shading=shading, motion=mb.Motion.linear(translate(-half), translate(half))
    )
    light = mb.DirectionalLight((-0.3, -1.0, -0.6), 1.0)
    return mb.Scene([obj], cam, lights=[light], ambient=0.05, shutter="box")


def test_a_shaded_sphere_gets_its_time_averaged_colours():
    """The streak of a lambert sphere shows the mean of its shading, not its rim's: the error
    against accumulation falls to less than half (measured 0.0115 -> 0.0041 on sphere80k)."""
    sc = _sphere_scene()
    ref = mb.render(sc, "accumulation", samples=128, aa=2).rgba
    paper = mb.render(sc, "motion_volume", filter="box", aa=2, colors="contour")
    ours = mb.render(sc, "motion_volume", filter="box", aa=2)
    assert ours.stats["averaged"] == 1 and paper.stats["averaged"] == 0
    assert rmse(ours.rgba, ref) < 0.5 * rmse(paper.rgba, ref), (rmse(ours.rgba, ref), rmse(paper.rgba, ref))
    # only the colours change: the coverage alphas are the model's
    np.testing.assert_array_equal(ours.rgba[..., 3] > 0, paper.rgba[..., 3] > 0)
    np.testing.assert_allclose(ours.rgba[..., 3], paper.rgba[..., 3], atol=1e-6)


def test_per_vertex_colours_are_mixed_along_the_motion():
    """A flat sphere, red on its left half and green on its right, moving right: at the middle
    of the streak the average is about half and half; the paper's colours show the contour's."""
    sc = _sphere_scene(shading="flat", move=(2.4, 0.0, 0.0))
    obj = sc.objects[0]
    v = obj.mesh.vertices
    rgb = np.where(v[:, :1] < 0, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]]).astype(np.float32)
    sc = sc.with_(objects=[mb.Object(obj.mesh, color=rgb, shading="flat", motion=obj.motion)])
    ref = mb.render(sc, "accumulation", samples=128, aa=2).rgba
    ours = mb.render(sc, "motion_volume", filter="box", aa=2).rgba
    paper = mb.render(sc, "motion_volume", filter="box", aa=2, colors="contour").rgba
    assert rmse(ours, ref) < 0.5 * rmse(paper, ref)
    y, x = 36, 48  # the streak's centre: red and green pass it for equal times
    r, g = ours[y, x, :2] / ours[y, x, 3]
    assert abs(r - g) < 0.15, (r, g)


def test_one_flat_colour_skips_the_extra_pass_and_matches_the_paper():
    sc = _sphere_scene(shading="flat", color=(0.8, 0.3, 0.1))
    ours = mb.render(sc, "motion_volume", filter="box", aa=2)
    paper = mb.render(sc, "motion_volume", filter="box", aa=2, colors="contour")
    assert ours.stats["averaged"] == 0
    np.testing.assert_array_equal(ours.rgba, paper.rgba)


@pytest.mark.parametrize("move", [(0.0, 0.0, 1.5), (40.0, 0.0, 0.0), (0.0, 0.0, 4.6)])
def test_hard_motions_keep_finite_colours_in_range(move):
    """Motion along the view axis (no image path: the sharp colours), far larger than the
    screen, and through the near plane."""
    sc = _sphere_scene(move=move)
    f = mb.render(sc, "motion_volume", filter="box", aa=1)
    assert np.isfinite(f.rgba).all()
    a = f.rgba[..., 3]
    assert (a >= 0).all() and (a <= 1 + 1e-6).all() and (f.rgba[..., :3] <= a[..., None] + 1e-5).all()


def test_bad_colors_option_is_refused():
    sc = _sphere_scene()
    with pytest.raises(ValueError, match="colors"):
        mb.render(sc, "motion_volume", colors="mean")
    with pytest.raises(ValueError, match="colors"):
        mb.render(sc, "motion_volume", colors=None)


def test_an_object_leaving_the_view_still_colours_its_streak():
    """Red left half, green right half, centred on the right border at mid-shutter: the green
    half is outside the view in the sharp image, yet it passes the pixels near the border during
    the shutter. The sharp render reaches beyond the view, so the averaged colours still beat the
    paper's against accumulation."""
    sc = _sphere_scene(shading="flat", move=(2.0, 0.0, 0.0))
    obj = sc.objects[0]
    v = obj.mesh.vertices
    rgb = np.where(v[:, :1] < 0, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]]).astype(np.float32)
    edge = 5.0 * np.tan(0.35) * 96 / 72  # the right border at the sphere's depth
    motion = mb.Motion.linear(translate((edge - 1.0, 0.0, 0.0)), translate((edge + 1.0, 0.0, 0.0)))
    sc = sc.with_(objects=[mb.Object(obj.mesh, color=rgb, shading="flat", motion=motion)])
    ref = mb.render(sc, "accumulation", samples=128, aa=2).rgba
    ours = mb.render(sc, "motion_volume", filter="box", aa=2)
    paper = mb.render(sc, "motion_volume", filter="box", aa=2, colors="contour").rgba
    assert ours.stats["averaged"] == 1
    assert rmse(ours.rgba, ref) < 0.6 * rmse(paper, ref), (rmse(ours.rgba, ref), rmse(paper, ref))
    # next to the border green passes for about a third of the covered time (its sharp image at
    # mid-shutter is all outside the view: a window cut at the border would give no green)
    got = ours.rgba[30:42, 88:95, 1] / ours.rgba[30:42, 88:95, 3]
    want = ref[30:42, 88:95, 1] / ref[30:42, 88:95, 3]
    assert want.min() > 0.25 and np.abs(got - want).max() < 0.1, (got, want)
