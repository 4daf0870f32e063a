"""render(scene, method, outputs=[...]): the ground truth lands on frame.outputs, equals the
ground_truth functions' own results, refuses what it cannot give before rendering, and
round-trips through EXR by channel name."""

from __future__ import annotations

import numpy as np
import pytest

import motionblur as mb
from motionblur.ground_truth import flow, sharp_frames


def _scene():
    v = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], float)
    obj = mb.Object(
        mb.Mesh(v, [[0, 1, 2], [0, 2, 3]]),
        color=(1, 0.5, 0.2),
        motion=mb.Motion.linear(np.zeros(3), (0.8, 0.2, 0)),
    )
    cam = mb.Camera(mb.look_at((0.0, 0.0, 5.0), (0.0, 0.0, 0.0)), 0.8, 64, 48, znear=0.1, zfar=100.0)
    return mb.Scene([obj], cam, background=(0, 0, 0, 0))


@pytest.mark.parametrize("method", ["accumulation", "analytic", "velocity"])
def test_outputs_land_on_the_frame_for_any_method(method):
    scene = _scene()
    f = mb.render(
        scene, method, outputs=["sharp", "flow", "trajectory"], output_times=[0.0, 1.0], error_estimate=False
    )
    assert f.stats["output_times"] == [0.0, 1.0]
    assert len(f.outputs["sharp"]) == 2
    np.testing.assert_array_equal(f.outputs["sharp"][1].ids, sharp_frames(scene, [1.0])[0].ids)
    np.testing.assert_array_equal(f.outputs["flow"], flow(scene, [0.0, 1.0]))
    assert f.outputs["flow_backward"].shape == (2, 48, 64, 2) and f.outputs["mean_motion"].shape == (
        48,
        64,
        2,
    )
    # from close (the reference) back to close is no motion; from open back to close is the shift
    assert np.abs(f.outputs["flow_backward"][1]).max() < 1e-9
    seen = f.outputs["sharp"][0].ids == 0
    assert f.outputs["flow_backward"][0][seen][:, 0].mean() > 5.0
    assert len(f.stats["trajectory"]) == 1 and len(f.stats["trajectory"][0]["origin"]) == 64


def test_no_outputs_by_default():
    f = mb.render(_scene(), "accumulation", error_estimate=False)
    assert f.outputs == {} and "output_times" not in f.stats


def test_unknown_outputs_are_refused_before_rendering():
    with pytest.raises(ValueError, match="outputs: unknown output 'depth_of_field'"):
        mb.render(_scene(), "accumulation", outputs=["depth_of_field"])
    with pytest.raises(TypeError, match="outputs"):
        mb.render(_scene(), "accumulation", outputs="flow")
    with pytest.raises(ValueError, match="output_times"):
        mb.render(_scene(), "accumulation", outputs=["flow"], output_times=[2.0])


def test_outputs_round_trip_through_exr_by_name(tmp_path):
    f = mb.render(_scene(), "analytic", outputs=["sharp", "flow", "trajectory"], error_estimate=False)
    path = f.save_exr(tmp_path / "gt.exr")
    back = mb.read_image(path)
    ch = back.outputs["channels"]
    for k in range(3):
        np.testing.assert_array_equal(ch[f"flow.{k}.X"], f.outputs["flow"][k][..., 0])
        np.testing.assert_array_equal(ch[f"sharp.{k}.A"], f.outputs["sharp"][k].rgba[..., 3])
        np.testing.assert_array_equal(ch[f"sharp.{k}.id"].view(np.int32), f.outputs["sharp"][k].ids)
    np.testing.assert_array_equal(ch["mean_motion.Y"], f.outputs["mean_motion"][..., 1])
    assert back.stats["output_times"] == [0.0, 0.5, 1.0]
    assert back.stats["trajectory"][0]["bbox"][0] == f.stats["trajectory"][0]["bbox"][0]
    # written again from what was read: the same channels
    again = mb.read_image(back.save_exr(tmp_path / "again.exr"))
    assert sorted(again.outputs["channels"]) == sorted(ch)


def test_exposure_comes_with_the_analytic_frame_and_is_refused_elsewhere(tmp_path):
    from motionblur.ground_truth import exposure

    scene = _scene()
    f = mb.render(scene, "analytic", outputs=["exposure"], error_estimate=False)
    ex = f.outputs["exposure"]
    alone = exposure(scene)
    np.testing.assert_array_equal(ex.fraction, alone.fraction)  # the same render's planes
    np.testing.assert_array_equal(ex.ids, [0, -1])
    np.testing.assert_allclose(ex.fraction.sum(axis=-1), 1.0, atol=1e-5)
    assert "exposure" not in f.stats
    plain = mb.render(scene, "analytic", error_estimate=False)
    np.testing.assert_array_equal(f.rgba, plain.rgba)  # asking for it changes no pixel
    back = mb.read_image(f.save_exr(tmp_path / "ex.exr")).outputs["channels"]
    np.testing.assert_array_equal(back["exposure.0.fraction"], ex.fraction[..., 0])
    np.testing.assert_array_equal(back["exposure.-1.last"], ex.last[..., 1])
    with pytest.raises(
        ValueError, match="outputs: 'exposure' is given by analytic only, not by method 'accumulation'"
    ):
        mb.render(scene, "accumulation", outputs=["exposure"])
