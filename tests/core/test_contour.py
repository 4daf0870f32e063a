"""contour_edges against the numpy twin built from trimesh's face_adjacency (exact equality).

Tolerance: none. The twin evaluates n . m with the same floating-point operations as the core,
so even ties (n . m = 0) must agree bit for bit.
"""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from _helpers.geometry_twins import (
    builtin,
    concave_mesh,
    front_faces,
    random_convex,
    reference_contour,
    reference_contour_any,
    sorted_rows,
)

from motionblur import Mesh, contour_edges, meshes


def closed_meshes():
    rng = np.random.default_rng(12)
    out = {
        "icosphere0": builtin(meshes.icosphere, 0),
        "icosphere3": builtin(meshes.icosphere, 3),
        "box": builtin(meshes.box),
        "box_flat": builtin(meshes.box, (2.0, 0.5, 0.01)),
        "torus": builtin(meshes.torus),
        "concave": concave_mesh(),
        "cylinder": builtin(meshes.cylinder, 0.5, 2.0, 24, 3),
    }
    for i in range(4):
        out[f"hull{i}"] = random_convex(rng)
    return out


MESHES = closed_meshes()


def motions(seed: int, n: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    m = rng.normal(size=(n, 3)) * 10.0 ** rng.uniform(-3, 3, size=(n, 1))
    axes = np.array([[1, 0, 0], [0, -1, 0], [0, 0, 1], [1, 1, 0], [0, 0, 0]], dtype=np.float64)
    return np.concatenate([m, axes])


@pytest.mark.parametrize("name", sorted(MESHES))
def test_contour_equals_trimesh_reference(name):
    tm = MESHES[name]
    mesh = Mesh(tm)
    for i, m in enumerate(motions(sum(map(ord, name)), 40)):
        got = contour_edges(mesh, m)
        assert got.dtype == np.int64 and got.shape[1] == 2
        np.testing.assert_array_equal(got, reference_contour(tm, m), err_msg=f"{name} motion {i} {m}")


@pytest.mark.parametrize("name", ["icosphere3", "torus", "concave", "hull0"])
def test_contour_line_equals_reference_with_camera(name):
    tm = MESHES[name]
    mesh = Mesh(tm)
    rng = np.random.default_rng(3)
    for _ in range(15):
        m = rng.normal(size=3)
        eye = rng.normal(size=3) * 5
        got = contour_edges(mesh, m, camera_position=eye)
        np.testing.assert_array_equal(got, reference_contour(tm, m, eye))
        assert len(got) <= len(contour_edges(mesh, m))


@pytest.mark.parametrize("name", ["icosphere3", "torus", "concave", "box", "hull1"])
def test_contours_of_closed_meshes_are_closed_oriented_loops(name):
    """Consistent orientation: every vertex has as many outgoing as incoming contour edges, and
    the front face lies to the left of each edge (it runs counter-clockwise in that face)."""
    tm = MESHES[name]
    rng = np.random.default_rng(5)
    for _ in range(10):
        m = rng.normal(size=3)
        e = contour_edges(tm, m)
        assert len(e) > 0
        out_deg = np.bincount(e[:, 0], minlength=len(tm.vertices))
        in_deg = np.bincount(e[:, 1], minlength=len(tm.vertices))
        np.testing.assert_array_equal(out_deg, in_deg)
        front = front_faces(tm.vertices, tm.faces, m)
        f = tm.faces[front]
        directed = {tuple(x) for x in np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])}
        assert all(tuple(x) in directed for x in e)


def test_reversed_motion_reverses_every_edge():
    tm = MESHES["concave"]
    m = np.array([0.3, -1.2, 0.7])
    a = contour_edges(tm, m)
    b = contour_edges(tm, -m)
    np.testing.assert_array_equal(a[:, ::-1], b)


def test_scale_of_motion_does_not_matter():
    tm = MESHES["torus"]
    m = np.array([0.3, -1.2, 0.7])
    np.testing.assert_array_equal(contour_edges(tm, m), contour_edges(tm, m * 1e6))


def test_perpendicular_faces_and_one_ulp():
    """Hard case: box faces with n . m = 0 are front (paper's >=); perturbing the motion by the
    smallest subnormal tips the +y faces to front and the -y faces to back (contour grows from
    the 4-edge square to the 6-edge L)."""
    tm = MESHES["box"]
    tiny = np.nextafter(0.0, 1.0)
    for m, n_edges in [([1.0, 0.0, 0.0], 4), ([1.0, tiny, 0.0], 6), ([1.0, -tiny, 0.0], 6)]:
        got = contour_edges(tm, m)
        assert len(got) == n_edges, m
        np.testing.assert_array_equal(got, reference_contour(tm, m))


def test_zero_motion_has_no_contour_on_a_closed_mesh():
    assert contour_edges(MESHES["icosphere3"], [0.0, 0.0, 0.0]).shape == (0, 2)


def test_open_nonmanifold_and_degenerate_follow_the_documented_rule():
    """Boundary edges are always contour edges; non-manifold edges by net winding; a zero-area
    face is front (n . m = 0). Checked against the numpy twin of the rule."""
    v, f = meshes.icosphere(2)
    rng = np.random.default_rng(9)
    open_f = f[rng.permutation(len(f))[:-25]]  # holes
    fin_v = np.vstack([v, [[3.0, 0.0, 0.0]], v[:1]])  # an extra vertex and a duplicate of vertex 0
    fin_f = np.vstack([f, [[f[0, 0], f[0, 1], len(v)]], [[f[1, 0], f[1, 1], f[1, 1]]], [[0, 1, len(v) + 1]]])
    for verts, faces in [(v, open_f), (fin_v, fin_f)]:
        mesh = Mesh(verts, faces)
        st = mesh.stats
        assert st["boundary_edges"] + st["nonmanifold_edges"] > 0
        for _ in range(10):
            m = rng.normal(size=3)
            got = contour_edges(mesh, m)
            np.testing.assert_array_equal(got, sorted_rows(reference_contour_any(verts, faces, m)))
    # Every boundary edge of the open mesh is in the contour, whatever the motion.
    mesh = Mesh(v, open_f)
    e = mesh.edges()[mesh.edge_face_counts() == 1]
    c = {tuple(sorted(x)) for x in contour_edges(mesh, [0.0, 0.0, 1.0])}
    assert all(tuple(x) in c for x in e)


def test_trimesh_object_is_accepted_and_caller_arrays_unchanged():
    v, f = meshes.icosphere(1)
    v32 = v.astype(np.float32)
    f32 = f.astype(np.int32)
    before = (v32.copy(), f32.copy())
    m = np.array([1.0, 2.0, 3.0])
    m0 = m.copy()
    a = contour_edges(Mesh(v32, f32), m)
    b = contour_edges(trimesh.Trimesh(v32, f32, process=False), m)
    np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(v32, before[0])
    np.testing.assert_array_equal(f32, before[1])
    np.testing.assert_array_equal(m, m0)


@pytest.mark.parametrize(
    "motion, cam, exc, text",
    [
        ([np.nan, 0, 0], None, ValueError, "motion"),
        ([1, 0], None, ValueError, "motion"),
        ("abc", None, TypeError, "motion"),
        ([1, 0, 0], [0, np.inf, 0], ValueError, "camera_position"),
        ([1, 0, 0], [[0, 1, 0]], ValueError, "camera_position"),
    ],
)
def test_bad_arguments_name_themselves(motion, cam, exc, text):
    with pytest.raises(exc, match=text):
        contour_edges(MESHES["box"], motion, camera_position=cam)


def test_bad_mesh_argument():
    with pytest.raises(TypeError, match="mesh"):
        contour_edges(np.zeros((3, 3)), [1, 0, 0])


def test_large_closed_mesh_over_several_edge_chunks_equals_reference():
    """icosphere(5) with radial noise: 30,720 edges, more than one selection chunk (16,384 edges),
    so the chunk offsets of the closed-mesh edge walk are exercised."""
    v, f = meshes.icosphere(5)
    v = v * (1.0 + 0.01 * np.random.default_rng(5).standard_normal((len(v), 1)))
    tm = trimesh.Trimesh(v, f, process=False)
    mesh = Mesh(tm)
    assert len(mesh.edges()) > 16_384
    for i, m in enumerate(motions(77, 6)):
        got = contour_edges(mesh, m)
        np.testing.assert_array_equal(got, reference_contour(tm, m), err_msg=f"motion {i} {m}")
