"""Scenes in motion: Motion, Object, DirectionalLight, Scene and the shutter filters.

Time is normalised: the shutter opens at t = 0 and closes at t = 1. A [`Motion`][motionblur.scene.Motion] is
keyframes over that interval, either rigid transforms (K,4,4) interpolated with lerp for the
translation, slerp for the rotation and linear interpolation of a positive uniform scale, or
vertex positions (K,V,3) of a deforming mesh interpolated linearly. Before the first keyframe
and after the last one the motion holds still.

A [`Scene`][motionblur.scene.Scene] holds objects, a camera (whose pose may move with ``camera_motion``), lights
and a shutter filter: ``"box"`` (uniform), ``"ramp"`` (weight 2t, rising to the close, the
motion-volume paper's), ``"triangle"`` (peak at 0.5), ``"gaussian"`` (centred at 0.5, sigma
1/6, truncated to [0, 1]) or a (M,) array of non-negative weights for M equal strata of the
shutter. These are the same filters as the motion volume's (``src/volume/filter.rs``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from . import _core
from ._validate import as_array, as_choice, as_colors, as_coords, as_float, as_list, as_rgb, with_alpha
from .geometry import Mesh, as_mesh
from .raster import Camera, unit_vector

__all__ = [
    "Motion",
    "Object",
    "DirectionalLight",
    "Scene",
    "SHUTTER_FILTERS",
    "Trapezoid",
    "shutter_cdf",
    "translate",
    "rotate",
]

#: The directions a rolling shutter reads its rows in (``Scene(rolling_direction=...)``).
ROLLING_DIRECTIONS = ("top_to_bottom", "bottom_to_top")

#: The shutter filters' names (the motion volume's filters, defined by the compiled core).
SHUTTER_FILTERS: tuple[str, ...] = tuple(_core.FILTERS)


def translate(offset) -> np.ndarray:
    """(4,4) float64 translation by ``offset`` (3,)."""
    m = np.eye(4)
    m[:3, 3] = as_coords(offset, "offset", (3,))
    return m


def rotate(angle: float, axis=(0.0, 0.0, 1.0), center=(0.0, 0.0, 0.0)) -> np.ndarray:
    """(4,4) float64 rotation by ``angle`` radians (right hand) about ``axis`` (3,) through ``center`` (3,)."""
    a = as_array(axis, "axis", np.float64, (3,))
    if not np.abs(a).max() > 0:
        raise ValueError("axis: must not be zero")
    if not 1e-150 < np.abs(a).max() < 1e150:  # only the direction counts: keep its length finite
        a = a / np.abs(a).max()
    c = as_coords(center, "center", (3,))
    return _core._rotate(as_float(angle, "angle"), a, c)


# ---------------------------------------------------------------- motion


def _rebuild_motion(times, transforms, vertices) -> Motion:
    if vertices is not None:
        return Motion.deforming(times, vertices)
    return Motion(times, transforms)


class Motion:
    """Keyframed motion over the shutter [0, 1].

    ``Motion(times, transforms)``: rigid keyframes, ``times`` (K,) float strictly increasing in
    [0, 1], ``transforms`` (K,4,4) float (row-major, acting on column vectors: ``p' = M @ [p, 1]``),
    each a rotation times a positive uniform scale plus a translation. Between keyframes the
    translation is lerped, the rotation slerped (shorter arc) and the scale lerped; before the first
    and after the last keyframe the transform holds. Use [`deforming`][motionblur.scene.Motion.deforming] for vertex keyframes.

    The keyframes are validated and split into translation, rotation and scale once, by the
    compiled core's keyframe engine (``src/motion/``), which also samples them.

    Raises ValueError for wrong shapes, NaN, unsorted or out-of-range times, K < 1,
    non-rigid matrices (shear, non-uniform scale, mirrors), scales outside [1/MAX_COORD,
    MAX_COORD] (1e-9 to 1e9: scaled coordinates stay in the coordinate range and the scale is
    split off through the determinant) and translations beyond ``+-MAX_COORD``. The inputs
    are copied.
    """

    def __init__(self, times, transforms):
        t = as_array(times, "times", np.float64, (None,), finite=False)
        m = as_array(transforms, "transforms", np.float64, (None, 4, 4), finite=False)
        self._keys = _core._Keyframes(t, m, None)  # validates times, count and every matrix
        self.times = t.view()  # read-only below; t may be the caller's own array
        self.transforms = m.copy()
        self.vertices = None
        for a in (self.times, self.transforms):
            a.flags.writeable = False

    @classmethod
    def linear(cls, start, end) -> Motion:
        """Two keyframes at t = 0 and t = 1. ``start`` and ``end``: (4,4) transforms or (3,) translations."""

        def mat(x, name):
            if np.shape(x) == (3,):
                return translate(as_coords(x, name, (3,)))
            return as_array(x, name, np.float64, (4, 4))

        return cls([0.0, 1.0], np.stack([mat(start, "start"), mat(end, "end")]))

    @classmethod
    def deforming(cls, times, vertices) -> Motion:
        """Vertex keyframes: ``times`` (K,) strictly increasing in [0, 1], ``vertices`` (K,V,3)
        float world positions (the object's mesh gives the faces, with V vertices). Positions are
        interpolated linearly between keyframes and held outside them."""
        t = as_array(times, "times", np.float64, (None,), finite=False)
        v = as_array(vertices, "vertices", np.float64, (None, None, 3), finite=False)
        self = cls.__new__(cls)
        self._keys = _core._Keyframes(t, None, v)  # validates times, count and values
        self.times = t.view()
        self.vertices = v.copy()
        self.transforms = None
        for a in (self.times, self.vertices):
            a.flags.writeable = False
        return self

    @property
    def is_deforming(self) -> bool:
        """True for vertex keyframes ([`deforming`][motionblur.scene.Motion.deforming]), False for rigid ones."""
        return self.vertices is not None

    @property
    def is_static(self) -> bool:
        """True when every keyframe is equal (no motion at all)."""
        k = self.vertices if self.is_deforming else self.transforms
        return bool((k == k[0]).all())

    def transform_at(self, t: float) -> np.ndarray:
        """(4,4) float64 rigid transform at shutter time ``t`` (identity for deforming motion)."""
        return self._keys.transform_at(as_float(t, "t"))

    def transforms_at(self, times) -> np.ndarray:
        """(N,4,4) float64 rigid transforms at the shutter times ``times`` (N,) (identities for
        deforming motion); each equals [`transform_at`][motionblur.scene.Motion.transform_at] of its time."""
        return self._keys.transforms_at(as_array(times, "times", np.float64, (None,), allow_empty=True))

    def vertices_at(self, t: float) -> np.ndarray:
        """(V,3) float64 positions at ``t`` of a deforming motion (linear between keyframes)."""
        if not self.is_deforming:
            raise ValueError("motion: vertices_at needs a deforming motion (Motion.deforming)")
        return self._keys.vertices_at(as_float(t, "t"))

    def __reduce__(self):
        return _rebuild_motion, (self.times, self.transforms, self.vertices)

    def __repr__(self) -> str:
        kind = "deforming" if self.is_deforming else "rigid"
        return f"Motion({kind}, {len(self.times)} keyframes)"


# ---------------------------------------------------------------- objects and lights


def _as_scene_mesh(mesh) -> Mesh:
    # C-contiguous copies: geometry.Mesh passes a matching ndarray on without making it contiguous.
    if isinstance(mesh, tuple) and len(mesh) == 2:
        return Mesh(np.ascontiguousarray(mesh[0]), np.ascontiguousarray(mesh[1]))
    if isinstance(mesh, Mesh):
        return mesh
    if hasattr(mesh, "vertices") and hasattr(mesh, "faces"):
        return Mesh(np.ascontiguousarray(mesh.vertices), np.ascontiguousarray(mesh.faces))
    return as_mesh(mesh)


class Object:
    """A mesh in the scene.

    ``mesh``: [`Mesh`][motionblur.scene.Mesh], a trimesh-like object or a ``(vertices, faces)`` tuple, in object
    space. ``color``: linear straight RGB(A), one (3,)/(4,) or per vertex (V,3)/(V,4), RGB >= 0 and
    alpha in [0, 1]. ``shading``: ``"flat"`` (unlit colour) or ``"lambert"`` (lights + ambient).
    ``motion``: None (static), a rigid [`Motion`][motionblur.scene.Motion] (placing the mesh's vertices in the world)
    or a deforming one (world positions, V must match). ``name``: a label.
    """

    def __init__(self, mesh, color=(1.0, 1.0, 1.0), shading: str = "flat", motion=None, name=None):
        self.mesh = _as_scene_mesh(mesh)
        nv = len(self.mesh.vertices)
        self.color = as_colors(color, "color", nv)
        self.shading = as_choice(shading, "shading", _core.SHADINGS)
        if motion is not None and not isinstance(motion, Motion):
            raise TypeError(f"motion: expected a motionblur.Motion or None, got {type(motion).__name__}")
        if motion is not None and motion.is_deforming and motion.vertices.shape[1] != nv:
            raise ValueError(
                f"motion: deforming keyframes have {motion.vertices.shape[1]} vertices, the mesh {nv}"
            )
        self.motion = motion
        self.name = None if name is None else str(name)

    @property
    def is_moving(self) -> bool:
        """True when the object has a motion whose keyframes differ."""
        return self.motion is not None and not self.motion.is_static

    @property
    def is_transparent(self) -> bool:
        """True when some part of the object has alpha under 1 (its surfaces must be sorted with
        the others' to be composited exactly)."""
        return float(np.min(self.rgba[..., 3])) < 1.0

    @property
    def rgba(self) -> np.ndarray:
        """(4,) or (V,4) float32 straight RGBA."""
        c = self.color
        return c if c.shape[-1] == 4 else with_alpha(c).reshape(*c.shape[:-1], 4)

    def transform_at(self, t: float) -> np.ndarray:
        """(4,4) rigid placement at ``t`` (identity for static and deforming objects)."""
        if self.motion is None:
            return np.eye(4)
        return self.motion.transform_at(t)

    def world_vertices(self, t: float) -> np.ndarray:
        """(V,3) float64 world positions at shutter time ``t`` (rigid, deforming or static)."""
        if self.motion is None:
            return np.array(self.mesh.vertices, dtype=np.float64)
        if self.motion.is_deforming:
            return self.motion.vertices_at(t)
        m = self.motion.transform_at(t)
        return self.mesh.vertices @ m[:3, :3].T + m[:3, 3]

    def __repr__(self) -> str:
        return f"Object({self.name or ''!s}, {len(self.mesh)} faces, {self.shading}, moving={self.is_moving})"


class DirectionalLight:
    """A light at infinity: ``direction`` (3,) the way the light travels (normalised here),
    ``intensity`` float or RGB (3,) >= 0 (irradiance on a surface facing it, linear)."""

    def __init__(self, direction, intensity=1.0) -> None:
        self.direction = unit_vector(direction, "direction")
        self.intensity = as_rgb(intensity, "intensity")

    def __repr__(self) -> str:
        return f"DirectionalLight(direction={self.direction.round(3).tolist()}, intensity={self.intensity.tolist()})"


# ---------------------------------------------------------------- shutter filters


@dataclass(frozen=True)
class Trapezoid:
    """A trapezoid shutter curve, as a mechanical shutter opens and closes (RenderMan's and
    Cycles' curves of this shape): for ``Scene(shutter=Trapezoid(open, close))``, the weight
    rises linearly over the first ``open`` of the shutter, holds, and falls linearly over the
    last ``close`` (fractions of the shutter, each >= 0, ``open + close <= 1``; (0, 0) is the
    box). Like every filter it weighs time within the exposure: the frame is the weighted
    average, as bright as a box shutter's. Honoured by accumulation, the analytic method,
    ``auto`` and the blur shell; the image-space methods (box only) and the motion volume (named
    filters only) refuse it."""

    open: float = 0.1
    close: float = 0.1

    def __post_init__(self) -> None:
        o, c = as_float(self.open, "open"), as_float(self.close, "close")
        if not (o >= 0.0 and c >= 0.0 and o + c <= 1.0):
            raise ValueError(f"open, close: ramps must be >= 0 with open + close <= 1, got {o} and {c}")
        object.__setattr__(self, "open", o)  # stored as floats (frozen: set once, here)
        object.__setattr__(self, "close", c)

    def cdf(self, t: np.ndarray) -> np.ndarray:
        """W(t) at ``t`` (clipped to [0, 1]): the weight of [0, t]."""
        o, c = self.open, self.close
        h = 1.0 / (1.0 - 0.5 * (o + c))
        t = np.clip(np.asarray(t, np.float64), 0.0, 1.0)
        rise = 0.5 * h * t * t / o if o > 0 else np.zeros_like(t)
        flat = h * (0.5 * o + (t - o))
        left = 1.0 - t
        fall = 1.0 - 0.5 * h * left * left / c if c > 0 else np.ones_like(t)
        return np.where(t < o, rise, np.where(t <= 1.0 - c, flat, fall))


def shutter_cdf(shutter, t) -> np.ndarray:
    """Cumulative shutter weight W(t) (W(0) = 0, W(1) = 1) of a filter name, (M,) weights or a
    [`Trapezoid`][motionblur.scene.Trapezoid], at ``t``."""
    t = np.clip(as_array(t, "t", np.float64, (None,) * np.ndim(t), allow_empty=True), 0.0, 1.0)
    if isinstance(shutter, Trapezoid):
        return shutter.cdf(t)
    if isinstance(shutter, str):
        if shutter == "box":
            return t.copy()
        if shutter == "ramp":
            return t * t
        if shutter == "triangle":
            return np.where(t <= 0.5, 2 * t * t, 1 - 2 * (1 - t) ** 2)
        if shutter == "gaussian":
            erf = np.vectorize(math.erf)
            phi = lambda x: 0.5 * (1 + erf(x / math.sqrt(2)))  # noqa: E731
            lo, hi = phi(-3.0), phi(3.0)
            return (phi((t - 0.5) * 6.0) - lo) / (hi - lo)
        raise ValueError(f"shutter: unknown filter {shutter!r}; expected one of {', '.join(SHUTTER_FILTERS)}")
    w = _check_shutter(shutter)
    cum = np.concatenate([[0.0], np.cumsum(w) / w.sum()])
    return np.interp(t, np.linspace(0.0, 1.0, len(w) + 1), cum)


def _check_shutter(shutter):
    if isinstance(shutter, Trapezoid):
        return shutter
    if isinstance(shutter, str):
        return as_choice(shutter, "shutter", SHUTTER_FILTERS)
    w = as_array(shutter, "shutter", np.float64, (None,))
    if (w < 0).any() or not w.sum() > 0:
        raise ValueError("shutter: weights must be >= 0 with a positive sum")
    w = w.copy()
    w.flags.writeable = False
    return w


class Scene:
    """Objects, a camera, lights and a shutter.

    ``objects``: sequence of [`Object`][motionblur.scene.Object]. ``camera``: a [`motionblur.Camera`][motionblur.Camera] (its pose
    is the pose at every time unless ``camera_motion`` is given). ``lights``: sequence of
    [`DirectionalLight`][motionblur.scene.DirectionalLight]. ``camera_motion``: None or a rigid [`Motion`][motionblur.scene.Motion] without scale
    that moves the camera as an object's motion moves its mesh: ``pose(t) = M(t) @ camera.pose``.
    ``shutter``: a filter name (``box``, ``ramp``, ``triangle``, ``gaussian``) or (M,) weights
    for M equal strata of [0, 1]. ``background``: straight RGBA (4,) behind everything (the
    methods composite the frame over it; (0,0,0,0) leaves it transparent). ``reference_time``:
    ``"close"`` (t = 1, as the motion-volume paper), ``"center"`` (0.5), ``"open"`` (0) or a
    float in [0, 1]: the instant of the sharp geometry and of the camera that motion-volume style
    methods render with. ``ambient``: float or RGB ambient light of lambert shading.

    ``rolling``: a rolling shutter's readout ``R`` in [0, 1) (0, the default: a global shutter).
    The scene's time [0, 1] then spans the whole capture and pixel row ``y`` (0 at the top) of
    an image ``H`` rows high is exposed over ``[o, o + 1 - R]``, ``o = R * y / H`` with
    ``rolling_direction="top_to_bottom"`` (the default) or ``o = R * (H - 1 - y) / H`` with
    ``"bottom_to_top"``; every sample of a pixel uses its pixel's row, and the shutter filter
    applies within each row's window, rescaled to it. ``analytic`` models it exactly,
    ``accumulation`` per row (converging to it) and ``auto`` renders the analytic frame;
    [`render`][motionblur.render.render] refuses it for the other methods (`ROLLING_METHODS`).
    """

    def __init__(
        self,
        objects,
        camera,
        lights=(),
        camera_motion=None,
        shutter="box",
        background=(0.0, 0.0, 0.0, 0.0),
        reference_time="close",
        ambient=0.0,
        rolling=0.0,
        rolling_direction="top_to_bottom",
    ) -> None:
        objects = as_list(objects, "objects", Object, "motionblur.Object")
        if not isinstance(camera, Camera):
            raise TypeError(f"camera: expected a motionblur.Camera, got {type(camera).__name__}")
        lights = as_list(
            () if lights is None else lights, "lights", DirectionalLight, "motionblur.DirectionalLight"
        )
        if camera_motion is not None:
            if not isinstance(camera_motion, Motion):
                raise TypeError(
                    f"camera_motion: expected a motionblur.Motion, got {type(camera_motion).__name__}"
                )
            if camera_motion.is_deforming:
                raise ValueError("camera_motion: must be rigid, not deforming")
            if np.abs(camera_motion._keys.scales() - 1.0).max() > 1e-9:
                raise ValueError("camera_motion: must not scale (rotation and translation only)")
        self.objects = objects
        self.camera = camera
        self.lights = lights
        self.camera_motion = camera_motion
        self.shutter = _check_shutter(shutter)
        bg = as_array(background, "background", np.float64, (4,))
        if (bg < 0).any() or bg[3] > 1:
            raise ValueError("background: RGB must be >= 0 and alpha in [0, 1]")
        self.background = bg
        if isinstance(reference_time, str):
            named = {"close": 1.0, "center": 0.5, "centre": 0.5, "open": 0.0}
            if reference_time not in named:
                raise ValueError(
                    f"reference_time: expected 'close', 'center', 'open' or a float, got {reference_time!r}"
                )
            self.reference_t = named[reference_time]
        else:
            rt = as_float(reference_time, "reference_time")
            if not 0.0 <= rt <= 1.0:
                raise ValueError(f"reference_time: must be in [0, 1], got {rt}")
            self.reference_t = rt
        self.reference_time = reference_time
        self.ambient = as_rgb(ambient, "ambient")
        r = as_float(rolling, "rolling")
        if not 0.0 <= r < 1.0:  # NaN fails too
            raise ValueError(f"rolling: the readout must be in [0, 1), got {r}")
        self.rolling = r
        self.rolling_direction = as_choice(rolling_direction, "rolling_direction", ROLLING_DIRECTIONS)

    @property
    def camera_moves(self) -> bool:
        return self.camera_motion is not None and not self.camera_motion.is_static

    @property
    def moving_objects(self) -> list[Object]:
        return [o for o in self.objects if o.is_moving]

    @property
    def static_objects(self) -> list[Object]:
        return [o for o in self.objects if not o.is_moving]

    def camera_pose_at(self, t: float) -> np.ndarray:
        """(4,4) camera-to-world pose at shutter time ``t``."""
        if self.camera_motion is None:
            return np.array(self.camera.pose)
        return self.camera_motion.transform_at(t) @ self.camera.pose

    def camera_poses_at(self, times) -> np.ndarray:
        """(N,4,4) camera-to-world poses at the shutter times ``times`` (N,), each equal to
        [`camera_pose_at`][motionblur.scene.Scene.camera_pose_at] of its time."""
        times = as_array(times, "times", np.float64, (None,))
        if self.camera_motion is None:
            return np.repeat(np.array(self.camera.pose)[None], len(times), axis=0)
        return self.camera_motion.transforms_at(times) @ self.camera.pose

    def camera_at(self, t: float) -> Camera:
        """The [`Camera`][motionblur.scene.Camera] at shutter time ``t`` (same intrinsics, moved pose)."""
        if self.camera_motion is None:
            return self.camera
        c = self.camera
        return Camera(self.camera_pose_at(t), c.yfov, c.width, c.height, znear=c.znear, zfar=c.zfar)

    def shutter_cdf(self, t) -> np.ndarray:
        """Cumulative shutter weight W(t) at ``t`` (scalar or array), W(0) = 0, W(1) = 1."""
        return shutter_cdf(self.shutter, t)

    def shutter_weights(self, times) -> np.ndarray:
        """(N,) float64 weights summing to 1 for the sample ``times`` (N,) (strictly increasing in
        [0, 1]): each time stands for the part of the shutter nearest to it (the cells between the
        midpoints of neighbouring times), weighted by the shutter filter's integral over it. For
        stratified times ``(i + 0.5) / N`` the cells are the strata."""
        t = as_array(times, "times", np.float64, (None,), finite=False)
        _core._check_times(t)
        edges = np.concatenate([[0.0], 0.5 * (t[1:] + t[:-1]), [1.0]])
        w = np.diff(self.shutter_cdf(edges))
        total = w.sum()
        if not total > 0:  # every sample in a zero-weight part of the shutter
            raise ValueError("times: the shutter filter gives these times zero total weight")
        return w / total

    def with_(self, **changes) -> Scene:
        """A copy of the scene with some constructor arguments changed."""
        args = dict(
            objects=self.objects,
            camera=self.camera,
            lights=self.lights,
            camera_motion=self.camera_motion,
            shutter=self.shutter,
            background=self.background,
            reference_time=self.reference_time,
            ambient=self.ambient,
            rolling=self.rolling,
            rolling_direction=self.rolling_direction,
        )
        args.update(changes)
        return Scene(**args)

    @classmethod
    def from_trimesh(
        cls, scene, camera=None, *, width: int = 640, height: int = 480, shading: str = "flat", **options
    ) -> Scene:
        """A still scene from a ``trimesh.Scene`` (or ``Trimesh``): every mesh placed by the graph,
        with its colours, named after its node; ``camera`` None: the scene's own, else one framing
        it (``width`` x ``height``). ``options`` go to [`Scene`][motionblur.scene.Scene]. Needs ``motionblur[interop]``;
        details in [`motionblur.interop.trimesh`][motionblur.interop.trimesh]."""
        from .interop.trimesh import read_trimesh

        parts, cam = read_trimesh(scene, camera, width=width, height=height)
        objects = [Object((p.vertices, p.faces), p.color, shading=shading, name=p.name) for p in parts]
        return cls(objects, cam, **options)

    @classmethod
    def from_gltf(
        cls,
        path,
        *,
        shutter=None,
        animation=0,
        camera=None,
        width: int = 640,
        height: int = 480,
        shading: str = "flat",
        resample: int = 0,
        **options,
    ) -> Scene:
        """A scene in motion from a glTF 2.0 file (``.gltf``, embedded or ``.glb``): meshes placed
        by the node hierarchy, moved by one ``animation``'s TRS keyframes, morph targets and skins;
        the shutter [0, 1] spans ``shutter = (start, end)`` seconds of it (default: all of it).
        ``camera`` None: the file's first camera, else one framing the scene; ``resample`` N adds
        N + 1 evenly spaced keyframes. ``options`` go to [`Scene`][motionblur.scene.Scene]. Needs
        ``motionblur[interop]``; details and limits in [`motionblur.interop.gltf`][motionblur.interop.gltf]."""
        from .interop.gltf import read_gltf

        parts, cam, cam_keys = read_gltf(
            path,
            shutter=shutter,
            animation=animation,
            camera=camera,
            width=width,
            height=height,
            resample=resample,
        )
        objects = []
        for p in parts:
            motion = None
            if p.transforms is not None:
                motion = Motion(p.times, p.transforms)
            elif p.positions is not None:
                motion = Motion.deforming(p.times, p.positions)
            objects.append(
                Object((p.vertices, p.faces), p.color, shading=shading, motion=motion, name=p.name)
            )
        camera_motion = None if cam_keys is None else Motion(*cam_keys)
        return cls(objects, cam, camera_motion=camera_motion, **options)

    def __repr__(self) -> str:
        return (
            f"Scene({len(self.objects)} objects ({len(self.moving_objects)} moving), {len(self.lights)} lights, "
            f"camera_moves={self.camera_moves}, shutter={self.shutter if isinstance(self.shutter, (str, Trapezoid)) else 'weights'})"
        )
