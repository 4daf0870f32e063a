"""render(scene, "motion_volume", contour_table=...): precomputed contour tables (section 4.4).

The tables replace the per-frame face split and contour search; the frame's stats report the
largest angle between an object's motion and the stored direction it swept, and the frame stays
close to the one computed for the true motion (measured with 128 directions: RMSE against
256-sample accumulation 0.00086 -> 0.00070 on cube, 0.00111 -> 0.00159 on sphere80k; see
benches/bench_contour_table.py).
"""

from __future__ import annotations

import numpy as np
import pytest

import motionblur as mb


@pytest.mark.parametrize("name", ["cube", "sphere80k"])
def test_tables_keep_the_frame_close_to_the_computed_contour(name):
    scene = mb.SCENES[name](160, 120)
    plain = mb.render(scene, "motion_volume", filter="box", segments=2)
    framed = mb.render(scene, "motion_volume", filter="box", segments=2, contour_table=True)
    angle = framed.stats["contour_error"]
    assert 0.0 < angle < np.radians(25)  # 128 stochastic directions
    assert "contour_error" not in plain.stats
    diff = np.abs(framed.rgba[..., 3] - plain.rgba[..., 3]).sum() / plain.rgba[..., 3].sum()
    assert diff < 0.05, diff


def test_given_tables_are_used_for_their_mesh_only_and_kept_ones_reused():
    scene = mb.SCENES["cube"](160, 120)
    mover = scene.moving_objects[0]
    exact = mb.ContourTable(mover.mesh, directions=[[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    other = mb.ContourTable(mb.Mesh(*mb.meshes.icosphere(1)), directions=4)
    a = mb.render(scene, "motion_volume", contour_table=[other, exact])
    b = mb.render(scene, "motion_volume", contour_table=exact)
    np.testing.assert_array_equal(a.rgba, b.rgba)
    assert a.stats["contour_error"] == b.stats["contour_error"]
    renderer = mb.Renderer()
    renderer.render(scene, "motion_volume", contour_table=16)
    kept = renderer.contour_tables.get((id(mover.mesh), 16))
    renderer.render(scene, "motion_volume", contour_table=16)
    assert renderer.contour_tables.get((id(mover.mesh), 16)) is kept and len(kept) == 16
    for bad in ("yes", 0, [1]):
        with pytest.raises((TypeError, ValueError), match="contour_table"):
            mb.render(scene, "motion_volume", contour_table=bad)
