"""The whole chain against real Mitsuba 3.9.1 (llvm variant when libLLVM 19 is there).

Tolerances (64x48 images, ours supersampled 4x4, Mitsuba 64+ spp with a box pixel filter):

- static scene, flat and lambert: RMSE over RGBA <= 0.008 (the edge pixels, where 16 regular
  samples and 64-256 random ones differ by up to ~0.15); on pixels away from any edge <= 0.003
  absolute (flat), <= 0.012 absolute and 0.5% median relative (lambert: the clamped cosine near
  the terminator averages differently over 16 regular and 256 random samples). The lit objects
  are smooth and convex, side by side with the light from the camera's side: Mitsuba casts
  shadows, the rasterizer does not;
- accumulation N = 256 against the K = 256 time-sampled reference on the moving cube scene:
  RMSE <= 0.006 (two Mitsuba seeds differ by ~0.002);
- accumulation error falls as N grows (4, 16, 64) on a moving lit sphere.

A diff image goes to out/test-failures/ on failure.
"""

from __future__ import annotations

import numpy as np
import pytest
from _helpers import pyrender_peer as peer
from scipy import ndimage

import motionblur as mb
from motionblur import meshes, metrics, reference
from motionblur.scene import translate

W, H = 64, 48


def _check(name: str, ok: bool, ours, ref, message: str):
    if not ok:
        path = peer.write_diff(name, ours.rgba, ref.rgba)
        pytest.fail(f"{message}; see {path}")


def _interior(frame: mb.Frame) -> np.ndarray:
    """Pixels whose 3x3 neighbourhood has one object id (no edge within a pixel)."""
    ids = frame.ids
    lo = ndimage.minimum_filter(ids, 3, mode="nearest")
    hi = ndimage.maximum_filter(ids, 3, mode="nearest")
    return lo == hi


def _static(scene: mb.Scene) -> mb.Scene:
    return scene.with_(objects=[mb.Object(o.mesh, o.color, o.shading, None, o.name) for o in scene.objects])


@pytest.mark.mitsuba
def test_variant_is_llvm_when_libllvm_is_installed():
    import os

    if os.path.exists("/usr/lib/x86_64-linux-gnu/libLLVM-19.so"):
        assert reference.mitsuba_variant() == "llvm_ad_rgb"


@pytest.mark.mitsuba
def test_static_flat_scene_matches_mitsuba():
    sc = _static(mb.SCENES["cube"](width=W, height=H))
    ref = reference.mitsuba(sc, times=1, spp=64)
    ours = mb.render(sc, "accumulation", samples=1, aa=4)
    e = metrics.rmse(ours, ref)
    inner = _interior(mb.render(sc, "accumulation", samples=1))
    diff = np.abs(ours.rgba - ref.rgba).max(axis=-1)[inner].max()
    _check("static-flat", e <= 0.008 and diff <= 0.003, ours, ref, f"RMSE {e:.4f}, interior max {diff:.4f}")


@pytest.mark.mitsuba
def test_static_lambert_scene_matches_mitsuba():
    light = mb.DirectionalLight((-0.4, -0.5, -1.0), 1.3)
    cam = mb.Camera(mb.look_at((0.3, 0.4, 4.0), (0.0, 0.0, 0.0)), 0.7, W, H, znear=0.5, zfar=30.0)
    objs = [
        mb.Object(meshes.icosphere(3, 0.7), (0.2, 0.5, 0.9), "lambert"),
        # convex, side by side: Mitsuba's shadows fall behind them, out of view
        # smooth surfaces (vertex normals mean the same on both sides)
        mb.Object(
            (meshes.icosphere(3)[0] * (0.5, 0.3, 0.4) + (1.3, 0.3, -0.4), meshes.icosphere(3)[1]),
            (0.9, 0.5, 0.2),
            "lambert",
        ),
    ]
    sc = mb.Scene(objs, cam, lights=[light])
    ref = reference.mitsuba(sc, times=1, spp=256)
    ours = mb.render(sc, "accumulation", samples=1, aa=4)
    e = metrics.rmse(ours, ref)
    inner = _interior(mb.render(sc, "accumulation", samples=1)) & (ref.rgba[..., 3] > 0.999)
    diff = np.abs(ours.rgba[..., :3] - ref.rgba[..., :3])
    rel = np.median((diff / np.maximum(ref.rgba[..., :3], 0.02)).max(axis=-1)[inner])
    assert inner.sum() > 300
    ok = e <= 0.008 and diff.max(axis=-1)[inner].max() <= 0.012 and rel <= 0.005
    _check(
        "static-lambert",
        ok,
        ours,
        ref,
        f"RMSE {e:.4f}, interior max {diff.max(axis=-1)[inner].max():.4f}, median rel {rel:.4f}",
    )


@pytest.mark.mitsuba
def test_accumulation_256_matches_the_256_time_reference():
    sc = mb.SCENES["cube"](width=W, height=H)
    ref = reference.mitsuba(sc, times=256, spp=4)
    ours = mb.render(sc, "accumulation", samples=256, aa=4)
    e = metrics.rmse(ours, ref)
    _check("accumulation-256", e <= 0.006, ours, ref, f"RMSE {e:.4f} > 0.006")
    assert abs(metrics.coverage_error(ours, ref)) < 0.01


@pytest.mark.mitsuba
def test_accumulation_error_falls_with_n():
    cam = mb.Camera(mb.look_at((0, 0, 5), (0, 0, 0)), 0.7, W, H, znear=0.5, zfar=30.0)
    obj = mb.Object(
        meshes.icosphere(3, 0.5), (0.8, 0.5, 0.2), "lambert", mb.Motion.linear((-0.8, 0, 0), (0.8, 0.3, 0))
    )
    sc = mb.Scene([obj], cam, lights=[mb.DirectionalLight((-0.3, -0.4, -1.0), 1.0)])
    ref = reference.mitsuba(sc, times=128, spp=8)
    errs = [metrics.rmse(mb.render(sc, "accumulation", samples=n, aa=4), ref) for n in (4, 16, 64)]
    assert errs[0] > 1.5 * errs[1] and errs[1] > errs[2], errs
    assert errs[2] < 0.003, errs


@pytest.mark.mitsuba
def test_reference_is_seeded_and_checks_its_arguments():
    cam = mb.Camera(mb.look_at((0, 0, 5), (0, 0, 0)), 0.7, 24, 18, znear=0.5, zfar=30.0)
    obj = mb.Object(meshes.box(), (0.5, 0.5, 0.5), motion=mb.Motion.linear((0, 0, 0), (1, 0, 0)))
    sc = mb.Scene([obj], cam)
    a = reference.mitsuba(sc, times=3, spp=2, seed=5)
    b = reference.mitsuba(sc, times=3, spp=2, seed=5)
    np.testing.assert_array_equal(a.rgba, b.rgba)
    for bad in ({"times": 0}, {"spp": 0}, {"times": 1.5}):
        with pytest.raises((ValueError, TypeError), match=next(iter(bad))):
            reference.mitsuba(sc, **bad)
    # per-vertex colours are taken now (tests/peers/test_reference_scenes.py); lens options pair up
    with pytest.raises(ValueError, match="focus_distance"):
        reference.mitsuba(sc, aperture=0.1)


@pytest.mark.pyrender
def test_pyrender_accumulation_peer_matches_ours():
    sc = mb.SCENES["cube"](width=W, height=H)
    theirs = reference.pyrender(sc, samples=16)
    ours = mb.render(sc, "accumulation", samples=16)
    # pyrender rounds to 8 bits and snaps differently on edges: compare away from them
    inner = _interior(ours)
    diff = np.abs(ours.rgba - theirs.rgba).max(axis=-1)[inner]
    assert np.median(diff) <= 1.0 / 255 and metrics.rmse(ours, theirs) < 0.02


@pytest.mark.mitsuba
def test_translated_reference_moves_the_object():
    """A far translation during the shutter: the reference is the sum of the two halves."""
    cam = mb.Camera(mb.look_at((0, 0, 5), (0, 0, 0)), 0.7, 32, 24, znear=0.5, zfar=30.0)
    obj = mb.Object(
        meshes.box((0.5, 0.5, 0.5)),
        (1.0, 1.0, 1.0),
        motion=mb.Motion(
            [0.0, 0.5, 0.51, 1.0], np.stack([translate((-1, 0, 0))] * 2 + [translate((1, 0, 0))] * 2)
        ),
    )
    sc = mb.Scene([obj], cam)
    ref = reference.mitsuba(sc, times=2, spp=16)
    left = reference.mitsuba(
        sc.with_(objects=[mb.Object(obj.mesh, obj.color, motion=mb.Motion.linear((-1, 0, 0), (-1, 0, 0)))]),
        times=1,
        spp=16,
    )
    right = reference.mitsuba(
        sc.with_(objects=[mb.Object(obj.mesh, obj.color, motion=mb.Motion.linear((1, 0, 0), (1, 0, 0)))]),
        times=1,
        spp=16,
        seed=0,
    )
    assert metrics.coverage(ref) == pytest.approx(
        0.5 * (metrics.coverage(left) + metrics.coverage(right)), rel=0.05
    )


@pytest.mark.pyrender
def test_pyrender_peer_draws_a_colour_a_vertex():
    # per-vertex colours went to pyrender's base colour as one (a TypeError); now as its vertex
    # colours, which it interpolates and rounds to 8 bits: the same frame away from the edges
    v, f = meshes.icosphere(2)
    v = np.asarray(v)
    colours = np.c_[(v + 1) / 2, np.ones(len(v))].astype(np.float32)
    motion = mb.Motion.linear(translate((-0.4, 0, 0)), translate((0.4, 0, 0)))
    cam = mb.Camera(mb.look_at((0, 0, 5), (0, 0, 0)), 0.7, W, H, znear=0.5, zfar=30.0)
    sc = mb.Scene([mb.Object(mb.Mesh(v * 0.8, f), color=colours, motion=motion)], cam)
    theirs = reference.pyrender(sc, samples=16)
    ours = mb.render(sc, "accumulation", samples=16)
    inner = _interior(ours)
    diff = np.abs(ours.rgba - theirs.rgba).max(axis=-1)[inner]
    assert np.median(diff) <= 1.0 / 255 and metrics.rmse(ours, theirs) < 0.02
    grey = reference.pyrender(mb.Scene([mb.Object(mb.Mesh(v * 0.8, f), (0.5, 0.5, 0.5), motion=motion)], cam))
    assert not np.allclose(grey.rgba, theirs.rgba, atol=0.05), "the vertex colours did not show"
