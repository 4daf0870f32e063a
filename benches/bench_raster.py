"""Rasterizer benchmark: motionblur.rasterize against pyrender (offscreen, OSMesa), same run.

Icospheres of 5k, 82k and 328k faces (meshes.icosphere(4/6/7)) at 1024x768, FLAT shading:

- opaque: one opaque sphere. Peer: pyrender ``render()`` with ``RenderFlags.FLAT``.
- transparent: the same sphere at alpha 0.5, back faces drawn. Ours: ``blend="exact"`` (every
  fragment composited in exact depth order). Peer: pyrender's BLEND material, which blends in
  submission order with no per-fragment sorting (unsorted hardware blending).

Both sides are timed end to end from Python (pyrender includes its readback into numpy; ours
includes building the frame's numpy arrays). Prints best-of-N milliseconds and ratios
(motionblur / pyrender, so below 1 means we are faster) and writes out/bench/raster.md.
Usage: python benches/bench_raster.py [--quick]
"""

from __future__ import annotations

import os
import platform
import sys
import time
from pathlib import Path

os.environ.setdefault("PYOPENGL_PLATFORM", "osmesa")

import numpy as np  # noqa: E402
import pyrender  # noqa: E402
import trimesh  # noqa: E402

import motionblur as mb  # noqa: E402
from motionblur import meshes  # noqa: E402

W, H = 1024, 768


def best_ms(fn, repeat: int) -> float:
    fn()  # warm-up (shader compilation, allocation)
    best = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best * 1e3


def pyrender_scene(v, f, rgba, camera, blend: bool):
    sc = pyrender.Scene(bg_color=[0.0, 0.0, 0.0, 0.0], ambient_light=[0.0, 0.0, 0.0])
    mat = pyrender.MetallicRoughnessMaterial(
        baseColorFactor=list(map(float, rgba)), alphaMode="BLEND" if blend else "OPAQUE", doubleSided=blend
    )
    sc.add(pyrender.Mesh.from_trimesh(trimesh.Trimesh(v, f, process=False), material=mat, smooth=False))
    cam = pyrender.PerspectiveCamera(
        yfov=camera.yfov, znear=camera.znear, zfar=camera.zfar, aspectRatio=W / H
    )
    sc.add(cam, pose=camera.pose)
    return sc


def main() -> None:
    quick = "--quick" in sys.argv
    subs = (4, 6) if quick else (4, 6, 7)
    cores = os.cpu_count()
    header = (
        f"machine: {platform.machine()}, {cores} cores, no GPU (pyrender on Mesa's OSMesa software "
        f"rasterizer), python {platform.python_version()}, pyrender {pyrender.__version__}"
    )
    print(header)
    camera = mb.Camera(mb.look_at((0.3, 0.4, 3.2), (0, 0, 0)), np.pi / 3, W, H)
    renderer = pyrender.OffscreenRenderer(W, H)
    rows = []
    for sub in subs:
        v, f = meshes.icosphere(sub)
        repeat = 7 if len(f) < 100_000 else 5
        for job, alpha in (("opaque", 1.0), ("transparent a=0.5", 0.5)):
            rgba = (0.8, 0.5, 0.2, alpha)
            draw = mb.Draw(v, f, rgba, cull_back=alpha == 1.0)
            sc = pyrender_scene(v, f, rgba, camera, blend=alpha < 1.0)
            ours = best_ms(lambda d=draw: mb.rasterize(camera, d, blend="exact"), repeat)
            peer = best_ms(lambda s=sc: renderer.render(s, flags=pyrender.RenderFlags.FLAT), repeat)
            rows.append((len(f), job, ours, peer, ours / peer))
            print(
                f"{len(f):>8} faces  {job:<18} ours {ours:8.2f} ms  pyrender {peer:8.2f} ms  ratio {ours / peer:5.2f}"
            )
    renderer.delete()
    lines = [
        "# Rasterizer benchmark",
        "",
        header + ".",
        f"{W}x{H}, FLAT shading, best of 5-7 runs after a warm-up; ratio = motionblur / pyrender "
        "(below 1: we are faster), measured in the same run (`python benches/bench_raster.py`, "
        "run by `make bench`). Transparent: ours composites every fragment in exact depth order, "
        "pyrender blends unsorted.",
        "",
        "| faces | job | motionblur ms | pyrender ms | ratio |",
        "|---:|---|---:|---:|---:|",
    ]
    lines += [f"| {n:,} | {job} | {o:.2f} | {p:.2f} | {r:.2f} |" for n, job, o, p, r in rows]
    out = Path("out/bench")
    out.mkdir(parents=True, exist_ok=True)
    (out / "raster.md").write_text("\n".join(lines) + "\n")
    print(f"wrote {out / 'raster.md'}")


if __name__ == "__main__":
    main()
