"""References: the same [`Scene`][motionblur.Scene] rendered by Mitsuba 3 and by pyrender.

``mitsuba(scene, times=K, spp=S, seed=0)``: Mitsuba 3.9 has no shape that moves with the ray
time, so the reference is K renders at accumulation's stratified shutter times (the box's
``(i + 0.5) / K``; under another filter the times cut its weight into K equal strata), each
weighing 1/K (`motionblur.methods.accumulation.sample_times`), summed. The conversion:

- meshes from numpy (``mi.Mesh`` filled through ``mi.traverse``); a moving lambert object is a
  shape group instanced with ``to_world`` = its rigid transform at the sample time; flat objects
  (emitters, which Mitsuba cannot instance) and deforming ones get their world vertex positions
  written at each time;
- the camera: ``to_world = pose @ diag(-1, 1, -1, 1)``, ``fov_axis='y'``, near/far clip; a moving
  camera's ``to_world`` is updated per time; a box pixel filter and an rgba film;
- ``flat`` shading: an area emitter of the object's colour on a black BSDF, seen directly
  (``path`` integrator, ``max_depth=1``); ``lambert``: a diffuse BSDF of the object's colour under
  directional emitters of irradiance ``pi * intensity`` (Mitsuba's diffuse BSDF is
  ``albedo / pi``), ``direct`` integrator. A scene with both is rendered in two passes (flat
  emitters with lambert objects black, then the lit pass with flat objects black) and summed, so
  flat objects never light lambert ones. Mitsuba casts shadows, the rasterizer does not: the
  built-in lit scenes have nothing that could shadow.

The variant is ``llvm_ad_rgb`` when libLLVM 19 is installed (``DRJIT_LIBLLVM_PATH``, or Debian's
path; the environment is never written: where Dr.Jit cannot find LLVM a RuntimeError says to set
the variable), ``scalar_rgb`` otherwise. Long runs show
a tqdm progress bar.

``pyrender(scene, t=None, samples=1)``: pyrender (OSMesa, ``RenderFlags.FLAT``) at one time, or
the mean of ``samples`` poses over the shutter (the 16-pose accumulation peer of the benchmark).

``blender(scene, samples=S)``: Blender Cycles (CPU) with its own motion blur, no shadows
([`motionblur.evaluation.blender`][motionblur.evaluation.blender]).
"""

from __future__ import annotations

import os
import time

import numpy as np

from .._optional import require, require_osmesa_pyopengl
from .._validate import as_int
from ..interop.mitsuba import OPENGL_TO_MITSUBA, mitsuba_variant, sensor_dict, set_variant, vertex_normals
from ..methods.accumulation import sample_times
from ..raster import Frame, over_background
from ..scene import Scene
from .blender import blender

__all__ = ["mitsuba", "pyrender", "blender", "mitsuba_variant"]

_FLIP = OPENGL_TO_MITSUBA


def _mi(variant=None):
    variant = variant or mitsuba_variant()
    return set_variant(require("mitsuba"), variant)


def _check_colours(scene: Scene):
    for k, o in enumerate(scene.objects):
        if o.shading == "lambert" and o.is_transparent:
            raise ValueError(
                f"scene: object {k}: the Mitsuba reference takes transparent objects with flat "
                "shading only (its direct integrator stops at the first surface); use alpha 1 or "
                "shading='flat'"
            )
    if scene.ambient.any() and any(o.shading == "lambert" for o in scene.objects):
        raise ValueError(
            "scene: the Mitsuba reference has no ambient light; use ambient=0 with lambert objects"
        )


def _colour(o, scale: float = 1.0) -> dict:
    """The object's colour as a Mitsuba texture: one RGB, or the per-vertex ``vertex_color``
    mesh attribute (interpolated over each triangle as the rasterizer does)."""
    if o.rgba.ndim == 2:
        return {"type": "mesh_attribute", "name": "vertex_color", "scale": scale}
    return {"type": "rgb", "value": [float(x) * scale for x in o.rgba[:3]]}


def _front_faces(v: np.ndarray, f: np.ndarray, eye: np.ndarray) -> np.ndarray:
    """(F,3) uint32 faces with those facing away from ``eye`` made degenerate (the rasterizer
    culls back faces, and a transparent object's must not hide what is behind it)."""
    a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    facing = (np.cross(b - a, c - a) * (eye - a)).sum(axis=1) > 0
    out = np.where(facing[:, None], f, f[:, :1]).astype(np.uint32)
    return np.ascontiguousarray(out)


class _MitsubaScene:
    """A Mitsuba scene built once for ``pass_`` ('flat', 'lambert' or 'all') and posed per time."""

    def __init__(self, mi, scene: Scene, pass_: str, spp: int, lens=None):
        self.mi, self.scene = mi, scene
        cam = scene.camera
        d = {"type": "scene"}
        coverage = pass_ == "coverage"
        layers = sum(o.is_transparent for o in scene.objects)
        if pass_ in ("flat", "coverage"):
            # a transparent surface is a null interaction: each one seen through costs a bounce
            d["integrator"] = {"type": "path", "max_depth": 1 + 2 * layers}
        elif layers:
            d["integrator"] = {"type": "path", "max_depth": 2 + 2 * layers}
        else:
            d["integrator"] = {"type": "direct", "emitter_samples": 1, "bsdf_samples": 0}
        self.moving: list[tuple[str, object, str]] = []  # (key, object, 'vertices' | 'instance')
        self.clear: list[tuple[str, object]] = []  # transparent objects: back faces dropped per time
        self.backdrop = layers > 0 and pass_ in ("flat", "coverage")
        for k, o in enumerate(scene.objects):
            emits = o.shading == "flat" and pass_ in ("flat", "all")
            lit = o.shading == "lambert" and pass_ in ("lambert", "all")
            if coverage:
                emits = lit = False
            clear = o.is_transparent
            # alpha as opacity: a mask of that opacity over the BSDF; a transparent emitter
            # radiates alpha times its colour (premultiplied, as the rasterizer composites it);
            # the coverage pass makes every object emit its alpha
            alpha = {"type": "rgb", "value": [float(np.min(o.rgba[..., 3]))] * 3}
            if o.rgba.ndim == 2:
                alpha = {"type": "mesh_attribute", "name": "vertex_alpha"}
            bsdf = {
                "type": "diffuse",
                "reflectance": _colour(o) if lit else {"type": "rgb", "value": [0.0] * 3},
            }
            if clear:
                bsdf = {"type": "mask", "opacity": alpha, "bsdf": bsdf}
            props = mi.Properties()
            props["bsdf"] = mi.load_dict(bsdf)
            if coverage:
                props["emitter"] = mi.load_dict({"type": "area", "radiance": alpha})
            elif emits:
                radiance = _colour(o, float(np.min(o.rgba[..., 3])) if o.rgba.ndim == 1 else 1.0)
                if o.rgba.ndim == 2 and clear:
                    radiance = {"type": "mesh_attribute", "name": "vertex_premultiplied"}
                props["emitter"] = mi.load_dict({"type": "area", "radiance": radiance})
            v, f = o.mesh.vertices, o.mesh.faces
            mesh = mi.Mesh(f"obj{k}", len(v), len(f), props, has_vertex_normals=o.shading == "lambert")
            p = mi.traverse(mesh)
            instanced = o.is_moving and not o.motion.is_deforming and not emits and not clear and not coverage
            v0 = v if instanced else o.world_vertices(scene.reference_t)
            p["vertex_positions"] = mi.Float(np.asarray(v0, np.float32).ravel())
            p["faces"] = mi.UInt32(np.asarray(f, np.uint32).ravel())
            if o.shading == "lambert":
                p["vertex_normals"] = mi.Float(vertex_normals(v0, f).ravel())
            p.update()
            if o.rgba.ndim == 2:
                rgba = np.asarray(o.rgba, np.float32)
                mesh.add_attribute("vertex_color", 3, np.ascontiguousarray(rgba[:, :3]).ravel())
                mesh.add_attribute("vertex_alpha", 1, np.ascontiguousarray(rgba[:, 3]).ravel())
                premultiplied = np.ascontiguousarray(rgba[:, :3] * rgba[:, 3:4])
                mesh.add_attribute("vertex_premultiplied", 3, premultiplied.ravel())
            if clear:
                self.clear.append((f"obj{k}", o))
            if instanced:
                d[f"group{k}"] = {"type": "shapegroup", f"obj{k}": mesh}
                d[f"obj{k}"] = {"type": "instance", "shapegroup": {"type": "ref", "id": f"group{k}"}}
                self.moving.append((f"obj{k}", o, "instance"))
            else:
                d[f"obj{k}"] = mesh
                if o.is_moving:
                    self.moving.append((f"obj{k}", o, "vertices"))
        if pass_ in ("lambert", "all"):
            for i, light in enumerate(scene.lights):
                d[f"light{i}"] = {
                    "type": "directional",
                    "direction": [float(x) for x in light.direction],
                    "irradiance": {"type": "rgb", "value": [float(x) * np.pi for x in light.intensity]},
                }
        if self.backdrop:
            # Mitsuba's film zeroes the colour of a ray that leaves through transparent surfaces
            # only (its alpha is 0): a black opaque backdrop behind everything keeps every ray,
            # and the coverage pass gives the alpha
            d["backdrop"] = {
                "type": "rectangle",
                "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.0] * 3}},
            }
            self._backdrop_scale = _backdrop_distance(scene)
        d["sensor"] = sensor_dict(mi, cam, scene.camera_pose_at(scene.reference_t), spp, lens)
        self.mi_scene = mi.load_dict(d)
        self.params = mi.traverse(self.mi_scene)

    def pose(self, t: float) -> None:
        mi, p = self.mi, self.params
        for key, o, how in self.moving:
            if how == "instance":
                p[f"{key}.to_world"] = mi.Transform4f(o.transform_at(t))
            else:
                v = o.world_vertices(t)
                p[f"{key}.vertex_positions"] = mi.Float(np.asarray(v, np.float32).ravel())
                if o.shading == "lambert":
                    p[f"{key}.vertex_normals"] = mi.Float(vertex_normals(v, o.mesh.faces).ravel())
        if self.scene.camera_motion is not None:
            p["sensor.to_world"] = mi.Transform4f(self.scene.camera_pose_at(t) @ _FLIP)
        pose = self.scene.camera_pose_at(t)
        for key, o in self.clear:
            v = o.world_vertices(t)
            p[f"{key}.vertex_positions"] = mi.Float(np.asarray(v, np.float32).ravel())
            p[f"{key}.faces"] = mi.UInt32(_front_faces(v, np.asarray(o.mesh.faces), pose[:3, 3]).ravel())
        if self.backdrop:
            dist = self._backdrop_scale
            cam = self.scene.camera
            half = dist * np.tan(cam.yfov / 2) * 2.0 * max(1.0, cam.width / cam.height)
            place = pose @ np.diag([half, half, 1.0, 1.0])
            place[:3, 3] = pose[:3, 3] - dist * pose[:3, 2]
            p["backdrop.to_world"] = mi.Transform4f(place @ _FLIP)
        p.update()

    def render(self, spp: int, seed: int) -> np.ndarray:
        return np.array(self.mi.render(self.mi_scene, spp=spp, seed=seed), dtype=np.float64)


def mitsuba(
    scene: Scene,
    times: int = 16,
    spp: int = 16,
    seed: int = 0,
    variant: str | None = None,
    progress=None,
    aperture: float | None = None,
    focus_distance: float | None = None,
) -> Frame:
    """The Mitsuba 3 time-sampled reference of ``scene``.

    ``times`` K >= 1 renders at accumulation's stratified shutter times (``(i + 0.5) / K`` under
    the box; equal strata of the filter's weight under another), 1/K each; ``spp`` S >= 1 samples per pixel each (independent sampler, seed
    ``seed * K + i``; the same seed gives the same image); ``variant`` overrides the Mitsuba
    variant; ``progress`` True/False forces the tqdm bar (default: when K * S * pixels is large).

    ``aperture`` and ``focus_distance`` (scene units, both or neither): Mitsuba's ``thinlens``
    sensor of that lens radius focused on the plane at that distance along the view axis (the
    depth-of-field reference of ``render(..., aperture=, focus_distance=)``).

    Per-vertex colours are a ``vertex_color`` mesh attribute (interpolated over each triangle
    as the rasterizer does). Transparent objects (alpha < 1, flat shading) are a ``mask`` of
    their alpha over the BSDF and radiate alpha times their colour, seen through with the
    ``path`` integrator, their back faces dropped at each time as the rasterizer culls them; a
    black backdrop behind everything keeps Mitsuba's film from zeroing the colour of rays that
    leave through them, and a coverage pass (every object radiating its alpha) gives the alpha.

    Returns a Frame: ``rgba`` (H,W,4) float32 premultiplied linear RGBA composited over the scene
    background; ``depth`` (inf) and ``ids`` (-1) are not computed; ``stats`` has ``times``, ``spp``,
    ``variant`` and ``ms``. Transparent lambert objects and ambient light raise ValueError
    (Mitsuba's direct integrator has no twin of them).
    """
    if not isinstance(scene, Scene):
        raise TypeError(f"scene: expected a motionblur.Scene, got {type(scene).__name__}")
    k = as_int(times, "times", minimum=1, maximum=1 << 16)
    spp = as_int(spp, "spp", minimum=1, maximum=1 << 20)
    seed = as_int(seed, "seed", minimum=0)
    _check_colours(scene)
    lens = _lens(aperture, focus_distance)
    t0 = time.perf_counter()
    mi = _mi(variant)
    shadings = {o.shading for o in scene.objects}
    passes = (
        ["flat", "lambert"]
        if len(shadings) == 2 and scene.lights
        else (["flat"] if shadings <= {"flat"} else ["lambert"])
    )
    if shadings == {"flat", "lambert"} and not scene.lights:
        passes = ["flat"]
    if any(o.is_transparent for o in scene.objects):
        passes.append("coverage")
    ts, ws = sample_times(scene, k, "stratified")
    cam = scene.camera
    if progress is None:
        progress = k * spp * cam.width * cam.height * len(passes) > 2e7
    # the plain text bar: tqdm.auto would look for ipywidgets in a notebook and warn without them
    tqdm = require("tqdm", "the progress bar of the Mitsuba reference").tqdm
    bar = tqdm(total=k * len(passes), desc="mitsuba reference", disable=not progress, leave=False)
    acc = np.zeros((cam.height, cam.width, 4))
    coverage = np.zeros((cam.height, cam.width))
    for pass_ in passes:
        ms = _MitsubaScene(mi, scene, pass_, spp, lens)
        for i, (t, w) in enumerate(zip(ts, ws)):
            ms.pose(t)
            img = ms.render(spp, seed * k + i)
            if pass_ == "coverage":
                coverage += w * img[..., 0]
                bar.update()
                continue
            if pass_ != passes[0]:
                img[..., 3] = 0.0  # the coverage is counted once
            acc += w * img
            bar.update()
    bar.close()
    if "coverage" in passes:
        acc[..., 3] = coverage
    rgba = acc.astype(np.float32)
    h, w_ = rgba.shape[:2]
    frame = Frame(
        rgba, np.full((h, w_), np.inf, np.float32), np.full((h, w_), -1, np.int32), np.zeros((h, w_, 2))
    )
    frame = over_background(frame, scene.background)
    frame.stats.update(
        times=k, spp=spp, variant=mi.variant(), passes=passes, ms=(time.perf_counter() - t0) * 1e3
    )
    return frame


def _lens(aperture, focus_distance):
    if aperture is None and focus_distance is None:
        return None
    if aperture is None or focus_distance is None:
        missing = "aperture" if aperture is None else "focus_distance"
        raise ValueError(f"{missing}: the thin lens needs both aperture and focus_distance")
    a, f = float(aperture), float(focus_distance)
    for name, v in (("aperture", a), ("focus_distance", f)):
        if not (np.isfinite(v) and v > 0):
            raise ValueError(f"{name}: must be finite and > 0 (scene units), got {v}")
    return a, f


def _backdrop_distance(scene: Scene) -> float:
    """A distance from the camera beyond every object at every time (the backdrop's)."""
    far = 1.0
    for t in (0.0, 0.5, 1.0):
        eye = scene.camera_pose_at(t)[:3, 3]
        for o in scene.objects:
            far = max(far, float(np.linalg.norm(o.world_vertices(t) - eye, axis=1).max()))
    return 4.0 * far


_renderers: dict = {}


def _require_gl_platform() -> None:
    """Refuse to start pyrender where it has no way to open a GL context: no
    ``PYOPENGL_PLATFORM`` (``osmesa`` or ``egl`` render offscreen) and no display. The process
    environment is read, never written (PyOpenGL reads the variable once, when OpenGL is first
    imported, so it must be set before that)."""
    if os.environ.get("PYOPENGL_PLATFORM") or os.environ.get("DISPLAY"):
        return
    raise RuntimeError(
        "reference.pyrender: no GL platform: set PYOPENGL_PLATFORM=osmesa (or egl) in the "
        "environment before Python imports OpenGL, or run with a display"
    )


def _pyrender_mesh(trimesh, obj, vertices):
    """The trimesh pyrender draws of ``obj`` at ``vertices`` (V,3): with its colours as vertex
    colours where it has one a vertex (pyrender keeps 8 bits of each; alpha 1, as the one colour
    of an object is drawn opaque)."""
    colours = None
    if obj.rgba.ndim == 2:
        colours = np.round(np.clip(np.asarray(obj.rgba, np.float64), 0.0, 1.0) * 255.0).astype(np.uint8)
        colours[:, 3] = 255
    return trimesh.Trimesh(
        np.asarray(vertices), np.asarray(obj.mesh.faces), vertex_colors=colours, process=False
    )


def pyrender(scene: Scene, t: float | None = None, samples: int = 1) -> Frame:
    """pyrender (offscreen OSMesa, ``RenderFlags.FLAT``: unlit base colour) of ``scene``.

    Needs ``PYOPENGL_PLATFORM=osmesa`` (or ``egl``) in the environment, or a display: without
    either, RuntimeError says so (the environment is never written here).

    ``t``: one shutter time (default the reference time) when ``samples`` is 1; otherwise the
    weighted mean of ``samples`` renders at the stratified shutter times (the classic
    accumulation buffer on an OpenGL peer, every object drawn at every pose). Lambert objects are
    drawn flat too (pyrender's lighting is not lambert); colours a vertex are drawn as pyrender's
    vertex colours (8 bits). Returns a Frame whose rgba is pyrender's
    RGB (over black) with alpha = coverage (depth > 0), averaged; depth is pyrender's of the last
    render (inf for background).
    """
    if not isinstance(scene, Scene):
        raise TypeError(f"scene: expected a motionblur.Scene, got {type(scene).__name__}")
    _require_gl_platform()
    require_osmesa_pyopengl()
    pr = require("pyrender")
    trimesh = require("trimesh", "the pyrender peer")

    samples = as_int(samples, "samples", minimum=1, maximum=1 << 16)
    t0 = time.perf_counter()
    cam = scene.camera
    key = (cam.width, cam.height)
    if key not in _renderers:
        _renderers[key] = pr.OffscreenRenderer(cam.width, cam.height)
    r = _renderers[key]
    sc = pr.Scene(bg_color=[0.0, 0.0, 0.0, 0.0], ambient_light=[0.0, 0.0, 0.0])
    nodes = []
    for o in scene.objects:
        # pyrender reads a mesh's vertex colours only without a material (it makes its own)
        mat = None
        if o.rgba.ndim == 1:
            mat = pr.MetallicRoughnessMaterial(baseColorFactor=[float(x) for x in o.rgba], alphaMode="OPAQUE")
        deforming = o.motion is not None and o.motion.is_deforming
        base = o.world_vertices(0.0) if deforming else o.mesh.vertices
        tm = _pyrender_mesh(trimesh, o, base)
        node = sc.add(pr.Mesh.from_trimesh(tm, material=mat, smooth=False))
        nodes.append((o, node, deforming, mat))
    camera_node = sc.add(cam.to_pyrender())
    if samples == 1:
        ts, ws = np.array([scene.reference_t if t is None else float(t)]), np.ones(1)
    else:
        ts, ws = sample_times(scene, samples, "stratified")
    acc = np.zeros((cam.height, cam.width, 4))
    depth = None
    for ti, wi in zip(ts, ws):
        for o, node, deforming, mat in nodes:
            if deforming:
                tm = _pyrender_mesh(trimesh, o, o.world_vertices(ti))
                node.mesh = pr.Mesh.from_trimesh(tm, material=mat, smooth=False)
            else:
                sc.set_pose(node, o.transform_at(ti))
        sc.set_pose(camera_node, scene.camera_pose_at(ti))
        colour, depth = r.render(sc, flags=pr.RenderFlags.FLAT)
        acc[..., :3] += wi * (colour.astype(np.float64) / 255.0)
        acc[..., 3] += wi * (depth > 0)
    h, w = acc.shape[:2]
    d = np.where(depth > 0, depth, np.inf).astype(np.float32)
    frame = Frame(acc.astype(np.float32), d, np.where(depth > 0, 0, -1).astype(np.int32), np.zeros((h, w, 2)))
    frame = over_background(frame, scene.background)
    frame.stats.update(samples=samples, ms=(time.perf_counter() - t0) * 1e3)
    return frame
