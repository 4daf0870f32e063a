"""``render(scene, "analytic")`` on every built-in scene, against accumulation's limit and Mitsuba.

Tolerances, per scene (64x48 or 80x60 pixels, 2x2 samples a pixel): the RMSE of the analytic
frame against 4096-sample accumulation stays within ``FACTOR`` times that accumulation's own
noise, measured in the test as its RMSE against 2048-sample accumulation. The analytic method's
remaining error is the chord of curved paths (``tolerance`` 0.01 px here) and the Gauss
quadrature of lambert shading that turns (the airplane), so those scenes get 3x, the rest 2x.
Against Mitsuba (K = 256 shutter times) the analytic frame is at least as close as 256-sample
accumulation (within 2% for the renderer's own sampling noise).
"""

from __future__ import annotations

import numpy as np
import pytest

import motionblur as mb
from motionblur import meshes, reference
from motionblur.scene import rotate, translate

FACTOR = {"airplane": 3.0, "spinning_propeller": 3.0, "curved": 3.0, "pan": 3.0}


def _rmse(a, b) -> float:
    return float(np.sqrt(np.mean((a.rgba - b.rgba) ** 2)))


@pytest.mark.parametrize("name", sorted(mb.SCENES))
def test_every_builtin_scene_equals_accumulations_limit(name):
    w, h = (64, 48) if name == "sphere80k" else (80, 60)
    scene = mb.SCENES[name](w, h)
    acc4 = mb.render(scene, "accumulation", samples=4096, aa=2)
    acc2 = mb.render(scene, "accumulation", samples=2048, aa=2)
    noise = _rmse(acc2, acc4)
    got = mb.render(scene, "analytic", aa=2, tolerance=0.01)
    err = _rmse(got, acc4)
    assert err <= FACTOR.get(name, 2.0) * noise, f"{name}: {err:.2e} against noise {noise:.2e}"
    # depth and ids describe the surface at the reference time, as accumulation's do
    assert (got.ids == acc4.ids).mean() > 0.97


@pytest.mark.mitsuba
@pytest.mark.parametrize("name", ["cube", "airplane", "spinning_propeller", "bending_arm"])
def test_at_least_as_close_to_mitsuba_as_256_samples(name):
    scene = mb.SCENES[name](64, 48)
    ref = reference.mitsuba(scene, times=256, spp=4)
    acc = mb.render(scene, "accumulation", samples=256, aa=2)
    got = mb.render(scene, "analytic", aa=2)
    assert _rmse(got, ref) <= 1.02 * _rmse(acc, ref), (_rmse(got, ref), _rmse(acc, ref))


def _cam(w=64, h=48):
    return mb.Camera(mb.look_at((0, 0.3, 4), (0, 0, 0)), 0.7, w, h, znear=0.5, zfar=30)


def test_zero_motion_is_the_static_render_bit_for_bit():
    v, f = meshes.torus(0.5, 0.2, 24, 12)
    place = rotate(0.6, (1, 0, 0))
    still = mb.Object((v, f), (0.3, 0.8, 0.2), "lambert", motion=mb.Motion.linear(place, place))
    fixed = mb.Object((still.world_vertices(0.0), f), (0.3, 0.8, 0.2), "lambert")
    light = [mb.DirectionalLight((0, -1, -1), 1.0)]
    for aa in (1, 2):
        a = mb.render(mb.Scene([still], _cam(), lights=light), "analytic", aa=aa)
        b = mb.render(mb.Scene([fixed], _cam(), lights=light), "accumulation", samples=1, aa=aa)
        assert np.array_equal(a.rgba, b.rgba) and np.array_equal(a.depth, b.depth)


def test_a_concave_mesh_turning_over_a_static_floor():
    # the case the motion volume gets wrong: a torus turning while it moves, over a floor
    v, f = meshes.torus(0.4, 0.15, 32, 12)
    motion = mb.Motion.linear(
        translate((-0.8, 0, 0)) @ rotate(0.2, (1, 0, 0)), translate((0.8, 0, 0)) @ rotate(1.4, (1, 0, 0))
    )
    torus = mb.Object((v, f), (0.9, 0.5, 0.2), motion=motion)
    floor = mb.Object(meshes.box((6, 0.1, 4)), (0.3, 0.3, 0.35))
    floor = mb.Object((floor.mesh.vertices + (0, -0.7, 0), floor.mesh.faces), (0.3, 0.3, 0.35))
    scene = mb.Scene([torus, floor], _cam(80, 60))
    ref = mb.render(scene, "accumulation", samples=2048, aa=2)
    acc16 = mb.render(scene, "accumulation", samples=16, aa=2)
    got = mb.render(scene, "analytic", aa=2)
    assert _rmse(got, ref) < 0.1 * _rmse(acc16, ref)
    # coverage within 0.5% of the limit (the motion volume's convex hull over-covers by 14-97%)
    assert abs(got.rgba[..., 3].sum() / ref.rgba[..., 3].sum() - 1) < 0.005


def test_custom_shutter_weights_are_integrated():
    scene = mb.SCENES["cube"](64, 48).with_(shutter=[0.0, 1.0, 3.0, 0.5])
    ref = mb.render(scene, "accumulation", samples=2048, aa=2)
    box = mb.render(scene.with_(shutter="box"), "analytic", aa=2)
    got = mb.render(scene, "analytic", aa=2)
    assert _rmse(got, ref) < 0.05 * _rmse(box, ref)


def test_transparent_and_per_vertex_coloured_objects():
    v, f = meshes.icosphere(2, 0.5)
    rgba = np.concatenate([0.5 + 0.5 * v, np.full((len(v), 1), 0.6)], axis=1)
    ball = mb.Object((v, f), rgba, motion=mb.Motion.linear(translate((-0.7, 0, 0)), translate((0.6, 0.2, 0))))
    wall = mb.Object(meshes.box((5, 4, 0.1)), (0.2, 0.2, 0.6))
    wall = mb.Object((wall.mesh.vertices + (0, 0, -1), wall.mesh.faces), (0.2, 0.2, 0.6))
    scene = mb.Scene([ball, wall], _cam())
    ref = mb.render(scene, "accumulation", samples=2048, aa=2)
    acc64 = mb.render(scene, "accumulation", samples=64, aa=2)
    got = mb.render(scene, "analytic", aa=2)
    assert _rmse(got, ref) < 0.25 * _rmse(acc64, ref)


def test_options_and_stats():
    scene = mb.SCENES["spinning_propeller"](64, 48)
    coarse = mb.render(scene, "analytic", tolerance=0.5)
    fine = mb.render(scene, "analytic", tolerance=0.02)
    assert coarse.stats["segments"] < fine.stats["segments"] <= 256
    fixed = mb.render(scene, "analytic", segments=5)
    assert fixed.stats["segments"] >= 5
    for key in ("prims", "intervals", "pieces", "splits", "ms_tiles", "ms_total"):
        assert key in fine.stats
    for bad, name in [({"aa": 3}, "aa"), ({"gauss": 0}, "gauss"), ({"tolerance": -1.0}, "tolerance"),
                      ({"segments": 0}, "segments")]:  # fmt: skip
        with pytest.raises(ValueError, match=name):
            mb.render(scene, "analytic", **bad)


@pytest.mark.parametrize("name", ["airplane", "pan", "bending_arm"])
def test_a_small_memory_budget_gives_the_same_frame(name, monkeypatch):
    # lambert shading, a static backdrop, camera motion, deformation: tiles done in halves
    # (down to single rows and samples) give the same bits as whole tiles
    scene = mb.SCENES[name](64, 48)
    whole = mb.render(scene, "analytic", aa=2, error_estimate=False)
    monkeypatch.setattr(mb.analytic, "TILE_BUDGET_BYTES", 1 << 16)
    part = mb.render(scene, "analytic", aa=2, error_estimate=False)  # the pilot's exact frame needs more
    assert whole.stats["splits"] == 0 and part.stats["splits"] > 0
    for key in ("rgba", "depth", "ids", "velocity"):
        assert np.array_equal(getattr(part, key), getattr(whole, key)), key


def _twisting_torus(shading: str) -> mb.Scene:
    v, f = meshes.torus(0.5, 0.2, 16, 8)  # 128 vertices: every vertex is a test point
    ts = np.linspace(0.0, 1.0, 3)
    frames = []
    for t in ts:
        ang = 1.2 * t * v[:, 1] / 0.2  # a twist about the vertical, growing with height
        c, s = np.cos(ang), np.sin(ang)
        frames.append(np.stack([v[:, 0] * c + v[:, 2] * s, v[:, 1], -v[:, 0] * s + v[:, 2] * c], -1))
    obj = mb.Object(
        (frames[0], f), (0.8, 0.6, 0.3), shading, motion=mb.Motion.deforming(ts, np.stack(frames))
    )
    return mb.Scene([obj], _cam(), lights=[mb.DirectionalLight((0, -1, -1), 1.0)])


def _vertex_normals(v, f):
    n = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
    out = np.zeros_like(v)
    for i in range(3):
        np.add.at(out, f[:, i], n)
    return out / np.linalg.norm(out, axis=1, keepdims=True)


def test_a_deforming_lambert_mesh_is_cut_until_its_normals_bend_linearly():
    from motionblur.methods.analytic import NORMAL_TOLERANCE, segment_times

    lit, flat = _twisting_torus("lambert"), _twisting_torus("flat")
    obj = lit.objects[0]
    times = segment_times(lit, [obj], lit.camera)
    # positions are linear between the keyframes, so only the normal rule cuts further
    assert segment_times(flat, [flat.objects[0]], flat.camera).tolist() == [0.0, 0.5, 1.0]
    assert len(times) > 3 and {0.0, 0.5, 1.0} <= set(times.tolist())
    f = np.asarray(obj.mesh.faces)
    worst = 0.0
    for a, b in zip(times[:-1], times[1:]):
        na, nb, nm = (_vertex_normals(obj.world_vertices(t), f) for t in (a, b, 0.5 * (a + b)))
        mean = (na + nb) / np.linalg.norm(na + nb, axis=1, keepdims=True)
        worst = max(worst, float(np.linalg.norm(nm - mean, axis=1).max()))
    assert worst <= NORMAL_TOLERANCE
    # and the cuts pay: the frame is closer to accumulation's limit than with the keyframes alone
    ref = mb.render(lit, "accumulation", samples=1024, aa=2)
    keyframes = mb.render(lit, "analytic", aa=2, segments=2)
    got = mb.render(lit, "analytic", aa=2)
    assert _rmse(got, ref) < 0.5 * _rmse(keyframes, ref)


def _numpy_transform(m, p):
    """The straddle's transform as numpy array steps (its former body): the oracle of its bits."""
    out = p[:, 0:1] * m[None, :, 0]
    out += p[:, 2:3] * m[None, :, 2]
    odd = p[:, 1:2] * m[None, :, 1]
    odd += p[:, 3:4] * m[None, :, 3] if p.shape[-1] == 4 else m[None, :, 3]
    out += odd
    return out


@pytest.mark.parametrize("dim", [3, 4])
def test_the_straddle_transform_has_the_numpy_steps_bits(rng, dim):
    """`_core._transform_points` (threads, the GIL released) against the numpy steps the
    straddle used before, bit for bit, on points over many magnitudes (the boundaries' bits,
    and every analytic frame of a turning object, depend on it); bad shapes name the argument."""
    from motionblur import _core
    from motionblur.methods.analytic import _transform

    m = rng.normal(size=(4, 4)) * np.array([1.0, 1e-3, 10.0, 1e2])
    p = rng.normal(size=(10_001, dim)) * 10.0 ** rng.integers(-4, 5, size=(10_001, 1))
    out = np.full((len(p), 4), np.nan)
    p_before = p.copy()
    _transform(m, p, out)
    assert np.array_equal(out.view(np.uint64), _numpy_transform(m, p).view(np.uint64))
    assert np.array_equal(p, p_before)
    with pytest.raises(ValueError, match="points"):
        _core._transform_points(m, np.zeros((5, 2)), np.zeros((5, 4)))
    with pytest.raises(ValueError, match="out"):
        _core._transform_points(m, p, np.zeros((len(p) + 1, 4)))
    with pytest.raises(ValueError, match="m"):
        _core._transform_points(np.eye(3), p, out)
