"""Ghosting of frame-averaged blur (GoPro/REDS-style datasets) against the exact integral.

Those datasets make a blurred frame by averaging K consecutive frames of 240 fps video (K = 7 to
13). Each video frame is nearly sharp (a short exposure in daylight), so the average is K copies
of the object, not a continuous smear: the accumulation buffer with K stratified samples. This
bench renders that average and the exact time integral of the same motion (``motionblur.exact``)
for the shipped bunny and the ant over a lit floor at 320x240, translating slowly and fast, and
writes the RMSE (premultiplied linear RGBA) and a picture per motion:
out/bench/ghosting/results.md and ghosting_<scene>.png (average of K=7, exact, and |difference|x4).

    python benches/bench_ghosting.py [--size 320x240] [--out out/bench/ghosting]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

import motionblur as mb
from motionblur.scenes_real import _camera, _floor, real_mesh

KS = (7, 9, 11, 13)
#: (name, mesh, distance travelled across the view in scene units): about 6 and 90 pixels at 320x240
MOTIONS = (
    ("bunny slow", "bunny", 0.08),
    ("bunny fast", "bunny", 1.2),
    ("ant slow", "ant", 0.08),
    ("ant fast", "ant", 1.2),
)


def _scene(mesh: str, distance: float, width: int, height: int) -> mb.Scene:
    y = -0.5 + 0.002
    motion = mb.Motion.linear(mb.translate((-distance / 2, y, 0.0)), mb.translate((distance / 2, y, 0.0)))
    obj = mb.Object(real_mesh(mesh), color=(0.85, 0.62, 0.35), shading="lambert", motion=motion, name=mesh)
    light = mb.DirectionalLight((-0.35, -1.0, -0.55), 1.0)
    return mb.Scene([obj, _floor()], _camera(width, height), lights=[light], ambient=0.0, shutter="box")


def _pixels(scene: mb.Scene) -> float:
    """How far the object's origin moves on screen over the shutter, in pixels."""
    p0 = scene.camera.project(scene.objects[0].transform_at(0.0)[None, :3, 3])[0][0]
    p1 = scene.camera.project(scene.objects[0].transform_at(1.0)[None, :3, 3])[0][0]
    return float(np.linalg.norm(p1 - p0))


def _rmse(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.sqrt(np.mean((a.astype(np.float64) - b) ** 2)))


def _picture(path: Path, frames: list[np.ndarray]) -> None:
    from PIL import Image

    row = np.concatenate(frames, axis=1)
    rgb = np.clip(row[..., :3] + (1 - row[..., 3:4]) * 0.1, 0, 1) ** (1 / 2.2)
    Image.fromarray((rgb * 255 + 0.5).astype(np.uint8)).save(path)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--size", default="320x240")
    p.add_argument("--out", default="out/bench/ghosting")
    args = p.parse_args(argv)
    w, h = (int(x) for x in args.size.split("x"))
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    lines = [
        "# Ghosting of frame-averaged blur against the exact integral",
        "",
        f"{w}x{h}, box shutter; RMSE of the average of K sharp frames (a 240 fps video's K frames) "
        "against `motionblur.exact` of the same motion (premultiplied linear RGBA).",
        "",
        "| motion | pixels moved | " + " | ".join(f"K={k}" for k in KS) + " |",
        "|---|---:|" + "---:|" * len(KS),
    ]
    for name, mesh, distance in MOTIONS:
        scene = _scene(mesh, distance, w, h)
        exact = mb.exact(scene).rgba
        row = []
        for k in KS:
            avg = mb.render(scene, "accumulation", samples=k, error_estimate=False).rgba
            row.append(_rmse(avg, exact))
            if k == KS[0]:
                diff = np.abs(avg - exact) * 4
                diff[..., 3] = 1.0
                _picture(out / f"ghosting_{name.replace(' ', '_')}.png", [avg, exact, diff])
        lines.append(f"| {name} | {_pixels(scene):.0f} | " + " | ".join(f"{e:.2e}" for e in row) + " |")
        print(lines[-1], flush=True)
    lines += ["", f"took {time.perf_counter() - t0:.0f} s"]
    (out / "results.md").write_text("\n".join(lines) + "\n")
    print(f"wrote {out / 'results.md'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
