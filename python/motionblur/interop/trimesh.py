"""trimesh in and out: ``Scene.from_trimesh`` and ``Mesh.to_trimesh`` delegate here.

[`read_trimesh`][motionblur.interop.trimesh.read_trimesh] turns a ``trimesh.Scene`` (or one ``trimesh.Trimesh``) into parts a
[`Scene`][motionblur.Scene] is made of: for every node of the scene graph that holds a triangle
mesh, the mesh's vertices placed in the world by the graph's transform, its faces and its
colour, and a camera (the scene's own camera when it has one, else one that frames the scene).

Colours: trimesh keeps RGBA as uint8; they are read as linear values ``/ 255``, as pyrender and
trimesh's glTF exporter (``baseColorFactor = colour / 255``) read them. One colour for the
whole mesh stays one colour; per-vertex colours stay per vertex; per-face colours become
per-vertex colours of unshared vertices (each face gets its own three vertices, so its colour
does not bleed into its neighbours); a texture is sampled at the vertices' UVs
(``visual.to_color()``); a mesh without colour is white (the default of
[`Object`][motionblur.Object]). Point clouds and paths in the scene are left out.

This module never imports [`motionblur.scene`][motionblur.scene] (which calls it), so there is no import cycle.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._optional import require
from .._validate import as_array, as_int
from ..raster import Camera

__all__ = ["Part", "read_trimesh", "to_trimesh", "framing_camera"]


@dataclass(frozen=True)
class Part:
    """One mesh of a scene: ``vertices`` (V,3) float64 world positions, ``faces`` (F,3) int64,
    ``color`` (4,) or (V,4) float32 straight linear RGBA, ``name`` (the graph node's)."""

    name: str
    vertices: np.ndarray
    faces: np.ndarray
    color: np.ndarray


def _colour(geom, vertices: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(vertices, faces, colour) of a trimesh geometry (see the module docs)."""
    visual = getattr(geom, "visual", None)
    kind = getattr(visual, "kind", None)
    if kind == "texture":
        try:
            visual = visual.to_color()
        except Exception:  # no UVs or no image: trimesh cannot sample it; the material's colour
            main = getattr(getattr(visual, "material", None), "main_color", None)
            rgba = np.asarray(main if main is not None else [255, 255, 255, 255], np.float32) / 255.0
            return vertices, faces, rgba
        kind = visual.kind
    if kind == "face":
        fc = np.asarray(visual.face_colors, np.float32) / 255.0
        if (fc == fc[0]).all():
            return vertices, faces, fc[0]
        # unshared vertices: a face's colour does not blend into its neighbours
        v = vertices[faces].reshape(-1, 3)
        f = np.arange(3 * len(faces), dtype=np.int64).reshape(-1, 3)
        return v, f, np.repeat(fc, 3, axis=0)
    if kind == "vertex":
        vc = np.asarray(visual.vertex_colors, np.float32) / 255.0
        return vertices, faces, (vc[0] if (vc == vc[0]).all() else vc)
    return vertices, faces, np.ones(4, np.float32)


def read_trimesh(scene, camera=None, *, width: int = 640, height: int = 480, yfov: float = 0.8):
    """``(parts, camera)`` of a ``trimesh.Scene`` or ``trimesh.Trimesh`` (module docs).

    ``camera``: a [`Camera`][motionblur.Camera], or None: the trimesh scene's camera when it has
    one (its vertical field of view and pose, at ``width`` x ``height``), else
    [`framing_camera`][motionblur.interop.trimesh.framing_camera] with ``yfov`` radians. The caller's scene is not modified (no
    camera is added to it). Raises TypeError for another type and ValueError for a scene
    without triangles.
    """
    tm = require("trimesh", "Scene.from_trimesh")
    width = as_int(width, "width", minimum=1)
    height = as_int(height, "height", minimum=1)
    if isinstance(scene, tm.Trimesh):
        nodes = [("mesh", np.eye(4), scene)]
    elif isinstance(scene, tm.Scene):
        nodes = []
        for node in scene.graph.nodes_geometry:
            transform, geometry_name = scene.graph[node]
            nodes.append((str(node), np.asarray(transform, np.float64), scene.geometry[geometry_name]))
    else:
        raise TypeError(f"scene: expected a trimesh.Scene or trimesh.Trimesh, got {type(scene).__name__}")
    parts = []
    for name, transform, geom in nodes:
        if not isinstance(geom, tm.Trimesh) or len(geom.faces) == 0:
            continue
        v = np.asarray(geom.vertices, np.float64) @ transform[:3, :3].T + transform[:3, 3]
        f = np.asarray(geom.faces, np.int64)
        if np.linalg.det(transform[:3, :3]) < 0:  # a mirroring node: keep the faces counter-clockwise
            f = f[:, ::-1].copy()
        v, f, c = _colour(geom, v, f)
        parts.append(Part(name, v, f, c))
    if not parts:
        raise ValueError("scene: holds no triangle mesh")
    if camera is None:
        if isinstance(scene, tm.Scene) and scene.has_camera:
            cam = scene.camera
            yfov_tm = float(np.radians(cam.fov[1]))
            znear = float(cam.z_near) if cam.z_near else 0.05
            zfar = float(cam.z_far) if cam.z_far else float("inf")
            camera = Camera(scene.camera_transform, yfov_tm, width, height, znear=znear, zfar=zfar)
        else:
            lo = np.min([p.vertices.min(axis=0) for p in parts], axis=0)
            hi = np.max([p.vertices.max(axis=0) for p in parts], axis=0)
            camera = framing_camera(np.stack([lo, hi]), yfov, width, height)
    elif not isinstance(camera, Camera):
        raise TypeError(f"camera: expected a motionblur.Camera or None, got {type(camera).__name__}")
    return parts, camera


def framing_camera(bounds, yfov: float, width: int, height: int) -> Camera:
    """A camera on the +Z side of the axis-aligned ``bounds`` (2,3) (min, max corners) looking
    down -Z at their centre (as trimesh's and pyrender's viewers start), far enough that the
    bounding sphere fits both fields of view with 5% to spare; ``znear`` just in front of the
    sphere, ``zfar`` infinite."""
    b = as_array(bounds, "bounds", np.float64, (2, 3))
    centre = b.mean(axis=0)
    radius = max(0.5 * float(np.linalg.norm(b[1] - b[0])), 1e-9)
    xfov = 2.0 * np.arctan(np.tan(yfov / 2.0) * width / height)
    distance = 1.05 * radius / np.sin(min(yfov, xfov) / 2.0)
    pose = np.eye(4)
    pose[:3, 3] = centre + [0.0, 0.0, distance]
    znear = max(distance - 1.05 * radius, 1e-3 * distance)
    return Camera(pose, yfov, width, height, znear=znear, zfar=float("inf"))


def to_trimesh(vertices: np.ndarray, faces: np.ndarray, rgba=None):
    """A ``trimesh.Trimesh`` of ``vertices`` (V,3) and ``faces`` (F,3), ``process=False`` (the
    vertices are not merged or reordered), with ``rgba`` (4,) or (V,4) straight linear colour in
    [0, 1] as uint8 vertex colours when given."""
    tm = require("trimesh", "to_trimesh")
    kwargs = {}
    if rgba is not None:
        c = np.asarray(rgba, np.float64)
        c = np.broadcast_to(c, (len(vertices), c.shape[-1])) if c.ndim == 1 else c
        kwargs["vertex_colors"] = np.round(np.clip(c, 0.0, 1.0) * 255.0).astype(np.uint8)
    return tm.Trimesh(vertices=np.array(vertices), faces=np.array(faces), process=False, **kwargs)
