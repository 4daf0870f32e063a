"""Per-face colours of motion volumes: leading and trailing faces keep their face's colour, joining
strips run from their front face's colour (shutter close) to their back face's (shutter open),
the volume stays closed geometrically, and bad input names ``face_colors``."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from _helpers.geometry_twins import front_faces, hull_volume, random_convex, signed_volume

from motionblur import JOINING, LEADING, TRAILING, Mesh, meshes, motion_volume, spin_volume


def colours(n, seed=0):
    return np.random.default_rng(seed).uniform(0.05, 1.0, size=(n, 4)).astype(np.float32)


@pytest.mark.parametrize("flt", ["ramp", "box"])
def test_leading_and_trailing_faces_keep_their_colour(flt):
    v, f = meshes.icosphere(2)
    m = np.array([0.8, 0.3, -0.2])
    fc = colours(len(f))
    vol = motion_volume(Mesh(v, f), m, face_colors=fc, filter=flt)
    front = front_faces(v, f, m)
    for tag, sel in ((LEADING, front), (TRAILING, ~front)):
        got = vol.rgba[vol.faces[vol.part == tag]][..., :3]  # (faces, 3 corners, rgb)
        if flt == "ramp":
            np.testing.assert_array_equal(got, np.repeat(fc[sel][:, None, :3], 3, axis=1))
        else:  # coarse faces are subdivided: each piece keeps its parent's colour
            assert (got == got[:, :1]).all()
            assert {tuple(c) for c in got[:, 0]} <= {tuple(c) for c in fc[sel][:, :3]}
    # Alpha: the face colour's alpha times the filter's.
    plain = motion_volume(Mesh(v, f), m, filter=flt)
    assert (vol.rgba[:, 3] <= fc[:, 3].max() + 1e-6).all()
    assert len(plain.faces) == len(vol.faces)
    assert len(vol.vertices) > len(plain.vertices)  # corners are not shared


def test_joining_strips_run_from_the_back_to_the_front_colour():
    v, f = meshes.box((1.0, 0.6, 0.4))
    m = np.array([2.0, 0.0, 0.0])
    fc = colours(len(f), 1)
    vol = motion_volume(Mesh(v, f), m, face_colors=fc, segments=4, filter="ramp")
    front = front_faces(v, f, m)
    tm = trimesh.Trimesh(v, f, process=False)
    strips = vol.faces[vol.part == JOINING].reshape(-1, 4, 2, 3)  # edge, segment, 2 triangles
    for s in strips:
        a0, a_end = s[0, 0, 0], s[-1, 1, 2]  # ring 0 and ring n of the strip's first vertex
        p0, p1 = vol.vertices[a0], vol.vertices[a_end]
        np.testing.assert_allclose(p1 - p0, m)
        # which faces share the edge: find the mesh edge from the ring-0 positions
        b0 = s[0, 0, 1]
        ia = np.flatnonzero((np.abs(v - vol.vertices[a0]) < 1e-12).all(1))[0]
        ib = np.flatnonzero((np.abs(v - vol.vertices[b0]) < 1e-12).all(1))[0]
        adj = [k for k, e in zip(tm.face_adjacency, tm.face_adjacency_edges) if set(e) == {ia, ib}][0]
        ff, fb = (adj[0], adj[1]) if front[adj[0]] else (adj[1], adj[0])
        np.testing.assert_allclose(vol.rgba[a0, :3], fc[fb, :3], atol=1e-6)
        np.testing.assert_allclose(vol.rgba[a_end, :3], fc[ff, :3], atol=1e-6)
        mid = s[1, 1, 2]  # ring 2 of 4: halfway
        np.testing.assert_allclose(vol.rgba[mid, :3], (fc[ff, :3] + fc[fb, :3]) / 2, atol=1e-6)


def test_joining_strip_colour_at_ring_zero_includes_the_filter_alpha():
    v, f = meshes.box()
    fc = colours(len(f), 2)
    vol = motion_volume(Mesh(v, f), [3.0, 0, 0], face_colors=fc, filter="ramp")
    j = np.unique(vol.faces[vol.part == JOINING])
    assert (vol.rgba[j, 3] <= fc[:, 3].max() + 1e-6).all()


def test_closed_geometrically_with_the_hull_volume():
    rng = np.random.default_rng(9)
    for _ in range(10):
        tm = random_convex(rng)
        v = np.asarray(tm.vertices)
        m = rng.normal(size=3)
        vol = motion_volume(tm, m, face_colors=colours(len(tm.faces)), segments=2)
        merged = trimesh.Trimesh(vol.vertices, vol.faces, process=True)  # merge equal positions
        assert merged.is_watertight and merged.is_winding_consistent
        c = v.mean(axis=0)
        want = hull_volume(v, v + m, center=c)
        assert abs(signed_volume(vol.vertices, vol.faces, c) - want) <= 1e-9 * want


def test_camera_rule_gives_a_one_sided_strip_one_colour():
    v, f = meshes.icosphere(3)
    rot = np.eye(4)
    c, s = np.cos(0.6), np.sin(0.6)
    rot[:2, :2] = [[c, -s], [s, c]]
    rot[0, 3] = 1.5
    keys = np.stack([np.eye(4), rot])
    fc = colours(len(f), 3)
    vol = motion_volume(Mesh(v, f), keys, face_colors=fc, camera_position=[0.5, 0, 6])
    j = vol.faces[vol.part == JOINING].reshape(-1, 2, 3)
    start, end = vol.rgba[j[:, 0, 0], :3], vol.rgba[j[:, 1, 2], :3]
    one_sided = np.all(start == end, axis=1)
    assert one_sided.any() and (~one_sided).any()


def test_static_and_spin_accept_face_colours():
    v, f = meshes.box()
    fc = colours(len(f), 4)
    still = motion_volume(Mesh(v, f), [0.0, 0.0, 0.0], face_colors=fc)
    assert len(still.vertices) == 3 * len(f) and (still.part == LEADING).all()
    np.testing.assert_array_equal(still.rgba[still.faces][..., :3], np.repeat(fc[:, None, :3], 3, axis=1))
    assert (still.rgba[:, 3] == np.repeat(fc[:, 3], 3)).all()
    spin = spin_volume(Mesh(v + [0.8, 0, 0], f), [0, 0, 1], 2.0, face_colors=fc[:, :3])
    assert np.isfinite(spin.rgba).all() and len(spin.faces) > len(f)


@pytest.mark.parametrize(
    "kwargs, exc, text",
    [
        (dict(face_colors=np.ones((5, 3))), ValueError, "face_colors"),
        (dict(face_colors=np.ones((12, 2))), ValueError, "face_colors"),
        (dict(face_colors=[1.0, 0.0, 0.0]), ValueError, "face_colors"),
        (dict(face_colors=np.full((12, 3), np.nan)), ValueError, "face_colors"),
        (dict(face_colors=np.full((12, 4), 2.0)), ValueError, "face_colors"),
        (dict(face_colors=np.ones((12, 3)), colors=[1, 0, 0]), ValueError, "face_colors"),
        (dict(face_colors=np.array([["a", "b", "c"]] * 12)), TypeError, "face_colors"),
    ],
)
def test_bad_face_colours_name_the_argument(kwargs, exc, text):
    v, f = meshes.box()
    copies = {k: np.array(x, copy=True) for k, x in kwargs.items()}
    with pytest.raises(exc, match=text):
        motion_volume(Mesh(v, f), [1.0, 0, 0], **kwargs)
    for k, c in copies.items():
        np.testing.assert_array_equal(np.asarray(kwargs[k]), c)
