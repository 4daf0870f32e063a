"""Contour tables driving the motion volume (Wloka and Zeleznik, section 4.4): frame time and error.

Every built-in scene that the motion volume renders (rigid motion), and a 328k-face sphere
(icosphere, 7 subdivisions, 327,680 faces) crossing a still camera, at 320x240, box filter, 2
segments: ``render(scene, "motion_volume")`` without a table and with ``contour_table=K`` (a
ContourTable of K stochastic directions per moving mesh, built before timing and kept, as in a
real-time loop), timed in interleaved rounds (one frame of each per round, best of R after a
warm-up; wall clock and the process's CPU time), with the volume build alone timed the same
way. The error is each frame's RMSE against a 256-sample accumulation of the same scene, and
the largest angle between an object's motion and the stored direction it swept (the frame's
``stats["contour_error"]``). Usage: python benches/bench_contour_table.py [--quick]; writes
out/bench/contour_table.md.
"""

from __future__ import annotations

import os
import platform
import sys
import time
from pathlib import Path

import numpy as np

import motionblur as mb
from motionblur.methods.motion_volume import apparent_motion
from motionblur.scene import translate


def best_ms(fns, repeat: int) -> tuple[list[float], list[float]]:
    """Best-of-``repeat`` wall-clock and process CPU milliseconds of each of ``fns``, timed in
    interleaved rounds after a warm-up."""
    for fn in fns:
        fn()
    wall = [float("inf")] * len(fns)
    cpu = [float("inf")] * len(fns)
    for _ in range(repeat):
        for i, fn in enumerate(fns):
            t0, c0 = time.perf_counter(), time.process_time()
            fn()
            wall[i] = min(wall[i], time.perf_counter() - t0)
            cpu[i] = min(cpu[i], time.process_time() - c0)
    return [b * 1e3 for b in wall], [b * 1e3 for b in cpu]


def big_sphere(width: int, height: int) -> mb.Scene:
    v, f = mb.meshes.icosphere(7, 0.6)
    ball = mb.Object(
        mb.Mesh(v, f),
        (0.8, 0.4, 0.2),
        motion=mb.Motion.linear(translate((-0.7, -0.1, 0)), translate((0.7, 0.2, 0.3))),
    )
    cam = mb.Camera(mb.look_at((0, 0.3, 4), (0, 0, 0)), 0.8, width, height)
    return mb.Scene([ball], cam)


def measure(scene: mb.Scene, k: int, repeat: int):
    """(faces moving, frame wall/CPU ms without and with tables, build wall/CPU ms without and
    with, RMSE without and with, largest angle in degrees) of one scene."""
    movers = [o for o in scene.objects if o.is_moving or scene.camera_moves]
    tables = [mb.ContourTable(o.mesh, directions=k) for o in movers]
    opts = {"filter": "box", "segments": 2}

    def frame(use):
        return mb.render(
            scene, "motion_volume", contour_table=tables if use else False, error_estimate=False, **opts
        )

    (w0, w1), (c0, c1) = best_ms([lambda: frame(False), lambda: frame(True)], repeat)
    # the volume build alone (every moving object), without and with the table
    eye = scene.camera_at(scene.reference_t).pose[:3, 3]
    keys = [apparent_motion(scene, o, 2) for o in movers]

    def build(use):
        for o, ap, t in zip(movers, keys, tables):
            mb.motion_volume(
                o.mesh, ap, filter="box", colors=o.rgba, camera_position=eye, visible_only=True,
                contour_table=t if use else None,
            )  # fmt: skip

    (b0, b1), (bc0, bc1) = best_ms([lambda: build(False), lambda: build(True)], repeat)
    ref = mb.render(scene, "accumulation", samples=256, aa=2)
    f0 = mb.render(scene, "motion_volume", aa=2, **opts)
    f1 = mb.render(scene, "motion_volume", aa=2, contour_table=tables, **opts)
    rmse = [float(np.sqrt(((f.rgba - ref.rgba) ** 2).mean())) for f in (f0, f1)]
    faces = sum(len(o.mesh.faces) for o in movers)
    angle = float(np.degrees(f1.stats.get("contour_error", 0.0)))
    return faces, w0, w1, c0, c1, b0, b1, bc0, bc1, rmse[0], rmse[1], angle


def main() -> None:
    quick = "--quick" in sys.argv
    repeat = 3 if quick else 9
    k = 128
    scenes = {n: mb.SCENES[n](320, 240) for n in ("cube", "airplane", "sphere80k", "curved", "pan")}
    scenes["sphere328k"] = big_sphere(320, 240)
    rows = []
    for name, scene in scenes.items():
        row = measure(scene, k, repeat)
        rows.append((name, *row))
        faces, w0, w1, c0, c1, b0, b1, bc0, bc1, r0, r1, angle = row
        print(
            f"{name:12s} {faces:7d} faces  frame {w0:7.2f} -> {w1:7.2f} ms (cpu {c0:7.2f} -> {c1:7.2f})  "
            f"build {b0:7.2f} -> {b1:7.2f} ms (cpu {bc0:7.2f} -> {bc1:7.2f})  "
            f"rmse {r0:.5f} -> {r1:.5f}  angle {angle:.1f} deg",
            flush=True,
        )
    out = Path("out/bench")
    out.mkdir(parents=True, exist_ok=True)
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    lines = [
        f"# Contour tables driving the motion volume ({k} directions)",
        "",
        f"{platform.machine()}, {os.cpu_count()} CPUs, load average {load:.1f}; 320x240, box filter, 2 segments; "
        f"best of {repeat} interleaved rounds; ms; ratio = with table / without.",
        "",
        "| scene | faces moving | frame wall | frame CPU | build wall | build CPU | RMSE without / with | angle |",
        "|---|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for name, faces, w0, w1, c0, c1, b0, b1, bc0, bc1, r0, r1, ang in rows:
        lines.append(
            f"| {name} | {faces} | {w0:.2f} -> {w1:.2f} ({w1 / w0:.2f}) | {c0:.2f} -> {c1:.2f} ({c1 / c0:.2f}) | "
            f"{b0:.2f} -> {b1:.2f} ({b1 / b0:.2f}) | {bc0:.2f} -> {bc1:.2f} ({bc1 / bc0:.2f}) | "
            f"{r0:.5f} / {r1:.5f} | {ang:.1f} deg |"
        )
    (out / "contour_table.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
