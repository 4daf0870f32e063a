"""Mesh: copies, dtypes, stats, normals and adjacency against trimesh and numpy twins."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from _helpers.geometry_twins import builtin, concave_mesh, raw_normals

from motionblur import Mesh, contour_edges, meshes


@pytest.mark.parametrize("vdtype", [np.float32, np.float64])
@pytest.mark.parametrize("fdtype", [np.int32, np.uint16, np.int64, np.uint64])
def test_dtypes_are_converted_into_an_own_copy(vdtype, fdtype):
    v, f = meshes.icosphere(1)
    v, f = v.astype(vdtype), f.astype(fdtype)
    v0, f0 = v.copy(), f.copy()
    m = Mesh(v, f)
    assert m.vertices.dtype == np.float64 and m.vertices.shape == v.shape
    assert m.faces.dtype == np.int64 and m.faces.shape == f.shape
    np.testing.assert_array_equal(m.vertices, v.astype(np.float64))
    assert not np.shares_memory(m.vertices, v)
    v[:] = 7  # the caller changes its array afterwards: the mesh keeps its own
    assert not (m.vertices == 7).any()
    assert not m.vertices.flags.writeable and not m.faces.flags.writeable
    np.testing.assert_array_equal(f, f0)
    del v0


def test_from_trimesh_and_from_mesh():
    tm = builtin(meshes.torus)
    m = Mesh(tm)
    np.testing.assert_array_equal(m.vertices, tm.vertices)
    np.testing.assert_array_equal(m.faces, tm.faces)
    assert Mesh(m).faces is m.faces
    assert len(m) == len(tm.faces)


@pytest.mark.parametrize("make", [meshes.box, meshes.torus, meshes.uv_sphere, concave_mesh])
def test_edges_and_stats_match_trimesh(make):
    tm = make() if make is concave_mesh else builtin(make)
    m = Mesh(tm)
    edges = m.edges()
    want = np.unique(np.sort(tm.edges, axis=1), axis=0)
    np.testing.assert_array_equal(edges, want)
    st = m.stats
    assert st["faces"] == len(tm.faces) and st["vertices"] == len(tm.vertices)
    assert st["edges"] == len(tm.edges_unique)
    assert st["closed"] == (tm.is_watertight and tm.is_winding_consistent)
    assert st["boundary_edges"] == st["nonmanifold_edges"] == st["inconsistent_edges"] == 0
    assert (m.edge_face_counts() == 2).all()


def test_stats_of_a_broken_mesh_match_numpy():
    v, f = meshes.icosphere(2)
    rng = np.random.default_rng(4)
    f = f[rng.permutation(len(f))[:-7]]  # holes
    extra = np.array([[f[0, 0], f[0, 1], 5], [f[3, 1], f[3, 0], 9], [2, 2, 7], [8, 8, 8]])  # fins, degenerate
    f = np.vstack([f, extra, f[10:11, ::-1]])  # and one face flipped onto another
    n0 = len(v)
    v = np.vstack([v, v[:1], [[5.0, 5.0, 5.0]], [[9, 0, 0], [9, 1, 0], [9, 0, 1], [9, -1, -1]]])
    # a zero-area face through coincident vertices (v[n0] == v[0]); n0 + 1 is unreferenced;
    # a patch whose two faces run edge (n0+2, n0+3) the same way (inconsistent winding)
    f = np.vstack([f, [[0, n0, 1]], [[n0 + 2, n0 + 3, n0 + 4], [n0 + 2, n0 + 3, n0 + 5]]])
    m = Mesh(v, f)
    st = m.stats
    he = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
    he = he[he[:, 0] != he[:, 1]]
    key, inv, counts = np.unique(np.sort(he, axis=1), axis=0, return_inverse=True, return_counts=True)
    net = np.bincount(inv.reshape(-1), weights=np.where(he[:, 0] < he[:, 1], 1, -1))
    assert st["edges"] == len(key)
    assert st["boundary_edges"] == (counts == 1).sum()
    assert st["nonmanifold_edges"] == (counts >= 3).sum()
    np.testing.assert_array_equal(m.edge_face_counts(), counts)
    assert st["degenerate_faces"] == (np.abs(raw_normals(v, f)).sum(1) == 0).sum() == 3
    assert st["unreferenced_vertices"] == 1
    assert st["inconsistent_edges"] == ((counts == 2) & (net != 0)).sum() == 1
    assert not st["closed"]


def test_face_and_vertex_normals_match_trimesh_and_numpy():
    tm = concave_mesh()
    m = Mesh(tm)
    np.testing.assert_allclose(m.face_normals(), tm.face_normals, atol=1e-12)
    np.testing.assert_array_equal(m.face_normals(unit=False), raw_normals(tm.vertices, tm.faces))
    raw = raw_normals(tm.vertices, tm.faces)
    acc = np.zeros_like(tm.vertices)
    for k in range(3):
        np.add.at(acc, tm.faces[:, k], raw)
    want = acc / np.linalg.norm(acc, axis=1, keepdims=True)
    np.testing.assert_allclose(m.vertex_normals(), want, atol=1e-12)


def test_degenerate_face_normal_is_zero():
    v = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [0, 1, 0]], dtype=float)
    m = Mesh(v, [[0, 1, 2], [0, 1, 3]])
    np.testing.assert_array_equal(m.face_normals()[0], [0, 0, 0])
    assert m.stats["degenerate_faces"] == 1


def test_adjacency_is_built_once_and_shared_by_deformed_copies():
    v, f = meshes.icosphere(3)
    m = Mesh(v, f)
    assert not m.has_adjacency
    contour_edges(m, [1, 0, 0])
    assert m.has_adjacency
    d = m.with_vertices(v * [1.0, 2.0, 0.5])
    assert d.has_adjacency  # shared, not rebuilt
    assert d.faces is m.faces
    np.testing.assert_array_equal(d.vertices, v * [1.0, 2.0, 0.5])
    np.testing.assert_array_equal(d.edges(), m.edges())
    with pytest.raises(ValueError, match="vertices"):
        m.with_vertices(v[:-1])


@pytest.mark.parametrize(
    "vertices, faces, exc, text",
    [
        (
            np.array([[0, 0, np.nan], [1, 0, 0], [0, 1, 0]]),
            [[0, 1, 2]],
            ValueError,
            "vertices: vertex 0 is NaN or inf",
        ),
        (np.array([[0, 0, np.inf], [1, 0, 0], [0, 1, 0]]), [[0, 1, 2]], ValueError, "vertices"),
        (np.eye(3), [[0, 1, 3]], ValueError, "faces: face 0 has an index out of range"),
        (np.eye(3), [[0, -1, 2]], ValueError, "faces: face 0 has an index out of range"),
        (np.eye(3), [[0.0, 1.0, 2.0]], TypeError, "faces: expected an integer"),
        (np.eye(3)[:, :2], [[0, 1, 2]], ValueError, "vertices: expected shape"),
        (np.eye(3), [[0, 1, 2, 0]], ValueError, "faces: expected shape"),
        (np.zeros((0, 3)), [[0, 1, 2]], ValueError, "vertices: is empty"),
        (np.eye(3), np.zeros((0, 3), dtype=int), ValueError, "faces: is empty"),
        (np.array([["a", "b", "c"]]), [[0, 0, 0]], TypeError, "vertices"),
        (np.eye(3), [[0, 1, 2**40]], ValueError, "faces"),
    ],
)
def test_bad_input_names_the_argument_and_leaves_arrays_alone(vertices, faces, exc, text):
    faces = np.asarray(faces)
    vb, fb = vertices.copy(), faces.copy()
    with pytest.raises(exc, match=text):
        Mesh(vertices, faces)
    np.testing.assert_array_equal(vertices, vb)
    np.testing.assert_array_equal(faces, fb)


def test_not_a_mesh_is_a_type_error():
    with pytest.raises(TypeError, match="mesh"):
        Mesh(object())
    with pytest.raises(TypeError, match="mesh"):
        Mesh(trimesh)  # a module has neither .vertices nor .faces
