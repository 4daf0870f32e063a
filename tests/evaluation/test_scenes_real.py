"""The report's real-mesh scenes: the PLY reader against files written here, the meshes read from
the wheels that ship them, and every scene's floor, light and motion."""

from __future__ import annotations

import struct
import sys

import numpy as np
import pytest

import motionblur as mb
from motionblur import MissingDependencyError
from motionblur import scenes_real as sr


def _ascii_ply(path, v, quads):
    lines = ["ply", "format ascii 1.0", f"element vertex {len(v)}", "property float x", "property float y",
             "property float z", "property uchar red", f"element face {len(quads)}",
             "property list uchar int vertex_indices", "end_header"]  # fmt: skip
    lines += [f"{x} {y} {z} 7" for x, y, z in v] + [f"{len(q)} " + " ".join(map(str, q)) for q in quads]
    path.write_text("\n".join(lines) + "\n")


def test_read_ply_reads_ascii_and_binary_and_fans_polygons(tmp_path, rng):
    v = rng.random((6, 3))
    _ascii_ply(tmp_path / "a.ply", v, [[0, 1, 2, 3], [3, 4, 5, 0]])
    va, fa = sr.read_ply(tmp_path / "a.ply")
    np.testing.assert_allclose(va, v, atol=1e-6)
    assert fa.tolist() == [[0, 1, 2], [0, 2, 3], [3, 4, 5], [3, 5, 0]]
    head = ("ply\nformat binary_big_endian 1.0\nelement vertex 6\nproperty double x\nproperty double y\n"
            "property double z\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n")  # fmt: skip
    body = (
        b"".join(struct.pack(">3d", *p) for p in v)
        + struct.pack(">B3i", 3, 0, 1, 2)
        + struct.pack(">B3i", 3, 5, 4, 3)
    )
    (tmp_path / "b.ply").write_bytes(head.encode() + body)
    vb, fb = sr.read_ply(tmp_path / "b.ply")
    np.testing.assert_array_equal(vb, v)
    assert fb.tolist() == [[0, 1, 2], [5, 4, 3]]


def test_the_real_meshes_come_from_the_wheels_normalised():
    bunny, ant = sr.real_mesh("bunny"), sr.real_mesh("ant")
    assert abs(len(bunny[1]) - sr.BUNNY_FACES) < 0.05 * sr.BUNNY_FACES  # decimated from 99,785
    assert len(ant[1]) == 912
    for name in sr.MESHES:
        v, f = sr.real_mesh(name)
        ext = v.max(0) - v.min(0)
        assert ext.max() == pytest.approx(sr.SIZE) and v[:, 1].min() == pytest.approx(0.0, abs=1e-9)
        assert f.min() >= 0 and f.max() < len(v) and not v.flags.writeable
        # outward winding: the signed volume is positive (the bunny's scan holes leave it about right)
        a, b, c = (v[f[:, i]] for i in range(3))
        assert np.einsum("ij,ij->i", a, np.cross(b, c)).sum() > 0, name


def test_every_scene_is_a_lit_mover_over_a_static_floor():
    assert len(sr.REAL_SCENES) == len(sr.MESHES) * len(sr.MOTIONS) + 1
    deforming = 0
    for name, build in sr.REAL_SCENES.items():
        sc = build(64, 48)
        mover, floor = sc.objects
        assert mover.is_moving and not floor.is_moving and name.startswith(mover.name)
        assert {mover.shading, floor.shading} == {"lambert"} and sc.lights and not sc.ambient.any()
        deforming += mover.motion.is_deforming
        start, end = mover.world_vertices(0.0), mover.world_vertices(1.0)
        assert np.abs(end - start).max() > 0.3  # a long motion
        assert start[:, 1].min() >= sr.FLOOR_Y - 1e-9  # on the floor, not in it
    assert deforming == 1
    turn = sr.REAL_SCENES["bunny_turn"]().objects[0].motion
    r0, r1 = turn.transform_at(0.0)[:3, :3], turn.transform_at(1.0)[:3, :3]
    assert np.degrees(np.arccos((np.trace(r0.T @ r1) - 1) / 2)) == pytest.approx(100.0, abs=0.01)


def test_a_scene_renders_and_a_missing_wheel_names_its_extra(monkeypatch):
    frame = mb.render(sr.REAL_SCENES["ant_translate"](48, 36), "accumulation", samples=2)
    alpha = frame.rgba[..., 3]
    assert alpha[-1].min() > 0.99 and alpha[0].max() == 0.0  # the floor below, nothing behind it above
    monkeypatch.setitem(sys.modules, "pyvista", None)
    with pytest.raises(MissingDependencyError, match=r"motionblur\[meshes\]"):
        sr._data_file("ant")
