"""Blur shells: the Rust shell against its numpy twin, each shell property of issue 5, the hard
cases, bad input, untouched caller arrays and thread-count independence."""

from __future__ import annotations

import hashlib
import os
import pickle
import subprocess
import sys
import textwrap

import numpy as np
import pytest
import trimesh
from _helpers.shell_twin import TwinShell, twin_face_edge, twin_facing, twin_normals

import motionblur as mb
from motionblur import meshes


def wobble(v: np.ndarray, k: int) -> list[np.ndarray]:
    """K positions of a deforming (non-rigid) motion of ``v``."""
    out = []
    for i in range(k):
        t = 0.37 * i
        w = np.sin(3.0 * v[:, 2] + t)[:, None] * 0.25
        out.append(v + w * [1.0, 0.0, 0.0] + [np.cos(0.7 * t) * 0.3, np.sin(1.3 * t) * 0.1, 0.05 * i])
    return out


def arm(k=9, **kw):
    pos, f = meshes.bending_arm(k, sections=12, rings=8, **kw)
    return pos, f


def strips(m: mb.ShellMesh) -> list[np.ndarray]:
    """Row indices of each strip (consecutive rows of one face)."""
    if len(m.face) == 0:
        return []
    cut = np.nonzero(np.diff(m.face) != 0)[0] + 1
    return np.split(np.arange(len(m.face)), cut)


def keyed(shell: mb.BlurShell, m: mb.ShellMesh) -> dict:
    """alpha by (face, recorded update, side); the base is recorded at update count (it becomes
    ring element 0 at the next update)."""
    rec = shell.updates - m.step.astype(np.int64)
    side = np.arange(len(m.face)) % 2
    return {(int(f), int(r), int(s)): float(a) for f, r, s, a in zip(m.face, rec, side, m.rgba[:, 3])}


def check_no_popping(shell: mb.BlurShell, seq, normals=None) -> int:
    """Feeds seq, checks the no-popping bound between consecutive builds; returns the number of
    vertex comparisons made."""
    step = shell.initial_alpha / shell.subdivisions + 1e-6
    before, faces_before, compared = None, set(), 0
    for i, v in enumerate(seq):
        shell.update(v, None if normals is None else normals[i])
        m = shell.build()
        now = keyed(shell, m)
        if before is not None:
            for key, a in before.items():
                if key in now:
                    assert abs(now[key] - a) <= step, (i, key, a, now[key])
                    compared += 1
                else:
                    assert a <= step, f"update {i}: {key} vanished at alpha {a}"
            for key, b in now.items():
                if key not in before and key[0] in faces_before:
                    old = before.get((key[0], key[1] - 1, key[2]), 0.0)
                    assert abs(b - old) <= step, (i, key, old, b)
        before, faces_before = now, set(int(f) for f in m.face)
    return compared


# --- numpy twin ------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "mesh, s, h, a, masked, colored, normals",
    [
        ("icosphere", 10, 3, 1.0, False, False, False),
        ("icosphere", 4, 0, 0.6, True, True, False),
        ("icosphere", 6, 1, 1.0, False, False, True),
        ("arm", 1, 2, 1.0, False, True, False),
        ("arm", 7, 5, 0.9, True, False, True),
    ],
)
def test_rust_shell_matches_numpy_twin(mesh, s, h, a, masked, colored, normals):
    if mesh == "icosphere":
        v, f = meshes.icosphere(2)
        seq = wobble(v, 14)
    else:
        pos, f = arm(7)
        seq = list(pos) + [pos[-1]] * 4 + list(pos[::-1])
    nv = len(seq[0])
    rng = np.random.default_rng(5)
    mask = rng.random(len(f)) > 0.3 if masked else None
    color = rng.random((nv, 3)) if colored else (0.2, 0.4, 0.9)
    ours = mb.BlurShell(f, s, h, a, mask=mask, color=color)
    twin = TwinShell(f, nv, s, h, a, mask=mask, color=None if color is None else np.asarray(color))
    nonempty = 0
    for i, v in enumerate(seq):
        # Given normals: flip every third update and tilt, so they differ from the computed ones.
        n = (v - v.mean(axis=0)) * (1 if i % 3 else -1) + [0.3, 0.0, 0.1] if normals else None
        ours.update(v, n)
        twin.update(v, n)
        st = ours.state()
        np.testing.assert_array_equal(st["facing"], twin.facing)
        np.testing.assert_array_equal(np.where(st["last_edge"] < 0, 3, st["last_edge"]), twin.last)
        np.testing.assert_array_equal(st["fade"], twin.fade)
        np.testing.assert_array_equal(st["run"], twin.run)
        np.testing.assert_array_equal(st["since"], twin.since)
        cur = v if i % 2 else None
        m, t = (
            ours.build(cur, n if cur is not None else None),
            twin.build(cur, n if cur is not None else None),
        )
        for name in ("vertices", "faces", "rgba", "normals", "face", "step"):
            np.testing.assert_array_equal(getattr(m, name), t[name], err_msg=f"{name} at update {i}")
        nonempty += len(m.faces) > 0
    assert nonempty >= len(seq) // 2


def test_motion_silhouette_matches_twin_and_geometry():
    v, f = meshes.icosphere(3)
    m = np.array([0.3, -0.2, 0.9])
    sil = mb.motion_silhouette(mb.Mesh(v + m, f), v)
    p32, q32 = (v + m).astype(np.float32), v.astype(np.float32)
    facing = twin_facing(twin_normals(p32, f), p32, q32)
    np.testing.assert_array_equal(sil.facing, facing)
    edge = twin_face_edge(facing, f)
    np.testing.assert_array_equal(sil.face_edge, np.where(edge == 3, -1, edge))
    assert len(sil.edges) > 10
    # Geometry: with the exact sphere normals, back vertices are those with p . m < 0, so every
    # silhouette edge joins two vertices on the back half next to a front one.
    sil = mb.motion_silhouette(trimesh.Trimesh(v + m, f, process=False), v, normals=v)
    d = v @ m
    assert (d[sil.edges] < 0).all()
    assert (d[f[sil.edge_faces]] > 0).sum(axis=1).min() == 1
    np.testing.assert_array_equal(np.where(d < 0, -1, 1).astype(np.int8), sil.facing)


@pytest.mark.parametrize("axis", [0, 1, 2])
def test_a_symmetric_mesh_moving_along_an_axis_keeps_its_silhouette(axis):
    """Vertices on the icosphere's equator have n . d exactly 0 when it moves along an axis;
    they count as front (>= 0), so the silhouette is as long as for a generic direction (with
    n . d == 0 neutral it had 2 edges instead of 24)."""
    v, f = meshes.icosphere(2)
    move = np.zeros(3)
    move[axis] = 0.3
    generic = mb.motion_silhouette(mb.Mesh(v + [0.21, 0.13, 0.17], f), v)
    sil = mb.motion_silhouette(mb.Mesh(v + move, f), v)
    p32, q32 = (v + move).astype(np.float32), v.astype(np.float32)
    facing = twin_facing(twin_normals(p32, f), p32, q32)
    np.testing.assert_array_equal(sil.facing, facing)
    edge = twin_face_edge(facing, f)
    np.testing.assert_array_equal(sil.face_edge, np.where(edge == 3, -1, edge))
    assert (sil.facing != 0).all()
    assert len(sil.edges) >= 0.75 * len(generic.edges), (len(sil.edges), len(generic.edges))
    # The edges run around the sphere: every silhouette vertex is on the back half, next to the
    # front half, and the edges form closed loops (each vertex starts and ends as many edges).
    d = v @ move
    assert (d[sil.edges] <= 0).all()
    np.testing.assert_array_equal(
        np.bincount(sil.edges[:, 0], minlength=len(v)), np.bincount(sil.edges[:, 1], minlength=len(v))
    )
    # The same in a blur shell: strips trail the sphere.
    m = mb.shell_over_shutter(f, [0.0, 1.0], np.stack([v, v + move]), subdivisions=3)
    assert len(np.unique(m.face)) == len(sil.edges)


# --- shell properties ------------------------------------------------------------------------


def test_strips_are_attached_and_alpha_falls_along_them():
    pos, f = arm(11)
    shell = mb.BlurShell(f, subdivisions=10, hysteresis=2, initial_alpha=0.9)
    for p in pos[:-1]:
        shell.update(p)
    m = shell.build(pos[-1])
    assert len(m) > 0
    assert m.faces.max() < len(m.vertices)
    for rows in strips(m):
        face = f[m.face[rows[0]]]
        base = rows[m.step[rows] == 0]
        assert len(base) == 2
        # Attached: the base pair is exactly an edge of its polygon on the current mesh.
        for r in base:
            assert any((pos[-1][c] == m.vertices[r]).all() for c in face)
        # Monotone: alpha never rises along the strip, by initial_alpha / S per pair.
        a = m.rgba[rows, 3]
        assert (np.diff(a) <= 0).all()
        np.testing.assert_array_equal(m.step[rows], np.repeat(np.arange(len(rows) // 2), 2))
        assert a[0] == pytest.approx(0.9) or a[0] < 0.9
    # A full strip spans the shutter: its last pair is at alpha 0 at the first position.
    full = [rows for rows in strips(m) if m.step[rows[-1]] == 10]
    assert full
    for rows in full:
        assert m.rgba[rows[-1], 3] == 0.0
        first = pos[0][f[m.face[rows[0]]]].astype(np.float32).astype(np.float64)
        assert any((first == m.vertices[rows[-1]]).all(axis=1))


def test_static_polygons_have_no_strip():
    pos, f = arm(9)
    moving = np.zeros(len(pos[0]), bool)
    for p in pos[1:]:
        moving |= (p.astype(np.float32) != pos[0].astype(np.float32)).any(axis=1)
    static_faces = ~moving[f].any(axis=1)
    assert static_faces.sum() > 50
    shell = mb.BlurShell(f, subdivisions=8)
    for p in pos:
        shell.update(p)
        m = shell.build()
        assert not static_faces[m.face].any()
    # A mesh that never moves has no strip at all, and every vertex is neutral.
    shell = mb.BlurShell(f, subdivisions=8)
    for _ in range(4):
        shell.update(pos[0])
    assert shell.build().is_empty
    assert (shell.state()["facing"] == 0).all()


def test_no_popping_bound_on_deforming_meshes():
    v, f = meshes.icosphere(2)
    seq = wobble(v, 30)
    assert check_no_popping(mb.BlurShell(f, subdivisions=6, hysteresis=2, initial_alpha=0.8), seq) > 1000
    pos, f2 = arm(8)
    back_and_forth = list(pos) + [pos[-1]] * 3 + list(pos[::-1]) + [pos[0]] * 12
    assert check_no_popping(mb.BlurShell(f2, subdivisions=5, hysteresis=1), back_and_forth) > 100


def test_mask_removes_exactly_the_masked_faces_strips():
    pos, f = arm(9)
    mask = np.random.default_rng(1).random(len(f)) > 0.4
    full = mb.shell_over_shutter(f, np.linspace(0, 1, 9), pos, subdivisions=6)
    part = mb.shell_over_shutter(f, np.linspace(0, 1, 9), pos, subdivisions=6, mask=mask)
    keep = mask[full.face]
    assert 0 < keep.sum() < len(full.face)
    np.testing.assert_array_equal(part.face, full.face[keep])
    np.testing.assert_array_equal(part.vertices, full.vertices[keep])
    np.testing.assert_array_equal(part.rgba, full.rgba[keep])
    assert not (~mask[part.source_face]).any()


def test_shell_colour_overrides_and_per_vertex_colours():
    pos, f = arm(5)
    one = mb.shell_over_shutter(f, np.linspace(0, 1, 5), pos, subdivisions=4, color=(1.0, 0.0, 0.5))
    assert (one.rgba[:, :3] == np.float32([1.0, 0.0, 0.5])).all()
    per = np.random.default_rng(2).random((len(pos[0]), 3))
    shell = mb.BlurShell(f, subdivisions=4, color=per)
    for p in pos:
        shell.update(p)
    m = shell.build()
    corner = [f[fi][list(f[fi]).index(v)] for fi, v in zip(m.face, _mesh_vertex(m, f, shell))]
    np.testing.assert_array_equal(m.rgba[:, :3], per[corner].astype(np.float32))


def test_an_rgba_colours_alpha_scales_each_strips_alpha():
    """The colour's alpha multiplies the strip's own (a translucent object's trail), per mesh
    vertex; the geometry and RGB stay those of the RGB colour, and alpha 1 is the RGB shell."""
    pos, f = arm(5)
    alphas = np.random.default_rng(3).random(len(pos[0]))
    rgb = np.full((len(pos[0]), 3), 0.5)
    shells = {
        "rgb": mb.BlurShell(f, subdivisions=4, color=(0.5, 0.5, 0.5)),
        "one": mb.BlurShell(f, subdivisions=4, color=(0.5, 0.5, 0.5, 1.0)),
        "quarter": mb.BlurShell(f, subdivisions=4, color=(0.5, 0.5, 0.5, 0.25)),
        "each": mb.BlurShell(f, subdivisions=4, color=np.column_stack([rgb, alphas])),
    }
    for p in pos:
        for shell in shells.values():
            shell.update(p)
    m = {k: sh.build() for k, sh in shells.items()}
    plain = m["rgb"]
    assert len(plain.faces) and (plain.rgba[:, 3] > 0).any()
    for k in ("one", "quarter", "each"):
        np.testing.assert_array_equal(m[k].vertices, plain.vertices)
        np.testing.assert_array_equal(m[k].rgba[:, :3], plain.rgba[:, :3])
    np.testing.assert_array_equal(m["one"].rgba, plain.rgba)
    np.testing.assert_array_equal(m["quarter"].rgba[:, 3], plain.rgba[:, 3] * np.float32(0.25))
    corner = [f[fi][list(f[fi]).index(v)] for fi, v in zip(plain.face, _mesh_vertex(plain, f, shells["rgb"]))]
    np.testing.assert_array_equal(m["each"].rgba[:, 3], plain.rgba[:, 3] * alphas[corner].astype(np.float32))
    copy = pickle.loads(pickle.dumps(shells["quarter"]))
    np.testing.assert_array_equal(copy.build().rgba, m["quarter"].rgba)
    with pytest.raises(ValueError, match="^color"):
        mb.BlurShell(f, color=(1.0, 1.0, 1.0, 1.5))


def _mesh_vertex(m, f, shell):
    """The mesh vertex behind each shell vertex, from the ring: pair j of face's strip."""
    out = []
    for r in range(len(m.face)):
        fi, j, side = int(m.face[r]), int(m.step[r]), r % 2
        k = shell.state()["last_edge"][fi] if j == 0 else shell.element(fi, j - 1)[0]
        out.append(f[fi][(k + side) % 3])
    return out


def test_update_index_and_ring_elements():
    pos, f = arm(6)
    shell = mb.BlurShell(f, subdivisions=4, hysteresis=1)
    assert shell.update_index is None and shell.build().is_empty
    for i, p in enumerate(pos):
        shell.update(p)
        assert shell.update_index == i % 4
    st = shell.state()
    on = np.nonzero(st["since"] == 0)[0]
    assert len(on) > 0
    for fi in on[:20]:
        k, flag = shell.element(int(fi), 0)
        assert flag and k == st["last_edge"][fi]
        assert shell.element(int(fi), int(st["run"][fi])) is None
    shell.reset()
    assert shell.updates == 0 and shell.build().is_empty


# --- hard cases ------------------------------------------------------------------------------


def test_a_vertex_that_does_not_move():
    v, f = meshes.icosphere(2)
    fixed = int(np.argmax(v[:, 0]))
    seq = [v + [0.1 * i, 0.0, 0.02 * i * i] for i in range(6)]
    for p in seq:
        p[fixed] = v[fixed]
    shell = mb.BlurShell(f, subdivisions=5)
    for p in seq:
        shell.update(p)
        st = shell.state()
        assert st["facing"][fixed] == 0 or shell.updates == 1
    sil = mb.motion_silhouette(mb.Mesh(seq[-1], f), seq[-2])
    assert sil.facing[fixed] == 0 and fixed not in sil.edges
    m = shell.build()
    assert len(m) > 0 and np.isfinite(m.vertices).all() and np.isfinite(m.normals).all()


def test_a_mesh_that_stops_mid_shutter():
    v, f = meshes.icosphere(2)
    t = np.linspace(0.0, 1.0, 11)
    travel = np.minimum(t, 0.5)[:, None, None] * np.array([2.0, 0.0, 0.0])
    pos = v[None] + travel
    s, h = 10, 0
    m = mb.shell_over_shutter(f, t, pos, subdivisions=s, hysteresis=h)
    assert len(m) > 0 and np.isfinite(m.vertices).all()
    # The strips lie where the mesh went: between its start and where it stopped.
    assert m.vertices[:, 0].min() >= v[:, 0].min() - 1e-6
    assert m.vertices[:, 0].max() <= v[:, 0].max() + 1.0 + 1e-6
    # At rest for 5 updates with no hysteresis, every strip has faded by 5 steps (fade rule).
    assert m.rgba[:, 3].max() <= np.float32(1.0 - 4.0 / s) + 1e-6
    # Kept at rest long enough, the shell disappears (hysteresis + subdivisions updates).
    shell = mb.BlurShell(f, subdivisions=4, hysteresis=2)
    for p in pos[:6]:
        shell.update(p)
    for _ in range(6):
        assert not shell.build().is_empty
        shell.update(pos[-1])
    assert shell.build().is_empty


@pytest.mark.parametrize("direction", [(0.0, 0.0, 1.0), (1.0, 0.0, 0.0)])
def test_a_polygon_perpendicular_to_its_motion(direction):
    # A square plate in z = 0: moving along z its plane is perpendicular to the motion (every
    # corner front: no silhouette edge, as in the paper); moving along x it slides in its own
    # plane (n . d == 0: every corner front too). Either way: no strip, no NaN, no error.
    v = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
    f = np.array([[0, 1, 2], [0, 2, 3]])
    shell = mb.BlurShell(f, subdivisions=3)
    for i in range(5):
        shell.update(v + 0.1 * i * np.array(direction))
    assert shell.build().is_empty
    assert (shell.state()["facing"] == 1).all()


def test_normals_that_flip_during_the_motion():
    v, f = meshes.icosphere(2)
    seq = wobble(v, 16)
    normals = [v * (1 if (i // 3) % 2 == 0 else -1) for i in range(16)]
    shell = mb.BlurShell(f, subdivisions=5, hysteresis=1)
    assert check_no_popping(shell, seq, normals) > 100
    m = shell.build(seq[-1], normals[-1])
    assert np.isfinite(m.normals).all()
    # Flipping the normals swaps front and back: the silhouette moves to the other side.
    a = mb.motion_silhouette(mb.Mesh(seq[1], f), seq[0], normals=v)
    b = mb.motion_silhouette(mb.Mesh(seq[1], f), seq[0], normals=-v)
    np.testing.assert_array_equal(a.facing, -b.facing)


def test_a_mesh_that_changes_vertex_count_is_a_clear_error():
    v, f = meshes.icosphere(1)
    shell = mb.BlurShell(f)
    shell.update(v)
    with pytest.raises(ValueError, match="vertices: expected 42 rows"):
        shell.update(np.concatenate([v, [[0.0, 0.0, 0.0]]]))
    with pytest.raises(ValueError, match="vertices"):
        shell.build(v[:-1])
    assert shell.updates == 1
    with pytest.raises(ValueError, match="positions: every time must have the same vertex count"):
        mb.shell_over_shutter(f, [0, 1], [v, v[:-1]])
    with pytest.raises(ValueError, match="n_vertices|faces"):
        mb.BlurShell(f, n_vertices=10)


# --- bad input, untouched arrays, threads ----------------------------------------------------


@pytest.mark.parametrize(
    "kwargs, exc, text",
    [
        ({"subdivisions": 0}, ValueError, "subdivisions"),
        ({"subdivisions": 256}, ValueError, "subdivisions"),
        ({"subdivisions": 2.5}, TypeError, "subdivisions"),
        ({"hysteresis": -1}, ValueError, "hysteresis"),
        ({"initial_alpha": 0.0}, ValueError, "initial_alpha"),
        ({"initial_alpha": 1e-50}, ValueError, "initial_alpha"),  # 0 in the core's float32
        ({"initial_alpha": 1.5}, ValueError, "initial_alpha"),
        ({"initial_alpha": float("nan")}, ValueError, "initial_alpha"),
        ({"mask": np.ones(3, bool)}, ValueError, "mask"),
        ({"mask": np.ones(80)}, TypeError, "mask"),
        ({"color": (1.0, 2.0)}, ValueError, "color"),
        ({"color": (-1.0, 0.0, 0.0)}, ValueError, "color"),
        ({"color": np.ones((5, 3))}, ValueError, "color"),
    ],
)
def test_bad_options_name_the_argument(kwargs, exc, text):
    v, f = meshes.icosphere(1)
    with pytest.raises(exc, match=text):
        shell = mb.BlurShell(f, **kwargs)
        shell.update(v)


def test_bad_arrays_name_the_argument():
    v, f = meshes.icosphere(1)
    with pytest.raises(ValueError, match="faces"):
        mb.BlurShell(f - 1)
    with pytest.raises(ValueError, match="faces"):
        mb.BlurShell(f, n_vertices=5)
    with pytest.raises(TypeError, match="faces"):
        mb.BlurShell(f.astype(float))
    with pytest.raises(ValueError, match="faces"):
        mb.BlurShell(np.zeros((0, 3), int))
    shell = mb.BlurShell(f)
    bad = v.copy()
    bad[3, 1] = np.nan
    with pytest.raises(ValueError, match="vertices"):
        shell.update(bad)
    with pytest.raises(ValueError, match="vertices"):
        shell.update(v[:, :2])
    with pytest.raises(TypeError, match="vertices"):
        shell.update(np.full((42, 3), "x"))
    with pytest.raises(ValueError, match="normals"):
        shell.update(v, normals=v[:5])
    with pytest.raises(ValueError, match="normals"):
        shell.update(v, normals=np.full_like(v, np.inf))
    assert shell.updates == 0
    with pytest.raises(ValueError, match="previous_vertices"):
        mb.motion_silhouette(mb.Mesh(v, f), v[:3])
    with pytest.raises(TypeError, match="mesh"):
        mb.motion_silhouette(v, v)
    with pytest.raises(ValueError, match="times"):
        mb.shell_over_shutter(f, [1.0, 0.0], np.stack([v, v]))
    with pytest.raises(ValueError, match="times"):  # the span overflows: was blamed on vertices
        mb.shell_over_shutter(f, [-1e308, 1e308], np.stack([v, v]))
    with pytest.raises(TypeError, match="times"):
        mb.shell_over_shutter(f, np.array([0.0, 1.0 + 1j]), np.stack([v, v]))
    with pytest.raises(TypeError, match="positions"):
        mb.shell_over_shutter(f, [0.0, 1.0], np.stack([v, v]) + 0j)
    with pytest.raises(TypeError, match="vertices"):
        mb.BlurShell(f).update(v + 0j)
    fed = mb.BlurShell(f)
    fed.update(v)
    with pytest.raises(ValueError, match="age"):  # was an OverflowError without the name
        fed.element(0, 10**30)
    with pytest.raises(ValueError, match="n_vertices"):
        mb.BlurShell(f, n_vertices=10**30)
    with pytest.raises(TypeError, match="initial_alpha"):
        mb.BlurShell(f, initial_alpha=True)
    with pytest.raises(ValueError, match="positions"):
        mb.shell_over_shutter(f, [0.0, 1.0], np.stack([v, v, v]))


def test_values_that_overflow_float32_name_the_argument():
    """Finite in float64 but inf in float32 (or whose float32 normals or n.d overflow): rejected
    with the argument's name instead of giving inf vertices or no silhouette."""
    v, f = meshes.icosphere(1)
    mesh = mb.Mesh(v, f)
    shell = mb.BlurShell(f)
    shell.update(v)
    for bad, name in [
        (lambda: shell.update(v + [1e39, 0, 0]), "vertices"),
        (lambda: shell.update(v * 1e20), "vertices"),  # cross products of 1e20 overflow float32
        (lambda: shell.update(v + 0.1, normals=np.full_like(v, 1e39)), "normals"),
        (lambda: shell.build(v * 1e20), "vertices"),
        (lambda: shell.build(v, normals=np.full_like(v, 1e39)), "normals"),
        (lambda: mb.motion_silhouette(mesh, v * 1e300), "previous_vertices"),
        (lambda: mb.motion_silhouette(mb.Mesh(v * 1e20, f), v), "vertices"),
        (lambda: mb.motion_silhouette(mesh, v + 0.1, normals=np.full_like(v, 1e39)), "normals"),
        (lambda: mb.motion_silhouette(mesh, v + np.nan), "previous_vertices"),
    ]:
        with pytest.raises(ValueError, match=name):
            bad()
    assert shell.updates == 1  # a rejected update changes nothing
    # Just inside the bounds everything stays finite and the silhouette is found.
    big = v * (mb.shell.MAX_COORD / 2)
    sil = mb.motion_silhouette(mb.Mesh(big, f), big - np.array([0.25, 0.13, 0.07]) * mb.shell.MAX_COORD)
    ref = mb.motion_silhouette(mb.Mesh(v, f), v - [0.5, 0.26, 0.14])
    assert len(sil.edges) > 0 and (sil.facing != 0).all() and len(sil.edges) == len(ref.edges)
    m = mb.shell_over_shutter(f, [0.0, 1.0], np.stack([big - [1e8, 3e7, 2e7], big]), subdivisions=2)
    assert len(m) > 0 and np.isfinite(m.vertices).all() and np.isfinite(m.normals).all()


def test_callers_arrays_are_never_modified():
    pos, f = arm(5)
    pos_before, f_before = pos.copy(), f.copy()
    nrm = np.ascontiguousarray(pos[0] * 2.0)
    nrm_before = nrm.copy()
    mask = np.ones(len(f), bool)
    color = np.full((len(pos[0]), 3), 0.5)
    f = np.ascontiguousarray(f, np.int64)  # the dtype the shell keeps: no copy on the way in
    times = np.linspace(0, 1, 5)
    writeable = [a.flags.writeable for a in (pos, f, nrm, mask, color, times)]
    assert all(writeable)
    ro = pos[2].copy()
    ro.flags.writeable = False
    shell = mb.BlurShell(f, subdivisions=3, mask=mask, color=color)
    for p in pos:
        shell.update(p, normals=nrm)
    shell.update(ro)
    m = shell.build(pos[-1], normals=nrm)
    m.vertices[:] = 0.0  # the result is ours to change, not a view of the input
    mb.shell_over_shutter(f, times, pos)
    mb.motion_silhouette(mb.Mesh(pos[1], f), pos[0], normals=nrm)
    np.testing.assert_array_equal(pos, pos_before)
    np.testing.assert_array_equal(f, f_before)
    np.testing.assert_array_equal(nrm, nrm_before)
    assert mask.all() and (color == 0.5).all()
    # Not even the flags: the shell keeps read-only views, never the caller's array made read-only.
    assert [a.flags.writeable for a in (pos, f, nrm, mask, color, times)] == writeable
    assert not shell.faces.flags.writeable


_THREAD_SCRIPT = textwrap.dedent(
    """
    import hashlib, numpy as np, motionblur as mb
    from motionblur import meshes
    v, f = meshes.icosphere(6)  # 81920 faces: the parallel path
    shell = mb.BlurShell(f, subdivisions=6, hysteresis=1)
    h = hashlib.sha256()
    for i in range(8):
        shell.update(v + [0.05 * i, 0.02 * np.sin(i), 0.0] + 0.03 * np.sin(v[:, :1] * 4 + i))
        m = shell.build()
        for a in (m.vertices, m.faces, m.rgba, m.normals, m.face, m.step, shell.state()["facing"]):
            h.update(np.ascontiguousarray(a).tobytes())
    print(len(m.faces), h.hexdigest())
    """
)


def test_results_do_not_depend_on_the_thread_count():
    out = []
    for n in (1, 2):
        env = dict(os.environ, RAYON_NUM_THREADS=str(n))
        r = subprocess.run([sys.executable, "-c", _THREAD_SCRIPT], env=env, capture_output=True, text=True)
        assert r.returncode == 0, r.stderr
        out.append(r.stdout.split())
    assert int(out[0][0]) > 1000
    assert out[0] == out[1]
    assert hashlib.sha256(b"").hexdigest() not in out[0]


def test_small_meshes_run_sequentially_with_the_same_results():
    """Meshes under the parallel threshold run the same chunks in order on the calling thread.
    A mesh of k identical disconnected copies of a small mesh (parallel) must give, per copy,
    exactly the small mesh's shell (sequential), with indices shifted."""
    v, f = meshes.icosphere(3)
    k = 40  # 40 * 1280 faces: parallel; one copy: sequential
    vk, fk = np.tile(v, (k, 1)), np.concatenate([f + i * len(v) for i in range(k)])
    one, many = mb.BlurShell(f, subdivisions=5, hysteresis=2), mb.BlurShell(fk, subdivisions=5, hysteresis=2)
    for i in range(7):
        d = [0.1 * i, 0.03 * np.sin(i), 0.0] + 0.05 * np.sin(4 * v[:, 2:3] + i) * [1.0, 0.0, 0.0]
        one.update(v + d)
        many.update(vk + np.tile(d, (k, 1)))
    a, b = one.build(), many.build()
    assert len(a) > 50 and len(b) == k * len(a)
    nv = len(a.vertices)
    assert np.array_equal(many.state()["facing"], np.tile(one.state()["facing"], k))
    assert np.array_equal(b.vertices, np.tile(a.vertices, (k, 1)))
    assert np.array_equal(b.rgba, np.tile(a.rgba, (k, 1)))
    assert np.array_equal(b.normals, np.tile(a.normals, (k, 1)))
    assert np.array_equal(b.step, np.tile(a.step, k))
    assert np.array_equal(b.face, np.concatenate([a.face + i * len(f) for i in range(k)]))
    assert np.array_equal(b.faces, np.concatenate([a.faces + i * nv for i in range(k)]))


# --- meshes ----------------------------------------------------------------------------------


def test_bending_arm_deforms_and_propeller_spins_rigidly():
    pos, f = meshes.bending_arm(5, angle=np.pi / 2)
    assert pos.shape[0] == 5 and pos.shape[2] == 3 and f.shape[1] == 3
    assert mb.Mesh(pos[-1], f).stats["closed"]
    root = pos[0][:, 2] < 1e-9
    np.testing.assert_allclose(pos[:, root], np.broadcast_to(pos[0][root], pos[:, root].shape))
    tip = int(np.argmin(np.linalg.norm(pos[0] - [0.0, 0.0, 2.0], axis=1)))  # the top cap's centre
    np.testing.assert_allclose(pos[-1][tip], [0.0, -1.0, 1.0], atol=1e-9)
    # Not rigid: distances between root and tip vertices change.
    d0 = np.linalg.norm(pos[0][tip] - pos[0][0])
    d1 = np.linalg.norm(pos[-1][tip] - pos[-1][0])
    assert abs(d0 - d1) > 0.1
    pp, pf = meshes.spinning_propeller(4, blades=3, turns=0.25)
    assert mb.Mesh(pp[0], pf).stats["closed"]
    d = lambda p: np.linalg.norm(p[pf[:, 0]] - p[pf[:, 1]], axis=1)  # noqa: E731
    np.testing.assert_allclose(d(pp[-1]), d(pp[0]), atol=1e-12)
    np.testing.assert_allclose(pp[-1][:, 2], pp[0][:, 2], atol=1e-12)
    ang = np.arctan2(pp[-1][:, 1], pp[-1][:, 0]) - np.arctan2(pp[0][:, 1], pp[0][:, 0])
    far = np.linalg.norm(pp[0][:, :2], axis=1) > 0.3
    np.testing.assert_allclose(np.mod(ang[far], 2 * np.pi), np.pi / 2, atol=1e-9)


def test_shell_mesh_exports():
    pos, f = arm(5)
    m = mb.shell_over_shutter(f, np.linspace(0, 1, 5), pos, subdivisions=4)
    tm = m.to_trimesh()
    assert isinstance(tm, trimesh.Trimesh)
    assert len(tm.faces) == len(m.faces) and len(tm.vertices) == len(m.vertices)
    d = m.draw(object_id=3)
    assert d.cull_back is False and d.object_id == 3
    with pytest.raises(ValueError, match="empty"):
        mb.ShellMesh.empty().draw()


def test_absurd_sizes_and_degenerate_faces():
    v, f = meshes.icosphere(1)
    with pytest.raises(
        MemoryError, match=r"n_vertices x subdivisions \+ 1: BlurShell needs 2\d\d\d\.\d\d GB"
    ):
        mb.BlurShell(f, subdivisions=255, n_vertices=400_000_000)
    # Repeated indices and zero-area faces: no panic, finite output, degenerate strips allowed.
    bad = np.concatenate([f, [[0, 0, 1], [2, 2, 2], [3, 4, 3]]])
    shell = mb.BlurShell(bad, subdivisions=4)
    for p in wobble(v, 6):
        shell.update(p)
    m = shell.build()
    assert len(m) > 0
    assert np.isfinite(m.vertices).all() and np.isfinite(m.normals).all() and np.isfinite(m.rgba).all()
    twin = TwinShell(bad, len(v), 4, 3)
    for p in wobble(v, 6):
        twin.update(p)
    np.testing.assert_array_equal(m.vertices, twin.build()["vertices"])
