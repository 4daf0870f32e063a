"""The analytic method's work savings on dense meshes change no result: the straddled boundary
positions computed one boundary at a time are the bits of the whole-array formula, on random
rigid, deforming and camera motions; and the frame of a dense turning mesh (where the pieces of
the same layers on either side of an event behind them are integrated as one) stays within
rounding of the exact integral's distance and does not depend on the thread count."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import numpy as np
import pytest

import motionblur as mb
from motionblur import meshes
from motionblur.methods.analytic import segment_times, straddled
from motionblur.raster import Camera, look_at
from motionblur.scene import DirectionalLight, Motion, Object, Scene, rotate, translate


def _straddled_whole_array(scene, obj, times):
    """The former numpy formula: every boundary at once, einsum's order of sums."""

    def transform(m, p):
        t = [p[..., j : j + 1] * m[:, None, :, j] for j in range(4)]
        return (t[0] + t[2]) + (t[1] + t[3])

    def homogeneous(p):
        return np.concatenate([p, np.ones((*p.shape[:-1], 1))], axis=-1)

    pos = np.stack([obj.world_vertices(t) for t in times])
    if len(times) < 2:
        return pos
    mids = 0.5 * (times[1:] + times[:-1])
    vp = np.stack([scene.camera_at(t).view_projection for t in times])
    vpm = np.stack([scene.camera_at(t).view_projection for t in mids])
    clip = transform(vp, homogeneous(pos))
    mid = transform(vpm, homogeneous(np.stack([obj.world_vertices(t) for t in mids])))
    bow = mid - 0.5 * (clip[1:] + clip[:-1])
    if not np.abs(bow).max() > 1e-12 * (1.0 + np.abs(clip).max()):
        return pos
    shift = np.zeros_like(clip)
    shift[:-1] += 0.5 * bow
    shift[1:] += 0.5 * bow
    shift[1:-1] *= 0.5
    moved = transform(np.linalg.inv(vp), clip + 0.5 * shift)
    return moved[..., :3] / moved[..., 3:4]


def _random_scene(seed: int) -> Scene:
    rng = np.random.default_rng(seed)
    v, f = meshes.icosphere(2, 0.3 + 0.3 * rng.random())
    ts = np.linspace(0.0, 1.0, 2 + int(rng.integers(0, 4)))
    axis = rng.normal(size=3)
    mats = [
        translate(tuple(rng.normal(scale=0.3, size=3))) @ rotate(float(rng.normal()) * t, tuple(axis))
        for t in ts
    ]
    if seed % 3 == 2:  # deforming: vertex keyframes
        motion = Motion.deforming(
            ts, np.stack([v * (1.0 + 0.3 * t) + rng.normal(scale=0.05, size=3) for t in ts])
        )
    else:
        motion = Motion(ts, np.stack(mats))
    obj = Object((v, f), color=(0.8, 0.5, 0.3), shading="lambert", motion=motion)
    cam = Camera(look_at((0.0, 0.3, 3.0), (0.0, 0.0, 0.0)), 0.8, 96, 72)
    cam_motion = None
    if seed % 2 == 1:  # the camera pans too
        cam_motion = Motion.linear(np.eye(4), rotate(0.2 * float(rng.normal()), (0.0, 1.0, 0.0)))
    return Scene([obj], cam, camera_motion=cam_motion, lights=[DirectionalLight((-0.3, -1.0, -0.5), 1.0)])


@pytest.mark.parametrize("seed", range(6))
def test_straddled_one_boundary_at_a_time_is_the_whole_array_formula(seed):
    scene = _random_scene(seed)
    obj = scene.objects[0]
    times = segment_times(scene, [obj], scene.camera, 0.01)
    got = straddled(scene, obj, times)
    want = _straddled_whole_array(scene, obj, times)
    assert len(times) > 2 or seed % 3 == 2
    assert got.shape == want.shape
    np.testing.assert_array_equal(got, want)
    np.testing.assert_array_equal(np.signbit(got), np.signbit(want))


def _dense_turning(width: int = 80, height: int = 60) -> Scene:
    """An icosphere of 20k faces turning while it moves over a floor, with a second sphere
    passing behind it: layers hidden behind the front one end and cross there."""
    v, f = meshes.icosphere(5, 0.5)
    ts = np.linspace(0.0, 1.0, 3)
    turn = Motion(
        ts, np.stack([translate((-0.4 + 0.8 * t, 0.0, 0.0)) @ rotate(1.2 * t, (0, 1, 0)) for t in ts])
    )
    back = Motion.linear(translate((0.6, 0.1, -1.0)), translate((-0.6, 0.1, -1.0)))
    floor_v, floor_f = meshes.box((6.0, 0.1, 6.0))
    objs = [
        Object((v, f), color=(0.8, 0.5, 0.3), shading="lambert", motion=turn),
        Object((v * 0.8, f), color=(0.2, 0.5, 0.9), shading="lambert", motion=back),
        Object((floor_v + (0.0, -0.6, 0.0), floor_f), color=(0.3, 0.3, 0.3), shading="lambert"),
    ]
    cam = Camera(look_at((0.0, 0.4, 3.0), (0.0, 0.0, 0.0)), 0.8, width, height)
    return Scene(objs, cam, lights=[DirectionalLight((-0.3, -1.0, -0.5), 1.0)], ambient=0.1)


def test_a_dense_turning_mesh_is_near_the_limit_of_accumulation():
    scene = _dense_turning()
    got = mb.render(scene, "analytic", error_estimate=False)
    ref = mb.render(scene, "accumulation", samples=16384, error_estimate=False)
    acc = mb.render(scene, "accumulation", samples=4096, error_estimate=False)
    err = float(np.sqrt(np.mean((got.rgba - ref.rgba) ** 2)))
    noise = float(np.sqrt(np.mean((acc.rgba - ref.rgba) ** 2)))
    # the factor of the turning built-in scenes (test_analytic_method.py): the chord of the
    # curved paths (tolerance 0.01 px) remains
    assert err <= 3.0 * noise, f"analytic {err:.2e} against accumulation-4096's {noise:.2e}"
    # hidden layers cut the sweep; shaded pieces stay below one per span found
    assert got.stats["pieces"] < got.stats["spans"]


_CHILD = """
import hashlib, sys
sys.path.insert(0, sys.argv[1])
import motionblur as mb
import test_analytic_scale as t
f = mb.render(t._dense_turning(), "analytic", error_estimate=False)
print(hashlib.sha256(f.rgba.tobytes() + f.depth.tobytes() + f.ids.tobytes()).hexdigest())
"""


def test_a_dense_turning_frame_does_not_depend_on_the_thread_count():
    here = os.path.dirname(__file__)
    digests = []
    for threads in ("1", "2"):
        env = {**os.environ, "MOTIONBLUR_NUM_THREADS": threads}
        out = subprocess.run(
            [sys.executable, "-c", _CHILD, here], env=env, capture_output=True, text=True, check=True
        )
        digests.append(out.stdout.strip().splitlines()[-1])
    assert digests[0] == digests[1]


def _strip_scene(seed: int) -> Scene:
    """A random sphere of 1,280 faces turning (or deforming) over a panning camera's view, with
    a translucent second one crossing it: many prims over a few segments."""
    rng = np.random.default_rng(100 + seed)
    v, f = meshes.icosphere(3, 0.4 + 0.2 * rng.random())
    ts = np.linspace(0.0, 1.0, 3 + int(rng.integers(0, 3)))
    axis = tuple(rng.normal(size=3))
    start = rng.normal(scale=0.3, size=3)
    mats = [translate(tuple(start + t * rng.normal(scale=0.4, size=3))) @ rotate(1.5 * t, axis) for t in ts]
    objs = [
        Object((v, f), color=(0.8, 0.5, 0.3), shading="lambert", motion=Motion(ts, np.stack(mats))),
        Object(
            (v * 0.7, f),
            color=(0.2, 0.5, 0.9, 0.6),
            shading="flat",
            motion=Motion.linear(translate((0.7, 0.1, -0.5)), translate((-0.7, -0.1, -0.3))),
        ),
    ]
    cam = Camera(look_at((0.0, 0.3, 3.0), (0.0, 0.0, 0.0)), 0.8, 128, 96)
    cam_motion = Motion.linear(np.eye(4), rotate(0.1 * float(rng.normal()), (0.0, 1.0, 0.0)))
    return Scene(objs, cam, camera_motion=cam_motion, lights=[DirectionalLight((-0.3, -1.0, -0.5), 1.0)])


def _planes(f) -> list[np.ndarray]:
    return [f.rgba, f.depth, f.ids, f.velocity]


@pytest.mark.parametrize("seed", range(4))
def test_a_frame_set_up_strip_by_strip_is_the_bits_of_the_whole_frame(seed, monkeypatch):
    scene = _strip_scene(seed)
    whole = mb.render(scene, "analytic", aa=2, error_estimate=False)
    assert whole.stats["strips"] == 1
    # a small budget: the frame's prims pass twice it, so it is done strip by strip
    monkeypatch.setattr(mb.analytic, "TILE_BUDGET_BYTES", 256 << 10)
    strips = mb.render(scene, "analytic", aa=2, error_estimate=False)
    assert strips.stats["strips"] > 2
    for k in ("prims", "bin_entries", "spans", "pieces"):
        assert strips.stats[k] == whole.stats[k], k
    for a, b in zip(_planes(strips), _planes(whole), strict=True):
        np.testing.assert_array_equal(a, b)
        np.testing.assert_array_equal(np.signbit(a), np.signbit(b))


_MEMORY_CHILD = """
import json, sys
sys.path.insert(0, sys.argv[1])
import motionblur as mb
import test_analytic_scale as t
def hwm():
    for line in open("/proc/self/status"):
        if line.startswith("VmHWM:"):
            return int(line.split()[1]) * 1024
w, h = int(sys.argv[2]), int(sys.argv[3])
scene = t._dense_turning(w, h)
before = hwm()
f = mb.render(scene, "analytic", error_estimate=False)
print(json.dumps({"before": before, "peak": hwm(), "segments": f.stats["segments"],
                  "prims": f.stats["prims"], "strips": f.stats["strips"]}))
"""


def test_the_peak_memory_of_a_dense_turning_frame_is_bounded_by_its_pixels_and_budget():
    """In a fresh process: the peak while rendering grows by no more than the frame's own
    arrays (outputs and the per-sample backdrop), the boundary positions and normals, and the
    budgets (the strip's prims, two threads' tile buffers) with 96 MiB to spare, not with the
    prims of the whole frame (set up at once they would be ~2.4M x 124 bytes here)."""
    w, h = 320, 240
    out = subprocess.run(
        [sys.executable, "-c", _MEMORY_CHILD, os.path.dirname(__file__), str(w), str(h)],
        capture_output=True, text=True, check=True,
    ).stdout  # fmt: skip
    r = json.loads(out.strip().splitlines()[-1])
    assert r["strips"] > 1
    budget = mb.analytic.TILE_BUDGET_BYTES
    vertices = 2 * len(meshes.icosphere(5, 0.5)[0])  # the two moving spheres
    boundaries = r["segments"] + 1
    # positions f64 and normals f32 per boundary and vertex, twice (the Python side builds them)
    inputs = 2 * boundaries * vertices * 3 * (8 + 4)
    pixels = w * h * (16 + 4 + 4 + 8 + 24)  # outputs and the per-sample backdrop
    bound = inputs + pixels + 2 * budget + 2 * 2 * budget + (96 << 20)
    grown = r["peak"] - r["before"]
    assert grown < bound, f"peak grew {grown >> 20} MiB, bound {bound >> 20} MiB ({r})"


_KERNEL_MEMORY_CHILD = """
import json, sys
import numpy as np
import motionblur as mb
from motionblur import meshes
from motionblur.analytic import MovingDraw, rasterize_motion
from motionblur.raster import Camera, look_at
from motionblur.scene import rotate, translate
def status(key):
    for line in open("/proc/self/status"):
        if line.startswith(key):
            return int(line.split()[1]) * 1024
k, w, h, budget = (int(a) for a in sys.argv[1:5])
mb.analytic.TILE_BUDGET_BYTES = budget
v, f = meshes.icosphere(5, 0.5)
times = np.linspace(0.0, 1.0, k + 1)
hom = np.concatenate([v, np.ones((len(v), 1))], axis=1)
turn = [translate((-0.4 + 0.8 * t, 0.0, 0.0)) @ rotate(1.2 * t, (0, 1, 0)) for t in times]
draw = MovingDraw(np.stack([(hom @ m.T)[:, :3] for m in turn]), f, (0.8, 0.5, 0.3))
cam = Camera(look_at((0.0, 0.0, 1.0), (0.0, 0.0, 0.0)), 0.8, w, h)
with open("/proc/self/clear_refs", "w") as fh:
    fh.write("5")  # VmHWM from here on
before = status("VmRSS:")
fr = rasterize_motion(cam, [draw], times)
print(json.dumps({"grown": status("VmHWM:") - before, "strips": fr.stats["strips"],
                  "faces": len(f), "vertices": len(v)}))
"""


def test_the_kernel_holds_no_clip_position_of_every_vertex_and_boundary_when_done_strip_by_strip():
    """A sphere of 10k vertices turning over 256 segments, seen close up, with a 4 MiB tile
    budget: done strip by strip, the kernel's peak grows by its frame, the plan (4 then 2 bytes
    per face and segment), a strip's prims (twice the budget, or one row of tiles), the two
    threads' tile buffers (twice the budget each) and 16 MiB to spare (allocator, tables of the
    strip's clip positions), not by every vertex's clip position at every boundary (32 bytes
    each, 84 MB here) nor 12 bytes of plan per face and segment (which took 174 MiB in all).
    Linux only, like the memory test above: it reads /proc/self/status, and fails elsewhere."""
    k, w, h, budget = 256, 320, 240, 4 << 20
    out = subprocess.run(
        [sys.executable, "-c", _KERNEL_MEMORY_CHILD, str(k), str(w), str(h), str(budget)],
        env={**os.environ, "MOTIONBLUR_NUM_THREADS": "2"}, capture_output=True, text=True, check=True,
    ).stdout  # fmt: skip
    r = json.loads(out.strip().splitlines()[-1])
    assert r["strips"] > 1
    frame = w * h * (16 + 4 + 4 + 8)
    plan = 6 * r["faces"] * k
    bound = frame + plan + 2 * 2 * budget + 2 * 2 * budget + (16 << 20)
    every_clip = 32 * (k + 1) * r["vertices"]
    assert every_clip > bound // 2
    assert r["grown"] < bound, f"the kernel grew {r['grown'] >> 20} MiB, bound {bound >> 20} MiB ({r})"
