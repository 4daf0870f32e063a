"""The same [`Scene`][motionblur.Scene] rendered by Blender Cycles (CPU) with its motion blur.

``blender(scene, samples=S, seed=0)`` builds a fresh Blender scene through ``bpy`` (Blender as a
Python module, the ``blender`` extra) and renders one frame whose shutter spans the scene's
shutter [0, 1]. Cycles is the path tracer behind Kubric and BlenderProc; this is how such
datasets get their motion-blurred ground truth. The conversion:

- axes: Blender is Z-up, so every world matrix (object placement, camera pose) is
  ``A @ M`` with ``A`` taking our (x, y, z) to Blender's (x, -z, y); meshes keep their object
  space vertices;
- time: the shutter curve is Blender's default (flat), the ``box`` filter; other shutter filters
  raise ValueError. Cycles turns the curve into a 256-entry inverse-CDF table whose entries
  run from 0.0019 to 0.9941 of the shutter, so its rays sample that part only (a box 0.8 %
  shorter and 0.2 % early). The conversion compensates: Blender's shutter is
  ``1 / (0.9941 - 0.0019)`` frames centred on frame 1, and scene time ``t`` is placed where the
  rays' times land, ``[0, 1]`` exactly;
- rigid motion: Cycles samples an object's (and the camera's) transform at ``2**s + 1`` evenly
  spaced motion steps (``cycles.motion_steps = s``) and interpolates between them as this
  package does (translation and scale lerped, rotation slerped). Keys (LINEAR) are inserted at
  every step with the exact transform of its scene time, the first and last segment extended
  past [0, 1] for the steps outside it. ``s`` = 1 for motions of two keyframes (exact); 6 (65
  steps, 1/64 apart) when a keyframe lies inside the shutter, which Cycles then rounds to the
  step grid. Deforming motion (Cycles would need shape keys) raises ValueError;
- camera: ``sensor_fit='VERTICAL'`` and the lens of the camera's ``yfov``; near clip ``znear``
  (a plane, as Cycles clips along the view axis), far clip ``zfar`` (at most 1e6);
- film: ``film_transparent`` (alpha = coverage), box pixel filter of width 1 (the pixel's
  square; ``aa=n`` gives the exact method's n x n point samples instead), adaptive sampling and
  denoising off, a fixed
  ``seed``, the view transform ``Standard`` (the EXR keeps linear values);
- colours: ``flat`` objects are an Emission shader of their colour (strength 1) and reflect
  nothing, so they look as the rasterizer draws them; ``lambert`` objects a Diffuse BSDF of their
  colour (``albedo / pi``) with their area-weighted vertex normals as custom normals, under Sun
  lamps of angle 0 and strength ``pi * intensity`` along each light's direction; ``ambient`` is a
  uniform world of that radiance (hidden from the camera by the transparent film). Per-vertex
  colours are a colour attribute; alpha < 1 mixes in a Transparent BSDF; back faces are
  transparent (the rasterizer culls them);
- light transport: ``max_bounces = 0`` (direct light only: no light from one object reaches
  another), and every object's ``visible_shadow`` ray visibility is off, so **nothing casts a
  shadow** — Cycles does ray-trace shadows by default, but per-object shadow visibility turns it
  off, and then a lambert surface gets ``albedo * (ambient + sum intensity * max(0, n . l))``,
  the rasterizer's shading. What still differs: Cycles interpolates the shading normal and
  renormalises it per sample (as the rasterizer), its triangles are the same, but its pixel is
  sampled at random positions and times (noise) where the exact method integrates.

The result is a [`Frame`][motionblur.Frame] (``rgba`` premultiplied linear, over the scene
background) whose ``stats`` hold ``samples``, ``seed``, ``motion_steps``, ``ms`` (the whole
call: scene build, sync, render, read-back) and ``ms_render`` (``bpy.ops.render.render`` alone).
"""

from __future__ import annotations

import contextlib
import os
import sys
import tempfile
import threading
import time

import numpy as np

from .._optional import require
from .._validate import as_int
from ..interop.mitsuba import vertex_normals
from ..methods._layers import downsample
from ..raster import Frame, over_background
from ..scene import Scene, Trapezoid

__all__ = ["blender", "motion_steps", "TO_BLENDER", "MAX_MOTION_STEPS"]

#: our world (Y-up) to Blender's (Z-up): (x, y, z) -> (x, -z, y)
TO_BLENDER = np.array([[1.0, 0, 0, 0], [0, 0, -1.0, 0], [0, 1.0, 0, 0], [0, 0, 0, 1.0]])

#: the ``cycles.motion_steps`` used for motions with keyframes inside the shutter (``2**6 + 1`` =
#: 65 transform samples, 1/64 frame apart; Blender merges keyframes closer than 0.01 frame, so
#: its largest setting, 7, would lose half of them)
MAX_MOTION_STEPS = 6

#: Cycles' SHUTTER_TABLE_SIZE (``intern/cycles/scene/tables.h``)
_SHUTTER_TABLE_SIZE = 256

# bpy holds one Blender session per process: one render at a time
_LOCK = threading.Lock()


@contextlib.contextmanager
def _quiet(fd: int, keep_on_error: bool = False):
    """Send the C-level output of file descriptor ``fd`` to a temporary file (Blender prints its
    render progress to stdout, and bpy's import an audio notice and a NumPy ABI notice); with
    ``keep_on_error``, write it back when the block raises."""
    sys.stdout.flush()
    sys.stderr.flush()
    saved = os.dup(fd)
    with tempfile.TemporaryFile() as sink:
        os.dup2(sink.fileno(), fd)
        try:
            yield
        except BaseException:
            os.dup2(saved, fd)
            if keep_on_error:
                sink.seek(0)
                os.write(fd, sink.read())
            raise
        finally:
            os.dup2(saved, fd)
            os.close(saved)


def _bpy():
    if sys.modules.get("bpy") is not None:
        return sys.modules["bpy"]
    with _quiet(1, keep_on_error=True), _quiet(2, keep_on_error=True):
        return require("bpy")


def motion_steps(scene: Scene) -> int:
    """The ``cycles.motion_steps`` s of the conversion: 1 (3 transform samples, exact for motions
    of two keyframes, which extend linearly past the shutter) when no motion of the scene has a
    keyframe inside (0, 1), else `MAX_MOTION_STEPS` (65 samples: Cycles interpolates
    between them, so a keyframe inside the shutter is rounded within 1/64 of it).
    Raises ValueError for deforming motion (Cycles would need shape keys)."""
    motions = [(f"objects[{k}]", o.motion) for k, o in enumerate(scene.objects) if o.is_moving]
    if scene.camera_moves:
        motions.append(("camera_motion", scene.camera_motion))
    inner = False
    for name, m in motions:
        if m.is_deforming:
            raise ValueError(
                f"scene: {name} is deforming (vertex keyframes); the Blender reference converts rigid "
                "motion only (Cycles would need shape keys)"
            )
        inner = inner or bool(((m.times > 0.0) & (m.times < 1.0)).any())
    return MAX_MOTION_STEPS if inner else 1


def _shutter_table_range() -> tuple[float, float]:
    """The shutter times [a, b] (fractions of Blender's shutter) where Cycles' rays land with the
    flat shutter curve: its inverse-CDF table of 256 entries holds ``(i + 0.5) / 256 * 255 / 256``
    (``util_cdf_inverted``), read with linear interpolation."""
    n = _SHUTTER_TABLE_SIZE
    return 0.5 / n * (n - 1) / n, (n - 0.5) / n * (n - 1) / n


def _timing(steps: int) -> tuple[float, np.ndarray, np.ndarray]:
    """Blender's shutter in frames, and the frames and scene times of the ``2**steps + 1`` motion
    steps, such that the shutter time Cycles' rays take, [a, b] of its shutter, is the scene's
    [0, 1]: frame ``offset + t`` holds scene time t, rendered at frame 1."""
    a, b = _shutter_table_range()
    shutter = 1.0 / (b - a)
    offset = 1.0 - shutter / 2.0 + a * shutter
    u = np.linspace(0.0, 1.0, (1 << steps) + 1)
    frames = 1.0 - shutter / 2.0 + u * shutter
    return shutter, frames, frames - offset


def _check(scene: Scene) -> None:
    if not isinstance(scene, Scene):
        raise TypeError(f"scene: expected a motionblur.Scene, got {type(scene).__name__}")
    if not (isinstance(scene.shutter, str) and scene.shutter == "box"):
        name = (
            scene.shutter
            if isinstance(scene.shutter, str)
            else (repr(scene.shutter) if isinstance(scene.shutter, Trapezoid) else "custom weights")
        )
        raise ValueError(
            f"scene: shutter {name!r}: the Blender reference renders the box shutter only (its shutter "
            "curve is sampled into a table, not the exact filter); use shutter='box'"
        )


def _matrix(m: np.ndarray):
    from mathutils import Matrix  # noqa: PLC0415 (bpy's module, importable once bpy is)

    return Matrix([list(map(float, row)) for row in TO_BLENDER @ m])


def _pose_at(motion, base: np.ndarray, t: float) -> np.ndarray:
    """(4,4) ``motion(t) @ base`` for any t: inside [0, 1] the motion's own transform; before 0
    (after 1), when a keyframe sits at 0 (1), its first (last) segment extended (translation and
    scale linearly, rotation along the same great circle), as Cycles' interpolation between
    motion steps continues it; otherwise the held transform."""
    times = motion.times
    before, after = t < times[0] <= 0.0, t > times[-1] >= 1.0
    if len(times) < 2 or not (before or after):
        return motion.transform_at(float(np.clip(t, 0.0, 1.0))) @ base
    from mathutils import Matrix  # noqa: PLC0415 (bpy's module, importable once bpy is)

    i = 0 if t < times[0] else len(times) - 2
    t0, t1 = float(times[i]), float(times[i + 1])
    m0 = Matrix([list(map(float, r)) for r in motion.transform_at(t0)])
    m1 = Matrix([list(map(float, r)) for r in motion.transform_at(t1)])
    return np.array(m0.lerp(m1, (t - t0) / (t1 - t0))) @ base


def _key(obj, pose_at, frames, times) -> None:
    """Key ``obj`` (rotation as a quaternion, LINEAR) at every motion-step frame with its pose at
    the scene time of that step."""
    obj.rotation_mode = "QUATERNION"
    prev = None
    for f, t in zip(frames, times):
        obj.matrix_world = _matrix(pose_at(float(t)))
        q = obj.rotation_quaternion.copy()
        if prev is not None and prev.dot(q) < 0:  # keep the quaternions on one side (shorter arc)
            q.negate()
            obj.rotation_quaternion = q
        prev = q
        for path in ("location", "rotation_quaternion", "scale"):
            obj.keyframe_insert(path, frame=float(f))
    for curve in obj.animation_data.action.fcurves if obj.animation_data else ():
        for point in curve.keyframe_points:
            point.interpolation = "LINEAR"


def _material(bpy, o, k: int):
    mat = bpy.data.materials.new(f"mat{k}")
    mat.use_nodes = True
    mat.cycles.emission_sampling = "NONE"  # a flat object is no light for lambert ones
    nodes, links = mat.node_tree.nodes, mat.node_tree.links
    nodes.clear()
    out = nodes.new("ShaderNodeOutputMaterial")
    if o.shading == "flat":
        surf = nodes.new("ShaderNodeEmission")
        surf.inputs["Strength"].default_value = 1.0
    else:
        surf = nodes.new("ShaderNodeBsdfDiffuse")
        surf.inputs["Roughness"].default_value = 0.0
    colour_in = surf.inputs["Color"]
    alpha_src = None
    if o.rgba.ndim == 2:
        attr = nodes.new("ShaderNodeAttribute")
        attr.attribute_name = "colour"
        links.new(attr.outputs["Color"], colour_in)
        alpha_src = attr.outputs["Alpha"] if float(o.rgba[:, 3].min()) < 1.0 else None
    else:
        colour_in.default_value = [float(x) for x in o.rgba[:3]] + [1.0]
    shader = surf.outputs[0]
    opaque = alpha_src is None and float(np.min(o.rgba[..., 3])) >= 1.0
    if not opaque:
        mix = nodes.new("ShaderNodeMixShader")
        clear = nodes.new("ShaderNodeBsdfTransparent")
        if alpha_src is not None:
            links.new(alpha_src, mix.inputs["Fac"])
        else:
            mix.inputs["Fac"].default_value = float(o.rgba[3])
        links.new(clear.outputs[0], mix.inputs[1])
        links.new(shader, mix.inputs[2])
        shader = mix.outputs[0]
    # back faces are not drawn (the rasterizer culls them): a transparent BSDF there
    geo = nodes.new("ShaderNodeNewGeometry")
    cull = nodes.new("ShaderNodeMixShader")
    back = nodes.new("ShaderNodeBsdfTransparent")
    links.new(geo.outputs["Backfacing"], cull.inputs["Fac"])
    links.new(shader, cull.inputs[1])
    links.new(back.outputs[0], cull.inputs[2])
    links.new(cull.outputs[0], out.inputs["Surface"])
    return mat


def _mesh_object(bpy, o, k: int):
    v = np.asarray(o.mesh.vertices, np.float64)
    f = np.asarray(o.mesh.faces, np.int64)
    me = bpy.data.meshes.new(f"mesh{k}")
    me.from_pydata(v.tolist(), [], f.tolist())
    if o.shading == "lambert":
        me.shade_smooth()
        me.normals_split_custom_set_from_vertices(vertex_normals(v, f).astype(np.float64).tolist())
    if o.rgba.ndim == 2:
        attr = me.color_attributes.new("colour", "FLOAT_COLOR", "POINT")
        attr.data.foreach_set("color", np.asarray(o.rgba, np.float32).ravel())
    me.materials.append(_material(bpy, o, k))
    ob = bpy.data.objects.new(f"obj{k}", me)
    # direct light only and no shadows: as the rasterizer shades
    ob.visible_shadow = False
    ob.visible_diffuse = ob.visible_glossy = ob.visible_transmission = False
    ob.visible_volume_scatter = False
    return ob


def _sun(bpy, light, i: int):
    intensity = np.asarray(light.intensity, np.float64)
    peak = float(intensity.max())
    lamp = bpy.data.lights.new(f"sun{i}", "SUN")
    lamp.energy = float(np.pi * peak)
    lamp.color = (intensity / peak).tolist() if peak > 0 else [1.0, 1.0, 1.0]
    lamp.angle = 0.0
    ob = bpy.data.objects.new(f"sun{i}", lamp)
    # the lamp's -Z is the direction the light travels
    z = -np.asarray(light.direction, np.float64)
    helper = np.array([1.0, 0.0, 0.0]) if abs(z[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = np.cross(helper, z)
    x /= np.linalg.norm(x)
    m = np.eye(4)
    m[:3, 0], m[:3, 1], m[:3, 2] = x, np.cross(z, x), z
    ob.matrix_world = _matrix(m)
    return ob


def _settings(bpy, scene: Scene, samples: int, seed: int, threads, sub: int, point: bool):
    sc = bpy.context.scene
    cam = scene.camera
    r = sc.render
    r.engine = "CYCLES"
    r.resolution_x, r.resolution_y, r.resolution_percentage = cam.width * sub, cam.height * sub, 100
    r.pixel_aspect_x = r.pixel_aspect_y = 1.0
    r.film_transparent = True
    r.use_motion_blur = True
    r.motion_blur_position = "CENTER"
    r.use_persistent_data = False
    if threads is not None:
        r.threads_mode, r.threads = "FIXED", threads
    r.image_settings.file_format = "OPEN_EXR"
    r.image_settings.color_mode = "RGBA"
    r.image_settings.color_depth = "32"
    r.image_settings.exr_codec = "NONE"
    sc.view_settings.view_transform = "Standard"
    sc.view_settings.look = "None"
    sc.view_settings.exposure = 0.0
    sc.view_settings.gamma = 1.0
    c = sc.cycles
    c.device = "CPU"
    c.samples = samples
    c.use_adaptive_sampling = False
    c.use_denoising = False
    c.seed, c.use_animated_seed = seed, False
    # Blender hands Cycles a box filter of width 1 whatever filter_width says; the narrowest
    # Gaussian (width 0.01: samples within 0.015 of the centre) stands for point samples
    c.pixel_filter_type = "GAUSSIAN" if point else "BOX"
    c.filter_width = 0.01 if point else 1.0
    c.max_bounces = c.diffuse_bounces = c.glossy_bounces = 0
    c.transmission_bounces = c.volume_bounces = 0
    c.transparent_max_bounces = 64
    c.sample_clamp_direct = c.sample_clamp_indirect = 0.0
    c.film_exposure = 1.0
    sc.frame_start = sc.frame_end = 1
    sc.frame_set(1)
    sc.world = bpy.data.worlds.new("world")
    sc.world.use_nodes = True
    bg = sc.world.node_tree.nodes["Background"]
    amb = np.asarray(scene.ambient, np.float64)
    uses_ambient = any(o.shading == "lambert" for o in scene.objects) and amb.any()
    bg.inputs["Color"].default_value = (amb.tolist() if uses_ambient else [0.0] * 3) + [1.0]
    bg.inputs["Strength"].default_value = 1.0 if uses_ambient else 0.0


def _camera(bpy, scene: Scene, steps: int):
    cam = scene.camera
    data = bpy.data.cameras.new("camera")
    data.sensor_fit = "VERTICAL"
    data.sensor_height = 24.0
    data.lens = 12.0 / float(np.tan(cam.yfov / 2.0))
    data.clip_start = float(cam.znear)
    data.clip_end = float(min(cam.zfar, 1e6))
    ob = bpy.data.objects.new("camera", data)
    ob.cycles.motion_steps = steps
    return ob


def _read_exr(bpy, path: str, h: int, w: int) -> np.ndarray:
    img = bpy.data.images.load(path)
    try:
        px = np.empty(h * w * 4, np.float32)
        img.pixels.foreach_get(px)
    finally:
        bpy.data.images.remove(img)
    return px.reshape(h, w, 4)[::-1].astype(np.float32)  # rows bottom-up


def _render(scene: Scene, samples: int, seed: int, threads, sub: int, aa, steps: int):
    """(rgba (H,W,4) float32 at the camera's size, render milliseconds, Blender's version) of
    ``scene`` built afresh in bpy's session, ``samples`` per (sub-)pixel."""
    bpy = _bpy()
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.context.preferences.edit.keyframe_new_interpolation_type = "LINEAR"
    _settings(bpy, scene, samples, seed, threads, sub, point=aa is not None)
    sc = bpy.context.scene
    shutter, frames, times = _timing(steps)
    sc.render.motion_blur_shutter = shutter
    for k, o in enumerate(scene.objects):
        ob = _mesh_object(bpy, o, k)
        sc.collection.objects.link(ob)
        ob.cycles.motion_steps = steps
        if o.is_moving:
            _key(ob, lambda t, o=o: _pose_at(o.motion, np.eye(4), t), frames, times)
        else:
            ob.matrix_world = _matrix(o.transform_at(0.0))
    for i, light in enumerate(scene.lights):
        if any(o.shading == "lambert" for o in scene.objects):
            sc.collection.objects.link(_sun(bpy, light, i))
    cam_ob = _camera(bpy, scene, steps)
    sc.collection.objects.link(cam_ob)
    sc.camera = cam_ob
    if scene.camera_moves:
        pose = np.asarray(scene.camera.pose)
        _key(cam_ob, lambda t: _pose_at(scene.camera_motion, pose, t), frames, times)
    else:
        cam_ob.matrix_world = _matrix(scene.camera_pose_at(0.0))
    sc.frame_set(1)
    cam = scene.camera
    with tempfile.TemporaryDirectory(prefix="motionblur-blender-") as tmp:
        path = os.path.join(tmp, "frame.exr")
        sc.render.filepath = path
        t1 = time.perf_counter()
        with _quiet(1):
            bpy.ops.render.render(write_still=True)
        ms_render = (time.perf_counter() - t1) * 1e3
        rgba = downsample(_read_exr(bpy, path, cam.height * sub, cam.width * sub), sub)
    return rgba, ms_render, bpy.app.version_string


def blender(
    scene: Scene, samples: int = 256, seed: int = 0, threads: int | None = None, aa: int | None = None
) -> Frame:
    """Blender Cycles (CPU) render of ``scene`` with its motion blur over the whole shutter.

    ``samples`` S >= 1 samples per pixel (each at a random position in the pixel's square and a
    random shutter time; no adaptive sampling, no denoising), ``seed`` the Cycles seed (the same
    seed gives the same image), ``threads`` the render threads (default: all cores).

    ``aa`` None (default): Cycles' box pixel filter of width 1, each sample at a random position
    in the pixel's square (the pixel's area integral, as datasets render). ``aa`` = n (1, 2 or
    4): the spatial samples of ``motionblur.exact(scene, aa=n)`` instead: Cycles renders n times
    the width and height with its narrowest pixel filter (a Gaussian of width 0.01 sub-pixel:
    every sample within 0.015 of the sub-pixel's centre; Blender gives Cycles' box filter width
    1 whatever is set) and ``samples / n**2`` samples each (``samples`` must be a multiple of
    ``n**2``), and the n x n blocks are averaged: Cycles and the exact method then estimate the
    same image, and their difference is Cycles' noise.

    Returns a Frame: ``rgba`` (H,W,4) float32 premultiplied linear RGBA (alpha = coverage)
    composited over the scene background; ``depth`` (inf) and ``ids`` (-1) are not computed;
    ``stats`` has ``samples``, ``seed``, ``motion_steps``, ``blender`` (its version), ``ms`` and
    ``ms_render``. Nothing casts shadows and light does not bounce (see the module docstring),
    so flat and lambert shading match the rasterizer's. Raises ValueError for a shutter other
    than ``box`` and for deforming motion;
    [`MissingDependencyError`][motionblur.MissingDependencyError] when ``bpy`` is not installed (the ``blender``
    extra, Python 3.11 only).
    """
    _check(scene)
    samples = as_int(samples, "samples", minimum=1, maximum=1 << 24)
    seed = as_int(seed, "seed", minimum=0, maximum=(1 << 31) - 1)
    if threads is not None:
        threads = as_int(threads, "threads", minimum=1, maximum=1024)
    sub = 1 if aa is None else as_int(aa, "aa")
    if sub not in (1, 2, 4):
        raise ValueError(f"aa: must be None, 1, 2 or 4, got {aa}")
    if samples % (sub * sub):
        raise ValueError(f"samples: must be a multiple of aa**2 = {sub * sub} with aa={aa}, got {samples}")
    steps = motion_steps(scene)
    t0 = time.perf_counter()
    with _LOCK:
        rgba, ms_render, version = _render(scene, samples // (sub * sub), seed, threads, sub, aa, steps)
    h, w = rgba.shape[:2]
    frame = Frame(
        rgba, np.full((h, w), np.inf, np.float32), np.full((h, w), -1, np.int32), np.zeros((h, w, 2))
    )
    frame = over_background(frame, scene.background)
    frame.stats.update(
        samples=samples,
        aa=aa,
        seed=seed,
        motion_steps=steps,
        blender=version,
        ms=(time.perf_counter() - t0) * 1e3,
        ms_render=ms_render,
    )
    return frame
