"""Accumulation benchmark: a frame's N samples drawn and summed by the core in one call, against
the rasterizer calls it is made of, measured in the same run.

Built-in scenes at 320x240, aa 1, N = 64 stratified samples, the static layer kept across
frames (as in a real-time loop). Per scene, best of R rounds after a warm-up, each round timing
the three once in turn:

- ``raster 1``: the one rasterizer call of a one-sample frame: the moving objects at t = 0.5
  through the projection of their pixel rectangle (``_core._Painter.layer``, what
  ``render(scene, "accumulation", samples=1)`` rasterizes); for the camera pan, one whole frame
  of every object (timed as 8 calls in a row, divided by 8).
- ``per sample``: the 64 samples of a 64-sample frame drawn one call at a time from Python, each
  followed by the accumulation kernel (``_core._accumulate``): the per-sample structure, 2N calls
  into the core.
- ``one call``: ``render(scene, "accumulation", samples=64)``, the whole frame in one call.

Ratios: ``one call / (64 x raster 1)`` (the target on ``cube``: at most 1.2) and
``one call / per sample``, of wall-clock time and of process CPU time. Usage: python benches/bench_accumulation.py [--quick]; writes
out/bench/accumulation.md.
"""

from __future__ import annotations

import os
import platform
import sys
import time
from pathlib import Path

import numpy as np

import motionblur as mb
from motionblur import _core
from motionblur.methods._layers import window_projection
from motionblur.methods._painter import Painter, box_corners
from motionblur.methods.accumulation import sample_times

N = 64


def best_ms(fns, repeat: int) -> tuple[list[float], list[float]]:
    """Best-of-``repeat`` wall-clock and process CPU milliseconds (every thread of this process:
    what the work costs, whatever else the machine runs) of each of ``fns``, timed in
    interleaved rounds (one call of each per round, after a warm-up) so that a change of the
    machine's load over the run touches all of them alike."""
    for fn in fns:
        fn()  # warm-up (allocation, the static layer cached)
    wall = [float("inf")] * len(fns)
    cpu = [float("inf")] * len(fns)
    for _ in range(repeat):
        for i, fn in enumerate(fns):
            t0, c0 = time.perf_counter(), time.process_time()
            fn()
            wall[i] = min(wall[i], time.perf_counter() - t0)
            cpu[i] = min(cpu[i], time.process_time() - c0)
    return [b * 1e3 for b in wall], [b * 1e3 for b in cpu]


def rect(cam: mb.Camera, objects, t: float):
    """The pixel rectangle of the moving ``objects`` at ``t`` (as the core bounds them)."""
    pts = []
    for o in objects:
        if o.motion.is_deforming:
            pts.append(o.world_vertices(t))
        else:
            m = o.transform_at(t)
            pts.append(box_corners(o.mesh) @ m[:3, :3].T + m[:3, 3])
    pts = np.concatenate(pts)
    xy, depth = cam.project(pts)
    if (depth <= 1e-9).any():
        return 0, 0, cam.width, cam.height
    x, y = xy[:, 0], xy[:, 1]
    x0, y0 = max(0, int(np.floor(x.min())) - 1), max(0, int(np.floor(y.min())) - 1)
    x1, y1 = min(cam.width, int(np.ceil(x.max())) + 1), min(cam.height, int(np.ceil(y.max())) + 1)
    return None if x0 >= x1 or y0 >= y1 else (x0, y0, x1, y1)


def jobs(scene: mb.Scene):
    """(painter, [(t, weight, view, projection, width, height)] of the 64 samples, the sample at
    t = 0.5 the same way)."""
    cam = scene.camera
    times, weights = sample_times(scene, N)
    c = np.ascontiguousarray
    if scene.camera_moves:
        painter = Painter(scene, list(enumerate(scene.objects)))

        def job(t, w):
            return t, w, c(scene.camera_at(t).view), c(cam.projection), cam.width, cam.height

    else:
        moving = [(k, o) for k, o in enumerate(scene.objects) if o.is_moving]
        painter = Painter(scene, moving, eye=cam.pose[:3, 3])

        def job(t, w):
            r = rect(cam, [o for _, o in moving], t)
            proj = c(window_projection(cam.projection, cam.width, cam.height, r))
            return t, w, c(cam.view), proj, r[2] - r[0], r[3] - r[1]

    return painter, [job(t, w) for t, w in zip(times, weights)], job(0.5, 1.0)


def measure(name: str, repeat: int) -> tuple:
    scene = mb.SCENES[name](320, 240)
    painter, samples, one = jobs(scene)

    def per_sample():
        acc = {}
        for t, w, view, proj, width, height in samples:
            rgba, depth, _ids = painter.core.layer(t, view, proj, width, height)
            a = acc.setdefault((width, height), np.zeros((height, width, 4), np.float32))
            _core._accumulate(a, rgba, depth, None, float(w))

    def raster1():
        for _ in range(8):  # a few calls, so that one timing is not a single short call
            painter.core.layer(one[0], *one[2:])

    def one_call():
        mb.render(scene, "accumulation", samples=N)

    (r8, loop, call), (cpu_r8, cpu_loop, cpu_call) = best_ms([raster1, per_sample, one_call], repeat)
    return name, r8 / 8, loop, call, cpu_call / (64 * cpu_r8 / 8), cpu_call / cpu_loop


def main() -> None:
    quick = "--quick" in sys.argv
    repeat = 5 if quick else 15
    cpu = next(
        (
            ln.split(":", 1)[1].strip()
            for ln in Path("/proc/cpuinfo").read_text().splitlines()
            if "model name" in ln
        ),
        platform.processor() or platform.machine(),
    )
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    header = (
        f"machine: {cpu}, {os.cpu_count()} cores, load average {load:.1f} at the start, "
        f"python {platform.python_version()}, numpy {np.__version__}"
    )
    print(header)
    rows = []
    scenes = ("cube", "curved") if quick else ("cube", "airplane", "curved", "sphere80k", "pan")
    for name in scenes:
        r = measure(name, 3 if name == "sphere80k" else repeat)
        rows.append(r)
        _, raster1, loop, call, cpu64, cpu_loop = r
        print(
            f"{name:<10} raster 1 {raster1:7.3f} ms  64 x raster 1 {64 * raster1:8.2f} ms  "
            f"per sample {loop:8.2f} ms  one call {call:8.2f} ms  "
            f"one call / (64 x raster 1) {call / (64 * raster1):5.2f}  one call / per sample {call / loop:5.2f}  "
            f"(CPU time: {cpu64:5.2f}, {cpu_loop:5.2f})"
        )
    lines = [
        "# Accumulation benchmark",
        "",
        header + ".",
        f"320x240, aa 1, {N} stratified samples, static layer cached, best of 3-15 interleaved rounds after a warm-up, "
        "all columns measured in the same run (`python benches/bench_accumulation.py`, run by `make bench`). "
        "raster 1: the one rasterizer call of a one-sample frame (moving objects at t = 0.5 in their "
        "rectangle; the whole frame for the camera pan); per sample: the 64 samples drawn one call at a "
        "time from Python with the accumulation kernel after each; one call: "
        "`render(scene, 'accumulation', samples=64)`. The CPU columns are the same two ratios of "
        "process CPU time (all threads), which another program's load on the machine changes less.",
        "",
        "| scene | raster 1 ms | 64 x raster 1 ms | per sample ms | one call ms | one call / (64 x raster 1) "
        "| one call / per sample | CPU: one call / (64 x raster 1) | CPU: one call / per sample |",
        "|---|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    lines += [
        f"| {n} | {r1:.3f} | {64 * r1:.2f} | {lp:.2f} | {c:.2f} | {c / (64 * r1):.2f} | {c / lp:.2f} "
        f"| {c64:.2f} | {cl:.2f} |"
        for n, r1, lp, c, c64, cl in rows
    ]
    out = Path("out/bench")
    out.mkdir(parents=True, exist_ok=True)
    (out / "accumulation.md").write_text("\n".join(lines) + "\n")
    print(f"wrote {out / 'accumulation.md'}")


if __name__ == "__main__":
    main()
