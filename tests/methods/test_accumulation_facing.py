"""Accumulation's per-frame constants: the Rust facing-face selection (``_core._facing_faces``)
keeps exactly the faces of the numpy expression it replaced, every face that faces the eye at
some shutter time, and all faces of a rotating object; bad input raises; the per-mesh cache is
not used on arrays a caller unlocked and edited in place."""

from __future__ import annotations

import numpy as np
import pytest
from _helpers.threads import digests, ticks_during

import motionblur as mb
from motionblur import _core, meshes
from motionblur.methods._painter import facing_faces
from motionblur.scene import rotate, translate


def numpy_facing(obj: mb.Object, faces: np.ndarray, eye: np.ndarray) -> np.ndarray:
    """The selection as it was written in numpy before the Rust kernel (the twin)."""
    keys = obj.motion.transforms
    lin = keys[0, :3, :3]
    scale = np.cbrt(np.linalg.det(lin))
    rot = lin / scale
    v = obj.mesh.vertices
    a = v[faces[:, 0]]
    n = np.cross(v[faces[:, 1]] - a, v[faces[:, 2]] - a)
    nlen = np.linalg.norm(n, axis=1)
    keep = np.zeros(len(faces), dtype=bool)
    for key in keys:
        e = rot.T @ (eye - key[:3, 3]) / scale
        d = e - a
        keep |= np.einsum("ij,ij->i", n, d) > -1e-9 * nlen * np.linalg.norm(d, axis=1)
    return faces[keep]


def random_case(rng, nv=300, nf=700):
    """A random triangle soup and a random rigid translation (same rotation and scale at 1-4
    keyframes), plus an eye."""
    v = rng.normal(size=(nv, 3))
    f = rng.integers(0, nv, size=(nf, 3))
    k = int(rng.integers(1, 5))
    times = np.sort(rng.choice(np.linspace(0.0, 1.0, 11), size=k, replace=False))
    base = rotate(rng.uniform(0, 6.3), rng.normal(size=3)) @ np.diag([*([rng.uniform(0.5, 2.0)] * 3), 1.0])
    keys = np.stack([translate(rng.normal(size=3) * 2.0) @ base for _ in range(k)])
    obj = mb.Object((v, f), motion=mb.Motion(times, keys))
    eye = rng.normal(size=3) * 4.0
    return obj, obj.mesh.faces, eye


@pytest.mark.parametrize("seed", range(6))
def test_kept_faces_equal_the_numpy_selection_and_hold_every_facing_face(seed):
    rng = np.random.default_rng(seed)
    obj, f, eye = random_case(rng)
    kept = facing_faces(obj, f, eye)
    want = numpy_facing(obj, f, eye)
    assert kept.dtype == np.int64 and kept.flags.c_contiguous
    np.testing.assert_array_equal(kept, want)  # the same faces in the same order, bit for bit
    # every face facing the eye (clearly, not edge-on) at one of many shutter times is kept
    kept_rows = {tuple(r) for r in kept}
    for t in np.linspace(0.0, 1.0, 41):
        w = obj.world_vertices(t)
        a = w[f[:, 0]]
        n = np.cross(w[f[:, 1]] - a, w[f[:, 2]] - a)
        d = eye - a
        facing = np.einsum("ij,ij->i", n, d) > 1e-7 * np.linalg.norm(n, axis=1) * np.linalg.norm(d, axis=1)
        assert {tuple(r) for r in f[facing]} <= kept_rows, t


def test_a_closed_mesh_loses_its_back_and_a_rotating_one_keeps_everything():
    v, f = meshes.icosphere(3, 0.5)
    eye = np.array([0.0, 0.3, 5.0])
    moving = mb.Object((v, f), motion=mb.Motion.linear(translate((-1, 0, 0)), translate((1, 0, 0))))
    kept = facing_faces(moving, moving.mesh.faces, eye)
    assert len(f) * 0.4 < len(kept) < len(f) * 0.7
    np.testing.assert_array_equal(kept, numpy_facing(moving, moving.mesh.faces, eye))
    spinning = mb.Object((v, f), motion=mb.Motion.linear(np.eye(4), rotate(0.3, (0, 1, 0))))
    assert facing_faces(spinning, spinning.mesh.faces, eye) is spinning.mesh.faces
    # seen from inside, every face of the sphere turns away: none is kept
    inside = mb.Object((v, f), motion=mb.Motion.linear(translate((0, 0, 4.9)), translate((0.01, 0, 4.9))))
    assert facing_faces(inside, inside.mesh.faces, eye).shape == (0, 3)
    # a quad facing the eye keeps both faces: the caller's array comes back
    quad = mb.Object(
        (np.array([[0.0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]), np.array([[0, 1, 2], [0, 2, 3]])),
        motion=mb.Motion.linear(translate((-1, 0, 0)), translate((1, 0, 0))),
    )
    assert facing_faces(quad, quad.mesh.faces, eye) is quad.mesh.faces


def test_the_kernel_checks_its_input_and_leaves_it_unchanged():
    v, f = meshes.icosphere(1, 0.5)
    f = np.ascontiguousarray(f, dtype=np.int64)
    v = np.ascontiguousarray(v, dtype=np.float64)
    eyes = np.array([[0.0, 0.0, 3.0]])
    v0, f0, e0 = v.copy(), f.copy(), eyes.copy()
    _core._facing_faces(v, f, eyes)
    assert (v == v0).all() and (f == f0).all() and (eyes == e0).all()
    bad_f = f.copy()
    bad_f[3, 1] = len(v)
    cases = [
        ((v, bad_f, eyes), "faces"),
        ((v, -f - 1, eyes), "faces"),
        ((v, f, np.array([[np.nan, 0.0, 0.0]])), "eyes"),
        ((v, f, np.zeros((0, 3))), "eyes"),
        ((np.where(np.arange(len(v))[:, None] == 2, np.inf, v), f, eyes), "vertices"),
        ((v[:, :2].copy(), f, eyes), "vertices"),
        ((v, f[:, :2].copy(), eyes), "faces"),
        ((np.asfortranarray(v), f, eyes), "vertices"),
    ]
    for args, name in cases:
        with pytest.raises(ValueError, match=name):
            _core._facing_faces(*args)
    with pytest.raises(TypeError):
        _core._facing_faces(v.astype(np.float32), f, eyes)


_DIGEST = """
import hashlib, numpy as np
from motionblur import _core, meshes
v, f = meshes.icosphere(5, 1.0)
eyes = np.array([[0.3, 0.2, 2.5], [0.9, -0.4, 2.0]])
print(hashlib.sha256(_core._facing_faces(np.ascontiguousarray(v, dtype=np.float64),
      np.ascontiguousarray(f, dtype=np.int64), eyes).tobytes()).hexdigest())
"""


def test_thread_count_independent_and_gil_released():
    d = digests(_DIGEST, threads=(1, 2))
    assert d[0] == d[1]
    v, f = meshes.icosphere(6, 1.0)
    v = np.ascontiguousarray(v, dtype=np.float64)
    f = np.ascontiguousarray(f, dtype=np.int64)
    eyes = np.array([[0.3, 0.2, 2.5], [0.9, -0.4, 2.0]])
    assert ticks_during(lambda: [_core._facing_faces(v, f, eyes) for _ in range(20)]) > 0


def test_unlocked_and_edited_mesh_is_not_served_from_the_cache():
    v, f = meshes.icosphere(2, 0.3)
    cam = mb.Camera(mb.look_at((0.0, 0.0, 4.0), (0.0, 0.0, 0.0)), 0.7, 96, 72)
    motion = mb.Motion.linear(translate((-0.8, 0, 0)), translate((0.4, 0, 0)))
    obj = mb.Object((v, f), color=(0.9, 0.4, 0.2), motion=motion)
    backdrop = mb.Object(meshes.box((6.0, 4.0, 0.1)), color=(0.2, 0.3, 0.3))
    sc = mb.Scene([obj, backdrop], cam)
    mb.render(sc, "accumulation", samples=4)  # the cache now holds the mesh's constants
    verts = obj.mesh.vertices
    verts.flags.writeable = True
    verts *= 2.5  # a bigger sphere: its sample windows must grow
    edited = mb.render(sc, "accumulation", samples=4).rgba
    fresh_obj = mb.Object((verts.copy(), f), color=(0.9, 0.4, 0.2), motion=motion)
    fresh = mb.render(mb.Scene([fresh_obj, backdrop], cam), "accumulation", samples=4).rgba
    np.testing.assert_array_equal(edited, fresh)


def test_the_per_mesh_cache_lets_meshes_go():
    import gc

    cam = mb.Camera(mb.look_at((0.0, 0.0, 4.0), (0.0, 0.0, 0.0)), 0.7, 48, 36)
    renderer = mb.Renderer()
    before = len(renderer.mesh_constants)
    for k in range(5):
        v, f = meshes.icosphere(1, 0.3 + 0.1 * k)
        obj = mb.Object(
            (v, f),
            shading="lambert",
            motion=mb.Motion.linear(translate((-0.5, 0, 0)), translate((0.5, 0, 0))),
        )
        renderer.render(
            mb.Scene([obj], cam, lights=[mb.DirectionalLight((0, 0, -1))]), "accumulation", samples=2
        )
        assert len(renderer.mesh_constants) == before + 1  # this mesh's entry, the previous one's gone
        del obj
        gc.collect()
    assert len(renderer.mesh_constants) == before
