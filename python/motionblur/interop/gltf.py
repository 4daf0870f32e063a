"""Animated glTF 2.0 in: ``Scene.from_gltf`` delegates here.

[`read_gltf`][motionblur.interop.gltf.read_gltf] reads a ``.gltf`` (buffers in ``.bin`` files beside it or embedded as data
URIs) or ``.glb`` file with pygltflib (the ``interop`` extra) into the parts of a
[`Scene`][motionblur.Scene] over a shutter interval:

- **meshes**: every primitive drawn as triangles (``TRIANGLES``, ``TRIANGLE_STRIP``,
  ``TRIANGLE_FAN``; points and lines are left out) of every node of the file's scene, one
  object per primitive, named after its node (``node/1``, ``node/2`` ... for a mesh of several
  primitives). Accessors may be interleaved (``byteStride``), normalized or sparse.
- **colour**: the material's ``baseColorFactor`` (linear RGBA) times ``COLOR_0`` (linear, per
  vertex); ``alphaMode`` ``OPAQUE`` sets alpha to 1, ``MASK`` to 0 or 1 at ``alphaCutoff``.
  Textures are not sampled (the factor alone colours a textured material).
- **node hierarchy**: ``matrix`` or translation / rotation / scale per node, composed from the
  scene's roots.
- **animation** (one, by index or name): ``translation``, ``rotation``, ``scale`` and morph
  ``weights`` channels, with ``LINEAR`` (slerp for rotations), ``STEP`` and ``CUBICSPLINE``
  interpolation. The shutter [0, 1] spans ``shutter = (start, end)`` seconds of it (default: the
  animation's first to last key). The keyframes of the objects are the animation's own key
  times inside the shutter plus its two ends (a ``STEP`` key also one millionth of the shutter
  before it), and ``resample`` N + 1 evenly spaced times when asked: at those times the scene
  is exactly the animation, between them the object's motion interpolates (lerp and slerp of
  the world placement, or vertex positions linearly).
- **morph targets** (``POSITION`` displacements weighted by the mesh's, the node's or the
  animated weights) and **skins** (``JOINTS_0`` / ``WEIGHTS_0`` with the joints' world
  placements times their ``inverseBindMatrices``; the skinned node's own placement is ignored,
  as the specification says) make a deforming motion of world vertex positions.
- an object whose world placement is a rotation times a positive uniform scale at every key
  gets a rigid [`Motion`][motionblur.Motion] of its local mesh; a non-uniform scale, shear or
  mirror gives a deforming motion (a mirror also reverses the faces to keep them
  counter-clockwise); an object that does not move gets no motion.
- **camera**: the first node with a perspective camera (``yfov``, ``znear``, ``zfar``; its
  ``aspectRatio`` gives way to ``width / height``), moving with its node as the scene's
  ``camera_motion``; without one, a camera framing every position the objects take.

KHR extensions (lights, materials, compression) are not read; a file that requires one raises
ValueError. This module never imports [`motionblur.scene`][motionblur.scene] (which calls it).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .._optional import require
from .._validate import as_int
from ..raster import Camera
from ._gltf_data import GltfData
from .trimesh import framing_camera

__all__ = ["GltfPart", "read_gltf"]

_SIMILAR_TOL = 1e-4  # |R^T R - I| of a world placement that is still a rotation times a scale


@dataclass(frozen=True)
class GltfPart:
    """One primitive of a node. ``vertices`` (V,3) float64: local positions for a rigid motion,
    else world positions at the shutter's start; ``faces`` (F,3) int64; ``color`` (4,) or (V,4)
    float32 straight linear RGBA; ``times`` (K,) float64 in [0, 1] or None; ``transforms``
    (K,4,4) rigid world placements, or ``positions`` (K,V,3) world vertex positions, or neither
    (a still object, ``vertices`` then in the world)."""

    name: str
    vertices: np.ndarray
    faces: np.ndarray
    color: np.ndarray
    times: np.ndarray | None = None
    transforms: np.ndarray | None = None
    positions: np.ndarray | None = None


def _similar(m: np.ndarray) -> np.ndarray | None:
    """``m`` (4,4) made an exact rotation times a positive uniform scale plus a translation, or
    None when it is not one within `_SIMILAR_TOL`."""
    lin = m[:3, :3]
    det = float(np.linalg.det(lin))
    if not det > 0 or abs(m[3] - [0, 0, 0, 1]).max() > 1e-9:
        return None
    s = det ** (1.0 / 3.0)
    r = lin / s
    if np.abs(r.T @ r - np.eye(3)).max() > _SIMILAR_TOL:
        return None
    u, _, vt = np.linalg.svd(r)
    out = np.eye(4)
    out[:3, :3] = s * (u @ vt)
    out[:3, 3] = m[:3, 3]
    return out


def _key_times(data: GltfData, anim, start: float, end: float, resample: int) -> np.ndarray:
    """Shutter times (seconds) of the keyframes: the animation's keys in [start, end], the ends,
    a time just before each STEP key, and ``resample`` + 1 evenly spaced times when > 0."""
    times = {start, end}
    eps = 1e-6 * (end - start)
    if anim is not None:
        for ch in anim.channels:
            sampler = anim.samplers[ch.sampler]
            for s in data.accessor(sampler.input)[:, 0]:
                if start < s < end:
                    times.add(float(s))
                    if sampler.interpolation == "STEP" and s - eps > start:
                        times.add(float(s) - eps)
    if resample > 0:
        times.update(np.linspace(start, end, resample + 1).tolist())
    return np.array(sorted(times))


def _shutter(data: GltfData, anim, shutter) -> tuple[float, float]:
    if shutter is None:
        if anim is None:
            return 0.0, 1.0
        keys = np.concatenate([data.accessor(anim.samplers[c.sampler].input)[:, 0] for c in anim.channels])
        start, end = float(keys.min()), float(keys.max())
        return (start, end) if end > start else (start, start + 1.0)
    try:
        start, end = (float(x) for x in shutter)
    except (TypeError, ValueError) as exc:
        raise TypeError("shutter: expected (start, end) in seconds of the animation") from exc
    if not (math.isfinite(start) and math.isfinite(end) and end > start):
        raise ValueError(f"shutter: expected finite start < end, got ({start}, {end})")
    return start, end


def _animation(gltf, animation):
    anims = gltf.animations or []
    if isinstance(animation, str):
        named = [a for a in anims if a.name == animation]
        if not named:
            raise ValueError(f"animation: no animation named {animation!r} (have {[a.name for a in anims]})")
        return named[0]
    index = as_int(animation, "animation", minimum=0)
    if not anims:
        return None
    if index >= len(anims):
        raise ValueError(f"animation: index {index} out of range (the file has {len(anims)})")
    return anims[index]


def _part(data: GltfData, node: int, p_index: int, name: str, times: np.ndarray, secs: np.ndarray, poses):
    """The GltfPart of primitive ``p_index`` of ``node``'s mesh; ``poses`` (K, nodes, 4, 4) are
    the world placements at the key times ``secs``."""
    prim_v, faces, colour = data.primitive(node, p_index)
    n = data.gltf.nodes[node]
    morphs = data.morph_positions(node, p_index, secs)  # (K,V,3) local, or None when no targets
    skinned = n.skin is not None and data.has_skin_attributes(node, p_index)
    world = poses[:, node]
    if skinned or morphs is not None:
        local = morphs if morphs is not None else np.broadcast_to(prim_v, (len(secs), *prim_v.shape))
        if skinned:
            pos = np.stack([data.skin(node, p_index, local[k], poses[k]) for k in range(len(secs))])
        else:
            pos = np.einsum("kij,kvj->kvi", world[:, :3, :3], local) + world[:, None, :3, 3]
        if not skinned and np.linalg.det(world[0, :3, :3]) < 0:
            faces = faces[:, ::-1].copy()
        if (pos == pos[0]).all():
            return GltfPart(name, pos[0].copy(), faces, colour)
        return GltfPart(name, pos[0].copy(), faces, colour, times, positions=pos)
    if (world == world[0]).all():
        v = prim_v @ world[0, :3, :3].T + world[0, :3, 3]
        f = faces[:, ::-1].copy() if np.linalg.det(world[0, :3, :3]) < 0 else faces
        return GltfPart(name, v, f, colour)
    rigid = [_similar(w) for w in world]
    if all(r is not None for r in rigid):
        return GltfPart(name, prim_v, faces, colour, times, transforms=np.stack(rigid))
    pos = np.einsum("kij,vj->kvi", world[:, :3, :3], prim_v) + world[:, None, :3, 3]
    if np.linalg.det(world[0, :3, :3]) < 0:
        faces = faces[:, ::-1].copy()
    return GltfPart(name, pos[0].copy(), faces, colour, times, positions=pos)


def _camera(data: GltfData, poses, times, width: int, height: int):
    """(Camera, camera keys or None) of the first node with a perspective camera, or None."""
    gltf = data.gltf
    for i in data.scene_nodes():
        n = gltf.nodes[i]
        if n.camera is None:
            continue
        cam = gltf.cameras[n.camera]
        if cam.type != "perspective" or cam.perspective is None:
            continue
        per = cam.perspective
        pose0 = _unscaled(poses[0, i])
        camera = Camera(pose0, float(per.yfov), width, height, znear=float(per.znear),
                        zfar=float(per.zfar) if per.zfar else float("inf"))  # fmt: skip
        keys = np.stack([_unscaled(p) @ np.linalg.inv(pose0) for p in poses[:, i]])
        if np.allclose(keys, np.eye(4), atol=1e-12):
            return camera, None
        return camera, (times, keys)
    return None


def _unscaled(m: np.ndarray) -> np.ndarray:
    """``m`` with its linear part made the nearest rotation (a camera neither scales nor mirrors)."""
    u, _, vt = np.linalg.svd(m[:3, :3])
    r = u @ vt
    if np.linalg.det(r) < 0:
        r = u @ np.diag([1.0, 1.0, -1.0]) @ vt
    out = np.eye(4)
    out[:3, :3], out[:3, 3] = r, m[:3, 3]
    return out


def read_gltf(path, *, shutter=None, animation=0, camera=None, width: int = 640, height: int = 480,
              resample: int = 0):  # fmt: skip
    """``(parts, camera, camera_keys)`` of the glTF file ``path`` (module docs): a list of
    [`GltfPart`][motionblur.interop.gltf.GltfPart], a [`Camera`][motionblur.Camera] (``camera`` when given) and None or
    ``(times (K,), transforms (K,4,4))`` of the camera's motion ``pose(t) = M(t) @ camera.pose``.

    Raises FileNotFoundError for a missing file, ValueError for a file that is not glTF 2.0,
    requires an extension, holds no triangle or names a missing animation, TypeError naming the
    argument for wrong types.
    """
    pygltflib = require("pygltflib", "Scene.from_gltf")
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"path: no such file {str(path)!r}")
    width = as_int(width, "width", minimum=1)
    height = as_int(height, "height", minimum=1)
    resample = as_int(resample, "resample", minimum=0, maximum=100000)
    if camera is not None and not isinstance(camera, Camera):
        raise TypeError(f"camera: expected a motionblur.Camera or None, got {type(camera).__name__}")
    try:
        gltf = pygltflib.GLTF2().load(str(path))
    except Exception as exc:  # pygltflib raises whatever its JSON or struct readers raise
        raise ValueError(f"path: {str(path)!r} is not a readable glTF 2.0 file ({exc})") from exc
    if gltf is None or not str(getattr(gltf.asset, "version", "")).startswith("2"):
        raise ValueError(f"path: {str(path)!r} is not a glTF 2.0 file")
    if gltf.extensionsRequired:
        raise ValueError(
            f"path: {str(path)!r} requires extensions that are not read: {gltf.extensionsRequired}"
        )
    data = GltfData(gltf, path)
    anim = data.anim = _animation(gltf, animation)
    start, end = _shutter(data, anim, shutter)
    secs = _key_times(data, anim, start, end, resample)
    times = (secs - start) / (end - start)
    poses = np.stack([data.world_poses(s) for s in secs])  # (K, nodes, 4, 4)
    parts = []
    for node in data.scene_nodes():
        n = gltf.nodes[node]
        if n.mesh is None:
            continue
        prims = gltf.meshes[n.mesh].primitives
        label = n.name or f"node{node}"
        for p_index in range(len(prims)):
            if data.triangles(node, p_index) is None:
                continue
            name = label if len(prims) == 1 else f"{label}/{p_index + 1}"
            parts.append(_part(data, node, p_index, name, times, secs, poses))
    if not parts:
        raise ValueError(f"path: {str(path)!r} holds no triangle mesh in its scene")
    cam_keys = None
    if camera is None:
        found = _camera(data, poses, times, width, height)
        if found is not None:
            camera, cam_keys = found
        else:
            pts = []
            for p in parts:
                if p.transforms is not None:
                    pts += [p.vertices @ m[:3, :3].T + m[:3, 3] for m in p.transforms]
                else:
                    pts += list(p.positions) if p.positions is not None else [p.vertices]
            allp = np.concatenate(pts)
            camera = framing_camera(np.stack([allp.min(axis=0), allp.max(axis=0)]), 0.8, width, height)
    return parts, camera, cam_keys
