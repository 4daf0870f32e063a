"""Array layouts: Fortran-ordered, strided and read-only inputs give the same results as C-ordered ones.

rust-numpy's ``as_slice`` accepts Fortran-contiguous arrays and returns their memory in column
order; a binding that trusted it would scramble (N,3) rows without an error. Every public entry
point is fed the same data in three layouts and must answer identically.
"""

from __future__ import annotations

import numpy as np
import pytest

import motionblur as mb
from motionblur import image, meshes


def layouts(a: np.ndarray):
    """The same values as C order, Fortran order, a strided view and a read-only copy."""
    a = np.ascontiguousarray(a)
    fortran = np.asfortranarray(a)
    wide = np.zeros(a.shape[:-1] + (a.shape[-1] * 2,), dtype=a.dtype)
    wide[..., ::2] = a
    strided = wide[..., ::2]
    ro = a.copy()
    ro.setflags(write=False)
    for name, arr in (("fortran", fortran), ("strided", strided), ("readonly", ro)):
        assert np.array_equal(arr, a)
        yield name, arr


@pytest.fixture(scope="module")
def sphere():
    v, f = meshes.icosphere(2)
    rng = np.random.default_rng(3)
    return v * (1 + 0.05 * rng.standard_normal((len(v), 1))), f


def test_mesh_and_contours(sphere):
    v, f = sphere
    m = np.array([0.4, 0.2, -0.3])
    want = mb.contour_edges(mb.Mesh(v, f), m)
    vol = mb.motion_volume(mb.Mesh(v, f), m, segments=2)
    for name, vv in layouts(v):
        for fname, ff in layouts(f):
            mesh = mb.Mesh(vv, ff)
            assert np.array_equal(mesh.vertices, v), (name, fname)
            assert np.array_equal(mesh.faces, f), (name, fname)
            assert np.array_equal(mb.contour_edges(mesh, m), want), (name, fname)
    got = mb.motion_volume(mb.Mesh(np.asfortranarray(v), np.asfortranarray(f)), m, segments=2)
    assert np.array_equal(got.faces, vol.faces) and np.allclose(got.vertices, vol.vertices)


def test_rasterize(sphere, rng):
    v, f = sphere
    cam = mb.Camera(mb.look_at((0, 0, 4), (0, 0, 0)), 0.8, 48, 40)
    rgba = rng.uniform(0.2, 1.0, (len(v), 4)).astype(np.float32)
    rgba[:, 3] = 1
    want = mb.rasterize(cam, mb.Draw(v, f, rgba, previous_vertices=v - 0.1))
    for name, vv in layouts(v):
        got = mb.rasterize(
            cam, mb.Draw(vv, np.asfortranarray(f), np.asfortranarray(rgba), previous_vertices=vv - 0.1)
        )
        assert np.array_equal(got.rgba, want.rgba), name
        assert np.array_equal(got.velocity, want.velocity), name


def test_image_kernels():
    rng = np.random.default_rng(1)
    rgba = rng.uniform(0, 1, (24, 32, 4)).astype(np.float32)
    rgba[..., :3] *= rgba[..., 3:]
    depth = rng.uniform(1, 5, (24, 32)).astype(np.float32)
    want_blur = image.opaque_motion_blur(rgba, (1.0, 0.5), 7)
    want_glow = image.glow(rgba[..., 3], (0.0, 1.0), 5)
    want_dof = image.depth_of_field(rgba, depth, 2.0, 0.05, 2.0, 0.8)
    for name, arr in layouts(rgba):
        assert np.array_equal(image.opaque_motion_blur(arr, (1.0, 0.5), 7), want_blur), name
    for name, arr in layouts(rgba[..., 3]):
        assert np.array_equal(image.glow(arr, (0.0, 1.0), 5), want_glow), name
    for name, arr in layouts(depth):
        assert np.array_equal(image.depth_of_field(rgba, arr, 2.0, 0.05, 2.0, 0.8), want_dof), name


def test_blur_shell(sphere):
    v, f = sphere
    v1 = v + (0.05, 0.0, 0.0)

    def run(ff, a, b):
        shell = mb.BlurShell(ff, subdivisions=4)
        shell.update(a)
        shell.update(b)
        return shell.build()

    want = run(f, v, v1)
    for name, ff in layouts(f):
        got = run(ff, np.asfortranarray(v), np.asfortranarray(v1))
        assert np.array_equal(got.faces, want.faces), name
        assert np.array_equal(got.vertices, want.vertices), name
        assert np.array_equal(got.rgba, want.rgba), name
