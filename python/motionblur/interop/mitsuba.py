"""A [`Scene`][motionblur.Scene] at one shutter time as a Mitsuba 3 scene dictionary.

``to_mitsuba_dict(scene, t)`` gives what ``mitsuba.load_dict`` takes, for users who want to
render the scene their own way (another integrator, more bounces, a different film). It follows
the conversion of the time-sampled reference ([`motionblur.evaluation.reference`][motionblur.evaluation.reference], which
uses the same sensor):

- every object is an ``mi.Mesh`` of its world vertex positions at ``t`` (rigid, deforming or
  still alike), keyed ``obj<k>`` by its index in ``scene.objects``;
- ``flat`` objects are area emitters of their colour on a black diffuse BSDF, ``lambert``
  objects diffuse BSDFs of their colour, with vertex normals as the rasterizer computes them;
  per-vertex colours become a ``vertex_color`` mesh attribute read by a ``mesh_attribute``
  texture; alpha below 1 wraps the BSDF in a ``mask`` of that opacity;
- the scene's directional lights are ``directional`` emitters of irradiance ``pi * intensity``
  (Mitsuba's diffuse BSDF is ``albedo / pi``); ambient light is left out (a constant emitter
  would also fill the background);
- the sensor: ``perspective``, ``to_world = pose(t) @ diag(-1, 1, -1, 1)``, ``fov_axis='y'``,
  the camera's near and far clip (an infinite far plane becomes 1e7), an ``hdrfilm`` of the
  camera's size with a box filter and ``rgba`` pixels, an ``independent`` sampler;
- the integrator: ``path`` with ``max_depth=1`` when every object is flat (emitters seen
  directly), else ``direct``. Unlike the rasterizer, Mitsuba lets flat emitters light lambert
  objects and casts shadows; the reference renders such scenes in two passes to avoid that.

Mitsuba must be imported with a variant set to make the meshes: ``variant`` (default: the one
the reference uses) is set when none is.
"""

from __future__ import annotations

import os

import numpy as np

from .._optional import require
from .._validate import as_float, as_int
from ..scene import Scene

__all__ = [
    "to_mitsuba_dict",
    "sensor_dict",
    "vertex_normals",
    "mitsuba_variant",
    "set_variant",
    "OPENGL_TO_MITSUBA",
]

_LLVM = "/usr/lib/x86_64-linux-gnu/libLLVM-19.so"

#: camera-to-world of OpenGL (looking down -Z) to Mitsuba's (looking down +Z): ``pose @ this``
OPENGL_TO_MITSUBA = np.diag([-1.0, 1.0, -1.0, 1.0])


def mitsuba_variant() -> str:
    """The Mitsuba variant used by default: ``llvm_ad_rgb`` when libLLVM is there (the file
    ``DRJIT_LIBLLVM_PATH`` names, or Debian's LLVM 19 at ``/usr/lib/x86_64-linux-gnu/libLLVM-19.so``),
    else ``scalar_rgb``. The process environment is read, never written: where Dr.Jit cannot
    load LLVM by itself, set ``DRJIT_LIBLLVM_PATH`` ([`set_variant`][motionblur.interop.mitsuba.set_variant] says so)."""
    path = os.environ.get("DRJIT_LIBLLVM_PATH")
    if path:
        return "llvm_ad_rgb" if os.path.exists(path) else "scalar_rgb"
    return "llvm_ad_rgb" if os.path.exists(_LLVM) else "scalar_rgb"


def set_variant(mi, variant: str):
    """``mi`` (the mitsuba module) with ``variant`` set. An ``llvm`` variant that cannot load
    raises RuntimeError naming ``DRJIT_LIBLLVM_PATH``, the variable that tells Dr.Jit where
    libLLVM is."""
    if mi.variant() == variant:
        return mi
    try:
        mi.set_variant(variant)
        if variant.startswith("llvm"):
            mi.Float([1.0]) + 1.0  # the backend loads LLVM at its first use
    except Exception as exc:  # Dr.Jit raises ImportError or RuntimeError, by version
        if not variant.startswith("llvm"):
            raise
        where = os.environ.get("DRJIT_LIBLLVM_PATH")
        raise RuntimeError(
            f"Mitsuba's {variant} variant cannot load libLLVM"
            + (f" from DRJIT_LIBLLVM_PATH={where!r}" if where else " (DRJIT_LIBLLVM_PATH is not set)")
            + f": set DRJIT_LIBLLVM_PATH to libLLVM's shared library (Debian: {_LLVM}, package "
            "libllvm19), or pass variant='scalar_rgb'"
        ) from exc
    return mi


def vertex_normals(v, f) -> np.ndarray:
    """(V,3) float32 area-weighted vertex normals of vertices ``v`` (V,3) and faces ``f`` (F,3),
    as the rasterizer computes them."""
    v = np.asarray(v, np.float64)
    f = np.asarray(f)
    n = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
    out = np.zeros_like(v)
    for i in range(3):
        np.add.at(out, f[:, i], n)
    length = np.linalg.norm(out, axis=1, keepdims=True)
    return (out / np.where(length > 0, length, 1.0)).astype(np.float32)


def sensor_dict(mi, camera, pose, spp: int, lens=None) -> dict:
    """The ``perspective`` sensor dict of ``camera`` (a [`Camera`][motionblur.Camera]) at ``pose``
    (4,4) camera-to-world, with an rgba ``hdrfilm`` (box filter) and ``spp`` samples per pixel;
    with ``lens`` = (aperture radius, focus distance) in scene units, a ``thinlens`` sensor."""
    extra = {} if lens is None else {"aperture_radius": float(lens[0]), "focus_distance": float(lens[1])}
    return {
        "type": "perspective" if lens is None else "thinlens",
        **extra,
        "fov": float(np.degrees(camera.yfov)),
        "fov_axis": "y",
        "near_clip": float(camera.znear),
        "far_clip": float(camera.zfar) if np.isfinite(camera.zfar) else 1e7,
        "to_world": mi.ScalarTransform4f(np.asarray(pose, np.float64) @ OPENGL_TO_MITSUBA),
        "film": {
            "type": "hdrfilm",
            "width": int(camera.width),
            "height": int(camera.height),
            "rfilter": {"type": "box"},
            "pixel_format": "rgba",
        },
        "sampler": {"type": "independent", "sample_count": int(spp)},
    }


def _mi(variant):
    mi = require("mitsuba", "to_mitsuba_dict")
    if variant is not None:
        return set_variant(mi, variant)
    if mi.variant() is None:
        return set_variant(mi, mitsuba_variant())
    return mi


def _mesh(mi, k: int, obj, t: float):
    v = np.asarray(obj.world_vertices(t), np.float64)
    f = np.asarray(obj.mesh.faces)
    rgba = obj.rgba
    per_vertex = rgba.ndim == 2
    lit = obj.shading == "lambert"
    colour = {"type": "mesh_attribute", "name": "vertex_color"} if per_vertex else {
        "type": "rgb", "value": [float(x) for x in rgba[:3]]}  # fmt: skip
    props = mi.Properties()
    bsdf = {"type": "diffuse", "reflectance": colour if lit else {"type": "rgb", "value": [0.0, 0.0, 0.0]}}
    alpha = float(rgba[..., 3].min())
    if alpha < 1.0:
        bsdf = {"type": "mask", "opacity": {"type": "rgb", "value": [alpha] * 3}, "bsdf": bsdf}
    props["bsdf"] = mi.load_dict(bsdf)
    if not lit:
        props["emitter"] = mi.load_dict({"type": "area", "radiance": colour})
    mesh = mi.Mesh(f"obj{k}", len(v), len(f), props, has_vertex_normals=lit)
    p = mi.traverse(mesh)
    p["vertex_positions"] = mi.Float(v.astype(np.float32).ravel())
    p["faces"] = mi.UInt32(f.astype(np.uint32).ravel())
    if lit:
        p["vertex_normals"] = mi.Float(vertex_normals(v, f).ravel())
    p.update()
    if per_vertex:
        mesh.add_attribute("vertex_color", 3, np.ascontiguousarray(rgba[:, :3], np.float32).ravel())
    return mesh


def to_mitsuba_dict(scene, t: float | None = None, *, spp: int = 16, variant: str | None = None) -> dict:
    """The Mitsuba 3 scene dictionary of ``scene`` at shutter time ``t`` in [0, 1] (default the
    scene's reference time), for ``mitsuba.load_dict`` (module docs). ``spp``: the sampler's
    samples per pixel; ``variant``: the Mitsuba variant to set (default: keep the one set, else
    the reference's). Raises TypeError / ValueError naming the argument."""
    if not isinstance(scene, Scene):
        raise TypeError(f"scene: expected a motionblur.Scene, got {type(scene).__name__}")
    t = scene.reference_t if t is None else as_float(t, "t")
    if not 0.0 <= t <= 1.0:
        raise ValueError(f"t: must be in the shutter interval [0, 1], got {t}")
    spp = as_int(spp, "spp", minimum=1)
    mi = _mi(variant)
    all_flat = all(o.shading == "flat" for o in scene.objects)
    d: dict = {"type": "scene"}
    d["integrator"] = {"type": "path", "max_depth": 1} if all_flat else {"type": "direct"}
    for k, o in enumerate(scene.objects):
        d[f"obj{k}"] = _mesh(mi, k, o, t)
    for i, light in enumerate(scene.lights):
        d[f"light{i}"] = {
            "type": "directional",
            "direction": [float(x) for x in light.direction],
            "irradiance": {"type": "rgb", "value": [float(x) * np.pi for x in light.intensity]},
        }
    d["sensor"] = sensor_dict(mi, scene.camera, scene.camera_pose_at(t), spp)
    return d
