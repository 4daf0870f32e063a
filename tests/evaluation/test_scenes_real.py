"""The report's real-mesh scenes: the mesh files shipped with the package, and every scene's
floor, light and motion."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

import motionblur as mb
from motionblur import MissingDependencyError
from motionblur import scenes_real as sr


def test_the_shipped_meshes_are_package_data_with_their_sources():
    """The decimated bunny and the ant ship with the package (read with trimesh), with a README
    that states each file's source and terms; the counts are the report's."""
    data = Path(sr.__file__).parent / "data"
    v, f = sr.shipped_mesh("bunny")
    assert (len(v), len(f)) == (2986, 5998) and abs(len(f) - sr.BUNNY_FACES) < 0.05 * sr.BUNNY_FACES
    v, f = sr.shipped_mesh("ant")
    assert (len(v), len(f)) == (486, 912) and v.dtype == np.float64 and f.dtype == np.int64
    notes = (data / "README.md").read_text()
    for words in ("Stanford 3D Scanning Repository", "bunny.ply", "ant.ply", "MIT", "pyvista"):
        assert words in notes
    with pytest.raises(ValueError, match="name"):
        sr.shipped_mesh("teapot")


def test_the_real_meshes_are_normalised():
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


def test_a_scene_renders_and_a_missing_reader_names_its_package(monkeypatch):
    frame = mb.render(sr.REAL_SCENES["ant_translate"](48, 36), "accumulation", samples=2)
    alpha = frame.rgba[..., 3]
    assert alpha[-1].min() > 0.99 and alpha[0].max() == 0.0  # the floor below, nothing behind it above
    monkeypatch.setitem(sys.modules, "trimesh", None)
    with pytest.raises(MissingDependencyError, match="trimesh"):
        sr.shipped_mesh("ant")
