"""The geometry twins (``tests/_helpers/geometry_twins.py``) checked on cases worked out by hand
and against trimesh, before the geometry tests trust them."""

from __future__ import annotations

import numpy as np
from _helpers.geometry_twins import (
    builtin,
    concave_mesh,
    random_convex,
    reference_contour,
    reference_contour_any,
    signed_volume,
    sorted_rows,
)

from motionblur import meshes


def test_reference_contour_of_a_box_is_the_back_square():
    tm = builtin(meshes.box)
    e = reference_contour(tm, [1.0, 0.0, 0.0])
    assert len(e) == 4
    assert (tm.vertices[e.ravel(), 0] < 0).all()
    # A closed loop: every vertex has one outgoing and one incoming edge.
    assert sorted(e[:, 0]) == sorted(e[:, 1])


def test_general_rule_twin_agrees_with_trimesh_twin_on_closed_meshes():
    tm = concave_mesh()
    rng = np.random.default_rng(1)
    for _ in range(5):
        m = rng.normal(size=3)
        np.testing.assert_array_equal(
            sorted_rows(reference_contour_any(tm.vertices, tm.faces, m)), reference_contour(tm, m)
        )


def test_volume_twin_matches_trimesh(rng):
    tm = random_convex(rng)
    assert abs(signed_volume(tm.vertices, tm.faces) - tm.volume) < 1e-12 * abs(tm.volume) * 100
