"""ContourTable (section 4.4): stored sets equal contour_edges for their direction; lookups pick
the nearest direction and report the exact angle to it (numpy twin, 1e-12)."""

from __future__ import annotations

import numpy as np
import pytest
from _helpers.geometry_twins import concave_mesh, front_faces

from motionblur import ContourTable, Mesh, contour_edges, meshes


@pytest.fixture(scope="module")
def blob():
    return Mesh(concave_mesh())


def test_directions_are_unit_seeded_and_spread(blob):
    t = ContourTable(blob, directions=256, seed=5)
    d = t.directions
    assert d.shape == (256, 3) and d.dtype == np.float64 and len(t) == 256
    np.testing.assert_allclose(np.linalg.norm(d, axis=1), 1.0, atol=1e-12)
    np.testing.assert_array_equal(d, ContourTable(blob, 256, seed=5).directions)
    assert not np.array_equal(d, ContourTable(blob, 256, seed=6).directions)
    # Uniform on the sphere: the mean is near zero and each octant gets a share.
    assert np.linalg.norm(d.mean(axis=0)) < 0.15
    octant = (d > 0) @ [1, 2, 4]
    assert np.bincount(octant, minlength=8).min() > 10


def test_stored_sets_equal_contour_edges_for_their_direction(blob):
    t = ContourTable(blob, directions=24, seed=1)
    v, f = blob.vertices, blob.faces
    for k, d in enumerate(t.directions):
        np.testing.assert_array_equal(t.edges(k), contour_edges(blob, d))
        np.testing.assert_array_equal(t.front_faces(k), front_faces(v, f, d))


def test_lookup_is_the_nearest_direction_with_its_angle(blob, rng):
    t = ContourTable(blob, directions=64, seed=2)
    d = t.directions
    for _ in range(50):
        m = rng.normal(size=3) * 10.0 ** rng.uniform(-3, 3)
        edges, err = t.lookup(m)
        u = m / np.linalg.norm(m)
        k = int(np.argmax(d @ u))
        assert t.nearest(m)[0] == k
        np.testing.assert_array_equal(edges, contour_edges(blob, d[k]))
        assert abs(err - np.arccos(np.clip(d[k] @ u, -1, 1))) < 1e-12
    # A stored direction is found exactly and gives the live result.
    edges, err = t.lookup(d[17] * 3.0)
    assert err < 1e-7
    np.testing.assert_array_equal(edges, contour_edges(blob, d[17]))


def test_more_directions_give_smaller_errors():
    mesh = Mesh(*meshes.icosphere(2))
    rng = np.random.default_rng(1)
    probes = rng.normal(size=(200, 3))
    errs = []
    for k in (16, 256, 4096):
        t = ContourTable(mesh, directions=k, seed=0)
        errs.append(np.array([t.nearest(p)[1] for p in probes]))
    med = [np.median(e) for e in errs]
    assert med[0] > med[1] > med[2]
    # Covering radius of K uniform points on the sphere scales like K^-1/2.
    assert errs[2].max() < 0.12


def test_given_directions_cluster_around_a_preferred_motion(blob):
    fwd = np.array([1.0, 0.0, 0.0])
    rng = np.random.default_rng(3)
    dirs = fwd + 0.05 * rng.normal(size=(32, 3))
    t = ContourTable(blob, directions=dirs)
    np.testing.assert_allclose(t.directions, dirs / np.linalg.norm(dirs, axis=1, keepdims=True), atol=1e-15)
    _, err = t.lookup([1.0, 0.01, 0.0])
    assert err < 0.05
    assert t.storage_bytes > 0


@pytest.mark.parametrize(
    "kwargs, exc, text",
    [
        (dict(directions=0), ValueError, "directions"),
        (dict(directions=10**7), ValueError, "directions"),
        (dict(directions=np.zeros((2, 3))), ValueError, "directions"),
        (dict(directions=np.ones((2, 2))), ValueError, "directions"),
        (dict(directions=[[np.nan, 0, 1]]), ValueError, "directions"),
        (dict(directions=4.5), TypeError, "directions"),
        (dict(seed=-1), ValueError, "seed"),
        (dict(seed=1.5), TypeError, "seed"),
    ],
)
def test_bad_construction(blob, kwargs, exc, text):
    with pytest.raises(exc, match=text):
        ContourTable(blob, **kwargs)


def test_bad_lookup(blob):
    t = ContourTable(blob, 8)
    m = np.array([0.0, 0.0, 0.0])
    with pytest.raises(ValueError, match="motion"):
        t.lookup(m)
    with pytest.raises(ValueError, match="motion"):
        t.lookup([1.0, np.nan, 0])
    with pytest.raises(ValueError, match="index"):
        t.edges(8)
    np.testing.assert_array_equal(m, 0.0)


# --- the table driving the motion volume (section 4.4) ---

VOLUME_PARTS = ("vertices", "faces", "rgba", "normals", "part")


@pytest.mark.parametrize("shape", ["sphere", "box"])
def test_a_stored_direction_gives_exactly_the_volume_without_a_table(shape):
    """The table's split and contour for the motion's own direction are the ones computed for
    it: the volume is the same array for array (a dense sphere sweeps the stored contour; the
    12-face box is subdivided for its alphas and maps the stored split to its new faces)."""
    from motionblur import motion_volume

    v, f = meshes.icosphere(4, 0.5) if shape == "sphere" else meshes.box((0.6, 0.5, 0.4))
    mesh = Mesh(v, f)
    move = np.array([0.9, 0.3, -0.4])
    table = ContourTable(mesh, directions=np.vstack([[0.0, 1.0, 0.0], move, [1.0, 0.0, 0.0]]))
    for kw in ({}, {"camera_position": [0.3, 0.4, 4.0], "visible_only": True}):
        want = motion_volume(mesh, move, segments=2, filter="box", **kw)
        got = motion_volume(mesh, move, segments=2, filter="box", contour_table=table, **kw)
        assert got.contour_error < 1e-6 and want.contour_error == 0.0
        for k in VOLUME_PARTS:
            np.testing.assert_array_equal(getattr(got, k), getattr(want, k), err_msg=k)


def test_a_nearby_direction_bounds_the_change_of_the_image():
    """128 stochastic directions: the stored direction is 2.6-13.7 degrees off the motion and the
    volume's coverage changes by at most 0.6% per pixel (L1 over the total; 0.15% total)."""
    from motionblur import Camera, Draw, look_at, motion_volume, rasterize

    mesh = Mesh(*meshes.icosphere(4, 0.5))
    eye = np.array([0.3, 0.4, 4.0])
    cam = Camera(look_at(eye, (0, 0, 0)), 0.8, 128, 96)
    move = np.array([0.9, 0.3, -0.4])

    def coverage(**kw):
        vol = motion_volume(
            mesh, move, segments=2, filter="box", camera_position=eye, visible_only=True, **kw
        )
        img = rasterize(cam, Draw(vol.vertices, vol.faces, vol.rgba), samples=2, blend="exact").coverage
        return img, vol.contour_error

    base, _ = coverage()
    for seed in range(3):
        table = ContourTable(mesh, directions=128, seed=seed)
        got, angle = coverage(contour_table=table)
        assert angle == pytest.approx(table.nearest(move)[1], abs=1e-12) and 0 < angle < np.radians(20)
        assert abs(got.sum() / base.sum() - 1) < 0.005
        assert np.abs(got - base).sum() / base.sum() < 0.01


def test_a_table_of_another_mesh_is_refused():
    from motionblur import motion_volume

    table = ContourTable(Mesh(*meshes.icosphere(2)), directions=8)
    with pytest.raises(ValueError, match="contour_table"):
        motion_volume(Mesh(*meshes.icosphere(3)), [1.0, 0, 0], filter="box", contour_table=table)
    with pytest.raises(TypeError, match="contour_table"):
        motion_volume(Mesh(*meshes.icosphere(2)), [1.0, 0, 0], filter="box", contour_table="yes")
