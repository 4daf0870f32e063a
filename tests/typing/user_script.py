"""A user's script, type-checked with ``mypy --strict`` by ``make lint``: the public API is typed
(no ``Any`` leaks out of a Frame, no untyped call)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from numpy.typing import NDArray

import motionblur as mb
from motionblur.scene import translate


def cube_scene(width: int, height: int) -> mb.Scene:
    cam = mb.Camera(mb.look_at([0, 0.5, 4], [0, 0, 0]), yfov=0.7, width=width, height=height)
    cube = mb.Object(
        mb.meshes.box((0.7, 0.7, 0.7)),
        color=(0.9, 0.35, 0.1),
        motion=mb.Motion.linear(translate((-1, 0, 0)), translate((1, 0, 0))),
    )
    light = mb.DirectionalLight((0.0, -1.0, -1.0), 1.0)
    return mb.Scene([cube], cam, lights=[light], shutter="box")


def blurred(scene: mb.Scene) -> NDArray[np.float32]:
    frame = mb.render(scene, "motion_volume", segments=4)
    depth: NDArray[np.float32] = frame.depth
    ids: NDArray[np.int32] = frame.ids
    velocity: NDArray[np.float32] = frame.velocity
    assert depth.shape == ids.shape == velocity.shape[:2]
    return frame.rgba


def error(scene: mb.Scene, out: Path) -> float:
    acc = mb.render(scene, "accumulation", samples=16)
    path = acc.save_exr(out / "acc.exr")
    back: mb.Frame = mb.read_image(path)
    coverage: NDArray[np.float32] = back.coverage
    assert coverage.shape == (back.height, back.width)
    return mb.metrics.rmse(mb.render(scene, "motion_volume"), back)


def sharp(scene: mb.Scene) -> mb.Frame:
    draws = [mb.Draw(o.world_vertices(1.0), o.mesh.faces, o.rgba) for o in scene.objects]
    return mb.rasterize(scene.camera, draws, samples=2)


if __name__ == "__main__":
    s = cube_scene(160, 120)
    print(blurred(s).shape, error(s, Path("out/typing")), sharp(s).width)
