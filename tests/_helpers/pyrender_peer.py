"""pyrender (offscreen, OSMesa) as the rasterizer's peer, plus image-diff helpers for tests.

pyrender under OSMesa returns RGB without alpha (coverage = depth > 0), depth as view-axis
distance with 0 for background, no multisampling. ``RenderFlags.FLAT`` gives the unlit base
colour without gamma, so it is directly comparable with ``shading="flat"``.
"""

from __future__ import annotations

import os

os.environ.setdefault("PYOPENGL_PLATFORM", "osmesa")

from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
import pyrender  # noqa: E402
import trimesh  # noqa: E402

FAILURES = Path(__file__).resolve().parents[2] / "out" / "test-failures"
_renderers: dict[tuple[int, int], pyrender.OffscreenRenderer] = {}


def renderer(width: int, height: int) -> pyrender.OffscreenRenderer:
    """One OSMesa renderer per image size, kept for the process (context creation is slow)."""
    key = (width, height)
    if key not in _renderers:
        _renderers[key] = pyrender.OffscreenRenderer(width, height)
    return _renderers[key]


def scene(meshes, camera, alpha_mode: str = "OPAQUE") -> pyrender.Scene:
    """A pyrender scene of ``meshes`` = [(vertices, faces, rgba (4,), double_sided[, pose (4,4)])]
    seen by a motionblur.Camera. pyrender sorts blended meshes by their node's position only."""
    sc = pyrender.Scene(bg_color=[0.0, 0.0, 0.0, 0.0], ambient_light=[0.0, 0.0, 0.0])
    for item in meshes:
        v, f, rgba, double_sided = item[:4]
        pose = item[4] if len(item) > 4 else np.eye(4)
        mat = pyrender.MetallicRoughnessMaterial(
            baseColorFactor=list(map(float, rgba)), alphaMode=alpha_mode, doubleSided=double_sided
        )
        tm = trimesh.Trimesh(np.asarray(v), np.asarray(f), process=False)
        sc.add(pyrender.Mesh.from_trimesh(tm, material=mat, smooth=False), pose=pose)
    cam = pyrender.PerspectiveCamera(
        yfov=camera.yfov, znear=camera.znear, zfar=camera.zfar, aspectRatio=camera.width / camera.height
    )
    sc.add(cam, pose=camera.pose)
    return sc


def render(meshes, camera, alpha_mode: str = "OPAQUE"):
    """(rgb (H,W,3) float in [0,1], depth (H,W) float32 with 0 for background) from pyrender FLAT."""
    r = renderer(camera.width, camera.height)
    color, depth = r.render(scene(meshes, camera, alpha_mode), flags=pyrender.RenderFlags.FLAT)
    return color.astype(np.float64) / 255.0, depth


def write_diff(name: str, ours: np.ndarray, theirs: np.ndarray) -> Path:
    """Writes ours | theirs | |difference| x 10 side by side as a PNG and returns its path."""
    from PIL import Image

    FAILURES.mkdir(parents=True, exist_ok=True)

    def rgb(a):
        a = np.asarray(a, dtype=np.float64)
        if a.ndim == 2:
            a = np.repeat(a[..., None], 3, axis=2)
        return a[..., :3]

    a, b = rgb(ours), rgb(theirs)
    img = np.concatenate([a, b, np.clip(np.abs(a - b) * 10.0, 0, 1)], axis=1)
    path = FAILURES / f"{name}.png"
    Image.fromarray(np.round(np.clip(img, 0, 1) * 255).astype(np.uint8)).save(path)
    return path
