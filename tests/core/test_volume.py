"""motion_volume against the exact oracle and numpy twins.

The oracle: for a convex mesh under pure translation the swept volume is the convex hull of the
mesh at shutter open and at shutter close. The single-segment motion volume must be watertight,
consistently wound, and enclose the hull's volume to 1e-9 relative (both volumes are computed
about the same centre, so that offsets do not cost digits).
"""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest
import trimesh
from _helpers.geometry_twins import (
    builtin,
    concave_mesh,
    dot3,
    front_faces,
    hull_volume,
    random_convex,
    raw_normals,
    signed_volume,
    swept_volume,
)

from motionblur import JOINING, LEADING, TRAILING, Mesh, contour_edges, meshes, motion_volume


def check_closed(vol, what=""):
    tm = trimesh.Trimesh(vol.vertices, vol.faces, process=False)
    assert tm.is_watertight, what
    assert tm.is_winding_consistent, what
    return tm


def check_boundary_free(vol):
    """Closed as a 2-chain: every directed edge a->b is matched by as many b->a. A concave mesh's
    contour can touch itself at a vertex (four contour edges there), so trimesh's
    exactly-two-faces-per-edge test does not apply; this is the closedness that does."""
    f = vol.faces
    he = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
    key = np.sort(he, axis=1)
    sign = np.where(he[:, 0] < he[:, 1], 1, -1)
    _, inv = np.unique(key, axis=0, return_inverse=True)
    assert (np.bincount(inv.reshape(-1), weights=sign) == 0).all()


def translate_keys(*offsets):
    k = np.repeat(np.eye(4)[None], len(offsets), axis=0)
    k[:, :3, 3] = offsets
    return k


def rot_z(angle, t=(0.0, 0.0, 0.0)):
    c, s = np.cos(angle), np.sin(angle)
    m = np.eye(4)
    m[:2, :2] = [[c, -s], [s, c]]
    m[:3, 3] = t
    return m


def test_convex_oracle_hundreds_of_random_cases():
    rng = np.random.default_rng(2024)
    worst = 0.0
    for i in range(300):
        tm = random_convex(rng)
        v = np.asarray(tm.vertices)
        m = rng.normal(size=3) * 10.0 ** rng.uniform(-2, 1)
        vol = motion_volume(tm, m)
        check_closed(vol, f"case {i}")
        c = v.mean(axis=0)
        got = signed_volume(vol.vertices, vol.faces, c)
        want = hull_volume(v, v + m, center=c)
        assert got > 0, f"case {i}: inward"
        worst = max(worst, abs(got - want) / want)
        assert abs(got - want) <= 1e-9 * want, f"case {i}: {got} vs {want}"
        # and the analytic swept volume (volume + |m| * shadow area)
        assert abs(got - swept_volume(tm, m)) <= 1e-9 * want
    assert worst <= 1e-9


@pytest.mark.parametrize("n", [2, 3, 5, 8])
def test_straight_path_in_n_segments_gives_the_same_volume(n):
    rng = np.random.default_rng(n)
    for _ in range(20):
        tm = random_convex(rng)
        v = np.asarray(tm.vertices)
        m = rng.normal(size=3) * 2
        one = motion_volume(tm, m)
        many = motion_volume(tm, m, segments=n)
        check_closed(many)
        assert many.segments == n
        assert (many.part == JOINING).sum() == 2 * n * one.contour_count
        c = v.mean(axis=0)
        a, b = signed_volume(one.vertices, one.faces, c), signed_volume(many.vertices, many.faces, c)
        assert abs(a - b) <= 1e-9 * a
        # The same path as n+1 translation keyframes.
        keys = translate_keys(*[m * (k / n) for k in range(n + 1)])
        kv = motion_volume(tm, keys)
        assert kv.segments == n
        assert abs(signed_volume(kv.vertices, kv.faces, c) - a) <= 1e-9 * a


def test_zero_motion_returns_the_mesh_itself_opaque():
    tm = concave_mesh()
    for motion in ([0.0, 0.0, 0.0], translate_keys([0, 0, 0], [0, 0, 0], [0, 0, 0])):
        for flt in ("ramp", "box", "gaussian"):
            vol = motion_volume(tm, motion, filter=flt, colors=[0.2, 0.4, 0.6, 1.0])
            np.testing.assert_array_equal(vol.vertices, tm.vertices)
            np.testing.assert_array_equal(vol.faces, tm.faces)
            assert (vol.part == LEADING).all()
            assert (vol.rgba[:, 3] == 1.0).all()
            np.testing.assert_allclose(vol.rgba[:, :3], [[0.2, 0.4, 0.6]] * len(vol.rgba), rtol=1e-7)


def test_parts_are_the_front_faces_at_close_and_back_faces_at_open():
    tm = concave_mesh()
    v, f = np.asarray(tm.vertices), np.asarray(tm.faces)
    m = np.array([0.4, -0.3, 1.1])
    vol = motion_volume(tm, m)
    front = front_faces(v, f, m)
    lead = vol.faces[vol.part == LEADING]
    trail = vol.faces[vol.part == TRAILING]
    np.testing.assert_array_equal(vol.vertices[lead], (v + m)[f[front]])
    np.testing.assert_array_equal(vol.vertices[trail], v[f[~front]])
    # Joining quads connect each contour edge at open (v) to itself at close (v + m).
    e = contour_edges(tm, m)
    assert vol.contour_count == len(e)
    j = vol.faces[vol.part == JOINING].reshape(-1, 2, 3)
    a0, b0, b1 = j[:, 0, 0], j[:, 0, 1], j[:, 0, 2]
    a1 = j[:, 1, 2]
    np.testing.assert_array_equal(vol.vertices[a0], v[e[:, 0]])
    np.testing.assert_array_equal(vol.vertices[b0], v[e[:, 1]])
    np.testing.assert_array_equal(vol.vertices[b1], (v + m)[e[:, 1]])
    np.testing.assert_array_equal(vol.vertices[a1], (v + m)[e[:, 0]])
    check_boundary_free(vol)  # a concave mesh still gives a closed surface (it may self-intersect)


def extent(v, d):
    d = d / np.linalg.norm(d)
    x = v @ d
    return x.max() - x.min()


def test_ramp_alpha_is_the_papers_formula():
    v, f = meshes.icosphere(2)
    m = np.array([0.7, 0.2, -0.1])
    vol = motion_volume(Mesh(v, f), m, colors=[1, 1, 1, 0.5])
    a = max(0.1, 1 - np.linalg.norm(m) / extent(v, m))
    np.testing.assert_allclose(vol.ring_alpha, [a, 1.0], rtol=1e-12)
    lead = np.unique(vol.faces[vol.part == LEADING])
    trail = np.unique(vol.faces[vol.part == TRAILING])
    np.testing.assert_allclose(vol.rgba[lead, 3], 0.5, rtol=1e-6)
    only_trail = np.setdiff1d(trail, lead)
    np.testing.assert_allclose(vol.rgba[only_trail, 3], 0.5 * a, rtol=1e-6)
    # The floor: a motion 10x the size.
    far = motion_volume(Mesh(v, f), m * 20)
    np.testing.assert_allclose(far.ring_alpha, [0.1, 1.0])


def test_multi_segment_ramp_follows_section_4_2():
    """Ring i has alpha max(0.1, 1 - sum of the lengths of segments i+1..n / extent)."""
    v, f = meshes.icosphere(2)
    pos = np.array([[0, 0, 0], [0.3, 0, 0], [0.5, 0.4, 0], [0.6, 0.5, 0.5]], dtype=float)
    vol = motion_volume(Mesh(v, f), translate_keys(*pos))
    seg = np.linalg.norm(np.diff(pos, axis=0), axis=1)
    ext = extent(v, pos[-1] - pos[0])
    want = [max(0.1, 1 - seg[i:].sum() / ext) for i in range(3)] + [1.0]
    np.testing.assert_allclose(vol.ring_alpha, want, rtol=1e-12)
    # Joining vertex alphas are ring alphas; ring vertices sit on the keyframe placements.
    j = np.unique(vol.faces[vol.part == JOINING])
    assert set(np.round(vol.rgba[j, 3], 5)) <= set(np.round(np.float32(want), 5))


def test_per_vertex_colours_and_normals_follow_their_vertex(rng):
    tm = concave_mesh()
    v, f = np.asarray(tm.vertices), np.asarray(tm.faces)
    col = rng.uniform(0, 1, size=(len(v), 3)).astype(np.float32)
    m = np.array([0.2, 0.9, 0.1])
    vol = motion_volume(tm, m, colors=col)
    front = front_faces(v, f, m)
    np.testing.assert_array_equal(vol.rgba[vol.faces[vol.part == LEADING]][..., :3], col[f[front]])
    np.testing.assert_array_equal(vol.rgba[vol.faces[vol.part == TRAILING]][..., :3], col[f[~front]])
    assert vol.rgba.dtype == np.float32 and vol.normals.dtype == np.float32
    raw = raw_normals(v, f)
    acc = np.zeros_like(v)
    for k in range(3):
        np.add.at(acc, f[:, k], raw)
    vn = acc / np.linalg.norm(acc, axis=1, keepdims=True)
    np.testing.assert_allclose(vol.normals[vol.faces[vol.part == LEADING]], vn[f[front]], atol=1e-6)
    given = np.tile([0.0, 0.0, 2.0], (len(v), 1))
    vol2 = motion_volume(tm, m, normals=given)
    np.testing.assert_array_equal(vol2.normals, np.tile(np.float32([0, 0, 1]), (len(vol2.normals), 1)))


def test_rotating_keyframes_orient_the_contour_at_every_time():
    """Section 4.3: with rotation, ring i is the contour placed by keyframe i; the volume stays
    closed; normals are rotated with their ring."""
    v, f = meshes.box((1.0, 0.5, 0.3))
    keys = np.stack([rot_z(0.0), rot_z(0.2, (0.5, 0.1, 0)), rot_z(0.4, (1.0, 0.3, 0))])
    vol = motion_volume(Mesh(v, f), keys)
    check_closed(vol)
    assert vol.segments == 2
    m_world = keys[2, :3, 3] - keys[0, :3, 3]  # the centroid is the origin
    m_obj = keys[2, :3, :3].T @ m_world
    e = contour_edges(Mesh(v, f), m_obj)
    assert vol.contour_count == len(e)
    ring1 = np.unique(vol.faces[vol.part == JOINING])
    placed = (keys[1, :3, :3] @ v[np.unique(e)].T).T + keys[1, :3, 3]
    got = {tuple(np.round(p, 9)) for p in vol.vertices[ring1]}
    assert all(tuple(np.round(p, 9)) in got for p in placed)
    lead = vol.faces[vol.part == LEADING]
    np.testing.assert_allclose(
        vol.vertices[lead],
        ((keys[2, :3, :3] @ v.T).T + keys[2, :3, 3])[f[front_faces(v, f, m_obj)]],
        atol=1e-12,
    )
    # Subdividing the rotation (slerp) keeps it closed and adds rings.
    fine = motion_volume(Mesh(v, f), keys, segments=3)
    assert fine.segments == 6
    check_closed(fine)


def test_camera_sweeps_only_the_contour_line_and_uses_the_visible_normals():
    tm = builtin(meshes.icosphere, 3)
    v, f = np.asarray(tm.vertices), np.asarray(tm.faces)
    m = np.array([1.5, 0.0, 0.0])
    eye = np.array([0.5, 0.0, 6.0])
    vol = motion_volume(tm, m, camera_position=eye)
    front = front_faces(v, f, m)
    raw = raw_normals(v, f)
    vis_lead = dot3(raw, eye - (v + m)[f[:, 0]]) > 0
    vis_trail = dot3(raw, eye - v[f[:, 0]]) > 0
    visible = np.where(front, vis_lead, vis_trail)
    adj = tm.face_adjacency
    sel = (front[adj[:, 0]] != front[adj[:, 1]]) & (visible[adj[:, 0]] | visible[adj[:, 1]])
    assert vol.contour_count == sel.sum() < len(contour_edges(tm, m))
    assert (vol.part == JOINING).sum() == 2 * sel.sum()
    # With a rotation, an edge whose leading side is hidden takes the trailing normals.
    keys = np.stack([rot_z(0.0), rot_z(0.6, (1.5, 0, 0))])
    rv = motion_volume(tm, keys, camera_position=eye)
    j = rv.faces[rv.part == JOINING].reshape(-1, 2, 3)
    n_a0, n_a1 = rv.normals[j[:, 0, 0]], rv.normals[j[:, 1, 2]]
    same = np.all(n_a0 == n_a1, axis=1)
    assert same.any()  # edges with one side hidden use one side's normal for the whole strip
    rot = keys[1, :3, :3]
    np.testing.assert_allclose(n_a1[~same], n_a0[~same] @ rot.T, atol=1e-6)  # the others rotate
    # Default (no camera): the normal at close is the normal at open rotated by the keyframe.
    dv = motion_volume(tm, keys)
    jd = dv.faces[dv.part == JOINING].reshape(-1, 2, 3)
    np.testing.assert_allclose(dv.normals[jd[:, 1, 2]], dv.normals[jd[:, 0, 0]] @ rot.T, atol=1e-6)


def test_to_trimesh():
    vol = motion_volume(builtin(meshes.icosphere, 2), [1.0, 0.0, 0.0], colors=[1.0, 0.5, 0.0, 1.0])
    tm = vol.to_trimesh()
    assert len(tm.vertices) == len(vol.vertices) and len(tm.faces) == len(vol.faces)
    assert tm.is_watertight
    assert tm.visual.vertex_colors.dtype == np.uint8
    assert (tm.visual.vertex_colors[:, 1] == 128).all()


# --- hard cases ---------------------------------------------------------------------------------


def test_hard_perpendicular_faces_and_one_ulp():
    """n . m = 0 (box sides along the motion) and +-1 ulp tilts: closed, exact hull volume."""
    v, f = meshes.box((1.0, 2.0, 0.5))
    tiny = np.nextafter(0.0, 1.0)
    for m in ([1.0, 0.0, 0.0], [1.0, tiny, 0.0], [1.0, -tiny, 0.0], [0.0, 0.0, -3.0]):
        vol = motion_volume(Mesh(v, f), m)
        check_closed(vol, m)
        want = hull_volume(v, v + m, center=np.zeros(3))
        assert abs(signed_volume(vol.vertices, vol.faces, np.zeros(3)) - want) <= 1e-12 * want


@pytest.mark.parametrize("scale", [1e-12, 1e6])
def test_hard_tiny_and_huge_motion(scale):
    """Motion of 1e-12 and 1e6 times the mesh size: closed, volume to 1e-9 of the analytic swept
    volume (qhull's hull is only good to ~1e-6 at 1e6 because of its merge tolerances, so it is
    checked to 1e-5), ramp alpha ~1 and at the 0.1 floor."""
    tm = random_convex(np.random.default_rng(7), 30)
    v = np.asarray(tm.vertices)
    m = np.array([0.3, -0.5, 0.8]) * scale * extent(v, np.array([0.3, -0.5, 0.8]))
    vol = motion_volume(tm, m)
    check_closed(vol)
    c = v.mean(axis=0) + m / 2
    got = signed_volume(vol.vertices, vol.faces, c)
    want = swept_volume(tm, m)
    assert abs(got - want) <= 1e-9 * want
    assert abs(got - hull_volume(v, v + m, center=c)) <= 1e-5 * want
    assert vol.ring_alpha[0] == (0.1 if scale > 1 else pytest.approx(1.0, abs=1e-11))


def test_hard_mesh_far_from_the_origin():
    """Offset 1e6: coordinates keep ~1e-10 absolute precision, so the volume (about 1) agrees
    with the hull to 1e-8 relative, computed about the mesh centre."""
    tm = random_convex(np.random.default_rng(8), 25)
    v = np.asarray(tm.vertices) + 1e6
    m = np.array([0.5, 0.25, -0.3])
    vol = motion_volume(Mesh(v, tm.faces), m)
    check_closed(vol)
    c = v.mean(axis=0)
    want = hull_volume(v, v + m, center=c)
    assert abs(signed_volume(vol.vertices, vol.faces, c) - want) <= 1e-8 * want


def test_hard_degenerate_open_and_nonmanifold_meshes_do_not_break():
    """Documented result: boundary edges are swept (each gives one joining quad per segment),
    degenerate faces are front (leading), non-manifold edges by net winding; no error."""
    v, f = meshes.icosphere(2)
    half = f[v[f].mean(axis=1)[:, 2] > 0]  # an open hemisphere-like cap
    mesh = Mesh(v, half)
    m = [0.2, 0.1, 1.0]
    vol = motion_volume(mesh, m, segments=2)
    assert vol.contour_count == len(contour_edges(mesh, m))
    assert (vol.part == JOINING).sum() == 4 * vol.contour_count
    n_boundary = mesh.stats["boundary_edges"]
    assert vol.contour_count >= n_boundary > 0
    # Degenerate faces (repeated index, collinear) and a fin on an edge.
    dv = np.vstack([v, [[3.0, 0, 0]], (v[0] + v[1]) / 2])
    df = np.vstack([f, [[0, 0, 1]], [[0, 1, len(v) + 1]], [[f[0, 0], f[0, 1], len(v)]]])
    dm = Mesh(dv, df)
    assert dm.stats["degenerate_faces"] == 2 and dm.stats["nonmanifold_edges"] >= 1
    for mo in ([1.0, 0, 0], [0, 0, 1e-12], [0, -5.0, 0]):
        out = motion_volume(dm, mo)
        assert np.isfinite(out.vertices).all() and np.isfinite(out.rgba).all()
        # the degenerate faces are front, so they are in the leading surface
        assert (out.part == LEADING).sum() == front_faces(dv, df, mo).sum()


def test_hard_flat_mesh_with_zero_extent_along_the_motion():
    """A square in the xy plane moving along z: extent 0, so the ramp gives the trailing ring
    the 0.1 floor; all faces front (leading), the four border edges swept. Moving along -z all
    faces are back (trailing at open). Moving in-plane, n . m = 0: leading, extent 1."""
    v = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], dtype=float)
    f = np.array([[0, 1, 2], [0, 2, 3]])
    up = motion_volume(Mesh(v, f), [0, 0, 2.0])
    np.testing.assert_array_equal(up.ring_alpha, [0.1, 1.0])
    assert (up.part == LEADING).sum() == 2 and (up.part == TRAILING).sum() == 0
    assert up.contour_count == 4 and (up.part == JOINING).sum() == 8
    down = motion_volume(Mesh(v, f), [0, 0, -2.0])
    assert (down.part == TRAILING).sum() == 2 and down.contour_count == 4
    side = motion_volume(Mesh(v, f), [0.5, 0, 0])
    np.testing.assert_allclose(side.ring_alpha, [0.5, 1.0])
    assert (side.part == LEADING).sum() == 2


# --- bad input ----------------------------------------------------------------------------------


def good():
    v, f = meshes.box()
    return v, f


@pytest.mark.parametrize(
    "kwargs, exc, text",
    [
        (dict(motion=[np.nan, 0, 0]), ValueError, "motion"),
        (dict(motion=[np.inf, 0, 0]), ValueError, "motion"),
        (dict(motion=[1, 0]), ValueError, "motion"),
        (dict(motion=np.zeros((1, 4, 4))), ValueError, "motion"),
        (dict(motion=np.zeros((2, 3, 3))), ValueError, "motion"),
        (dict(motion=np.stack([np.eye(4), np.diag([1, 1, -1, 1.0])])), ValueError, "motion"),
        (dict(motion=np.stack([np.eye(4), np.diag([1, 2, 1, 1.0])])), ValueError, "motion"),
        (dict(motion=np.stack([np.eye(4), np.full((4, 4), np.nan)])), ValueError, "motion"),
        (dict(segments=0), ValueError, "segments"),
        (dict(segments=-2), ValueError, "segments"),
        (dict(segments=1.5), TypeError, "segments"),
        (dict(segments=10**9), ValueError, "segments"),
        (dict(filter="median"), ValueError, "filter"),
        (dict(filter=3), TypeError, "filter"),
        (dict(colors=[1, 0]), ValueError, "colors"),
        (dict(colors=np.ones((5, 3))), ValueError, "colors"),
        (dict(colors=[1, 0, 0, 2]), ValueError, "colors"),
        (dict(colors=[np.nan, 0, 0]), ValueError, "colors"),
        (dict(normals=np.ones((3, 3))), ValueError, "normals"),
        (dict(normals=np.full((8, 3), np.nan)), ValueError, "normals"),
        (dict(camera_position=[0, 0]), ValueError, "camera_position"),
        (dict(camera_position=[0, np.nan, 0]), ValueError, "camera_position"),
    ],
)
def test_bad_input_names_the_argument(kwargs, exc, text):
    v, f = good()
    args = dict(motion=[1.0, 0.0, 0.0])
    args.update(kwargs)
    copies = {k: np.array(x, copy=True) for k, x in args.items() if isinstance(x, (list, np.ndarray))}
    vb, fb = v.copy(), f.copy()
    with pytest.raises(exc, match=text):
        motion_volume(Mesh(v, f), **args)
    for k, c in copies.items():
        np.testing.assert_array_equal(np.asarray(args[k]), c)
    np.testing.assert_array_equal(v, vb)
    np.testing.assert_array_equal(f, fb)


@pytest.mark.parametrize(
    "vertices, faces, text",
    [
        (np.array([[np.nan, 0, 0], [1, 0, 0], [0, 1, 0]]), np.array([[0, 1, 2]]), "vertices"),
        (np.eye(3), np.array([[0, 1, 5]]), "faces"),
        (np.eye(3), np.array([[0, -1, 2]]), "faces"),
        (np.zeros((0, 3)), np.zeros((0, 3), dtype=int), "vertices"),
    ],
)
def test_bad_trimesh_like_input(vertices, faces, text):
    class Like:
        pass

    obj = Like()
    obj.vertices, obj.faces = vertices, faces
    with pytest.raises(ValueError, match=text):
        motion_volume(obj, [1, 0, 0])


def test_results_do_not_depend_on_the_thread_count():
    code = textwrap.dedent(
        """
        import hashlib, numpy as np, motionblur as mb
        v, f = mb.meshes.icosphere(5)
        m = mb.Mesh(v, f)
        h = hashlib.sha256()
        h.update(mb.contour_edges(m, [0.3, 0.2, -0.9]).tobytes())
        vol = mb.motion_volume(m, [0.3, 0.2, -0.9], segments=3, camera_position=[0, 0, 5])
        for a in (vol.vertices, vol.faces, vol.rgba, vol.normals, vol.part):
            h.update(a.tobytes())
        t = mb.ContourTable(m, directions=16, seed=3)
        h.update(t.lookup([1.0, 2.0, 3.0])[0].tobytes())
        print(h.hexdigest())
        """
    )
    out = []
    for n in ("1", "2"):
        env = dict(os.environ, RAYON_NUM_THREADS=n)
        r = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
        out.append(r.stdout.strip())
    assert out[0] == out[1] and len(out[0]) == 64


@pytest.mark.parametrize("filt", ["box", "ramp"])
@pytest.mark.parametrize("level", [1, 3])
def test_visible_only_draws_the_same_image_from_fewer_faces(filt, level):
    """The leading faces turned away from the camera at close and the trailing ones turned away
    at open are culled by the rasterizer anyway: leaving them out changes no pixel."""
    import motionblur as mb

    mesh = Mesh(*meshes.icosphere(level, 0.5))
    eye = np.array([0.4, 0.7, 4.0])
    cam = mb.Camera(mb.look_at(eye, (0.3, 0.1, 0.0)), 0.8, 96, 72)
    move = np.array([0.9, 0.3, -0.4])
    full = motion_volume(mesh, move, segments=2, filter=filt, camera_position=eye)
    seen = motion_volume(mesh, move, segments=2, filter=filt, camera_position=eye, visible_only=True)
    assert len(seen.faces) < 0.8 * len(full.faces)
    np.testing.assert_array_equal(seen.vertices, full.vertices)
    assert (seen.part == JOINING).sum() == (full.part == JOINING).sum()
    frames = [
        mb.rasterize(cam, mb.Draw(vol.vertices, vol.faces, vol.rgba, cull_back=True), samples=2)
        for vol in (full, seen)
    ]
    np.testing.assert_array_equal(frames[0].rgba, frames[1].rgba)
    np.testing.assert_array_equal(frames[0].depth, frames[1].depth)
    # without a camera there is nothing to be turned away from: the whole volume
    alone = motion_volume(mesh, move, segments=2, filter=filt, visible_only=True)
    assert len(alone.faces) == len(motion_volume(mesh, move, segments=2, filter=filt).faces)
    with pytest.raises(TypeError, match="visible_only"):
        motion_volume(mesh, move, camera_position=eye, visible_only="yes")
