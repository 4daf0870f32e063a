"""References cached on disk, keyed by a hash of the scene and of the reference's settings.

A full report renders dozens of references (Mitsuba at K = 256 shutter times each, and each
method's own limit, accumulation with 1024 samples); a rerun, or another worker of a Dask
cluster sharing the folder, must render none of them twice. [`scene_hash`][motionblur.evaluation.cache.scene_hash] digests
everything a render of a [`Scene`][motionblur.Scene] depends on (every object's vertices, faces,
colours, shading and motion keyframes, the camera and its motion, lights, ambient, shutter,
background, reference time), so two scenes with equal hashes render equal images and a scene
changed in any of these gets a new key; [`cached`][motionblur.evaluation.cache.cached] reads or renders and writes one
``(H,W,4)`` float32 image under ``<folder>/<label>_<hash>.npy``. Writes go to a temporary
file renamed into place, so concurrent workers never read half a file.
"""

from __future__ import annotations

import hashlib
import json
import os
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from ..scene import Motion, Scene, Trapezoid

__all__ = ["scene_hash", "reference_key", "cached"]

#: Bumped when a change to the reference renderers makes old cached images wrong.
CACHE_VERSION = 1


def _arr(h, a) -> None:
    a = np.ascontiguousarray(np.asarray(a))
    h.update(f"{a.dtype.str}{a.shape}".encode())
    h.update(a.tobytes())


def _motion(h, m: Motion | None) -> None:
    if m is None:
        h.update(b"static")
        return
    _arr(h, m.times)
    if m.is_deforming:
        h.update(b"deforming")
        _arr(h, m.vertices)
    else:
        _arr(h, m.transforms)


def scene_hash(scene: Scene) -> str:
    """Hex SHA-256 (first 16 digits) of everything that decides a render of ``scene``."""
    h = hashlib.sha256(f"motionblur-scene-v{CACHE_VERSION}".encode())
    cam = scene.camera
    h.update(json.dumps([cam.width, cam.height, float(cam.yfov), float(cam.znear), float(cam.zfar)]).encode())
    _arr(h, np.asarray(cam.pose, np.float64))
    _motion(h, scene.camera_motion)
    for o in scene.objects:
        h.update(f"object:{o.shading}".encode())
        _arr(h, o.mesh.vertices)
        _arr(h, o.mesh.faces)
        _arr(h, o.color)
        _motion(h, o.motion)
    for light in scene.lights:
        _arr(h, np.asarray(light.direction, np.float64))
        _arr(h, np.asarray(light.intensity, np.float64))
    _arr(h, scene.ambient)
    _arr(h, scene.background)
    shutter = scene.shutter
    if isinstance(shutter, str):
        h.update(shutter.encode())
    elif isinstance(shutter, Trapezoid):
        h.update(repr(shutter).encode())
    else:
        h.update(np.asarray(shutter, np.float64).tobytes())
    h.update(repr(float(scene.reference_t)).encode())
    return h.hexdigest()[:16]


def reference_key(scene: Scene, kind: str, **settings) -> str:
    """The cache file's stem: ``kind``, the scene's hash and a hash of ``settings`` (K, spp,
    seed, variant, samples, aa: whatever decides the reference besides the scene)."""
    s = hashlib.sha256(json.dumps(settings, sort_keys=True, default=str).encode()).hexdigest()[:8]
    return f"{kind}_{scene_hash(scene)}_{s}"


def cached(folder, key: str, render: Callable[[], np.ndarray]) -> tuple[np.ndarray, float]:
    """``(image, ms)``: the array stored under ``folder/key.npy``, or ``render()`` written there
    first; ``ms`` is the render's wall time, 0.0 when the file was there."""
    path = Path(folder) / f"{key}.npy"
    if path.exists():
        return np.load(path), 0.0
    t0 = time.perf_counter()
    img = np.asarray(render(), np.float32)
    ms = (time.perf_counter() - t0) * 1e3
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    with open(tmp, "wb") as fh:
        np.save(fh, img)
    os.replace(tmp, path)
    return img, ms
