"""The CPU software rasterizer: Camera, Draw, rasterize, Frame.

Conventions (OpenGL / pyrender): the camera pose is camera-to-world, the camera looks down its -Z
with +Y up, ``yfov`` is the vertical field of view in radians and pixel centres sit at +0.5.
Faces are counter-clockwise seen from the front. Colours are linear; a Draw takes *straight*
(non-premultiplied) RGBA, a Frame holds *premultiplied* RGBA.

The rasterizer (Rust, parallel over 64x64-sample screen tiles, bit-identical for any thread count):

* clips triangles against the near and far planes (and a wide guard band), never dropping or
  wrapping triangles that cross the near plane;
* sets triangles up in 8-bit sub-pixel fixed point with the top-left fill rule, so a shared edge
  is drawn exactly once (no seams, no double blending);
* interpolates colour, alpha, normals and motion perspective-correctly;
* runs an opaque pass with a z-buffer (fragments with alpha == 1), then a transparent pass
  (0 < alpha < 1) whose fragments in front of the opaque surface are composited per sample,
  either in exact depth order (``blend="exact"``, premultiplied *over*, back to front, independent
  of submission order) or in submission order (``blend="unsorted"``, as unsorted z-buffer hardware);
* supersamples ``samples`` x ``samples`` per pixel with a box resolve of the colour. Depth, ids and
  velocity of a pixel come from its nearest sample (the smallest depth), so they always describe
  one real surface.

The frame's depth is the view-axis distance of the nearest surface with alpha > 0 (transparent
surfaces included), ``inf`` for background; ids and velocity belong to that same surface.
"""

from __future__ import annotations

import os
import time
from collections.abc import Sequence
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from . import _core
from ._optional import require
from ._validate import (
    as_array,
    as_bool,
    as_choice,
    as_coords,
    as_faces,
    as_float,
    as_int,
    as_path,
    as_rgb,
    as_rgba,
    as_samples,
    check_coords,
)

__all__ = ["Camera", "Draw", "Frame", "look_at", "rasterize"]

#: Largest image side in pixels, and largest pixel count (the frame takes 32 bytes a pixel);
#: defined by the compiled core.
MAX_SIDE: int = _core.MAX_SIDE
MAX_PIXELS: int = _core.MAX_PIXELS
#: Transparent fragments of one sample composited exactly with ``blend="exact"`` (see
#: [`rasterize`][motionblur.raster.rasterize]).
FRAGMENT_CAP: int = _core.FRAGMENT_CAP
#: The accepted vertical fields of view, radians: ``[MIN_YFOV, pi - MIN_YFOV]``. Below it the
#: projection's scale ``1 / tan(yfov / 2)`` sends points of the coordinate range past float32
#: pixels (velocities become inf); at the largest image side a pixel is then 6e-11 rad.
MIN_YFOV: float = 1e-6


def unit_vector(value, name: str) -> np.ndarray:
    """(3,) float64 ``value`` divided by its length: any finite non-zero vector, however large
    or small its components (it is scaled by its largest component first when they are)."""
    d = as_array(value, name, np.float64, (3,))
    m = float(np.abs(d).max())
    if m == 0.0:
        raise ValueError(f"{name}: must not be zero")
    if not 1e-150 < m < 1e150:
        d = d / m
    return d / np.linalg.norm(d)


def look_at(eye, target, up=(0.0, 1.0, 0.0)) -> np.ndarray:
    """Camera-to-world pose (4,4) float64 at ``eye`` (3,) whose -Z looks at ``target`` (3,), +Y near ``up``.

    ``eye`` and ``target`` lie in the coordinate range (``MAX_COORD``); ``up`` is any finite
    non-zero vector (only its direction counts) not parallel to ``target - eye``: otherwise
    ValueError naming the argument."""
    eye = as_coords(eye, "eye", (3,))
    target = as_coords(target, "target", (3,))
    up = unit_vector(up, "up")
    back = eye - target
    n = np.linalg.norm(back)
    if n == 0.0:
        raise ValueError("target: must differ from eye")
    z = back / n
    x = np.cross(up, z)
    nx = np.linalg.norm(x)
    if not nx >= 1e-12:
        raise ValueError("up: must not be parallel to the view direction")
    x /= nx
    y = np.cross(z, x)
    pose = np.eye(4)
    pose[:3, 0], pose[:3, 1], pose[:3, 2], pose[:3, 3] = x, y, z, eye
    return pose


def _check_size(width, height) -> tuple[int, int]:
    width = as_int(width, "width", minimum=1, maximum=MAX_SIDE)
    height = as_int(height, "height", minimum=1, maximum=MAX_SIDE)
    if width * height > MAX_PIXELS:
        raise ValueError(f"width: width * height must be <= {MAX_PIXELS}, got {width} x {height}")
    return width, height


class Camera:
    """A perspective camera (pyrender's ``PerspectiveCamera`` plus an image size).

    Parameters: ``pose`` (4,4) camera-to-world, its position in the coordinate range
    (``MAX_COORD``); ``yfov`` vertical field of view in radians, in [``MIN_YFOV``, pi -
    ``MIN_YFOV``] (1e-6); ``width``, ``height`` in pixels (1..``MAX_SIDE``, at most ``MAX_PIXELS`` pixels);
    ``znear`` > 0 and ``zfar`` > znear in scene units. The defaults are pyrender's:
    ``znear=0.05`` and ``zfar=inf``, its infinite projection (pyrender's ``zfar=None``), so
    nothing far away is clipped whatever the scene's units. [`from_pyrender`][motionblur.raster.Camera.from_pyrender] converts a
    pyrender camera.

    Attributes: ``pose``, ``yfov``, ``width``, ``height``, ``znear``, ``zfar``, ``aspect``
    (width / height), ``view`` (4,4) float64 world-to-camera, ``projection`` (4,4) float64 equal
    to ``pyrender.PerspectiveCamera(yfov, znear, zfar, aspectRatio=width/height)
    .get_projection_matrix(width, height)``, ``view_projection`` = projection @ view.
    """

    def __init__(
        self,
        pose: ArrayLike,
        yfov: float,
        width: int,
        height: int,
        znear: float = 0.05,
        zfar: float = float("inf"),
    ) -> None:
        pose = as_array(pose, "pose", np.float64, (4, 4)).copy()
        check_coords(pose[:3, 3], "pose")
        yfov = as_float(yfov, "yfov")
        if not MIN_YFOV <= yfov <= np.pi - MIN_YFOV:
            raise ValueError(f"yfov: must be in [{MIN_YFOV:g}, pi - {MIN_YFOV:g}] radians, got {yfov:g}")
        width, height = _check_size(width, height)
        znear = as_float(znear, "znear")
        if znear <= 0.0:
            raise ValueError(f"znear: must be > 0, got {znear}")
        zfar = as_float(zfar, "zfar", finite=False)
        if not zfar > znear:
            raise ValueError(f"zfar: must be > znear, got {zfar}")
        if abs(np.linalg.det(pose)) < 1e-12:
            raise ValueError("pose: is singular")
        self.pose, self.yfov, self.znear, self.zfar = pose, yfov, znear, zfar
        self.view = np.linalg.inv(pose)
        self.pose.flags.writeable = False
        self.view.flags.writeable = False
        self._size(width, height)

    def _size(self, width: int, height: int) -> None:
        self.width, self.height = width, height
        self.aspect = float(width) / float(height)
        # pyrender's get_projection_matrix, operation for operation.
        t = np.tan(self.yfov / 2.0)
        p = np.zeros((4, 4))
        p[0][0] = 1.0 / (self.aspect * t)
        p[1][1] = 1.0 / t
        p[3][2] = -1.0
        znear, zfar = self.znear, self.zfar
        if np.isinf(zfar):
            p[2][2] = -1.0
            p[2][3] = -2.0 * znear
        else:
            p[2][2] = (zfar + znear) / (znear - zfar)
            p[2][3] = (2 * zfar * znear) / (znear - zfar)
        self.projection = p
        self.view_projection = p @ self.view
        self.projection.flags.writeable = False
        self.view_projection.flags.writeable = False

    @classmethod
    def from_pyrender(cls, camera, pose, width: int, height: int) -> Camera:
        """The [`Camera`][motionblur.raster.Camera] of a ``pyrender.PerspectiveCamera`` seen from ``pose`` (4,4)
        camera-to-world (its node's pose) rendering ``width`` x ``height`` pixels: the same
        projection matrix as pyrender's (``zfar=None`` there is ``zfar=inf`` here). TypeError for
        other pyrender cameras, ValueError when its ``aspectRatio`` is not ``width / height``
        ([`motionblur.interop.pyrender`][motionblur.interop.pyrender])."""
        from .interop.pyrender import camera_parameters

        return cls(**camera_parameters(camera, pose, width, height))

    def to_pyrender(self) -> Any:
        """The ``pyrender.PerspectiveCamera`` with this camera's projection (``zfar=inf`` becomes
        pyrender's ``None``); put it on a node at ``self.pose``. Needs pyrender."""
        from .interop.pyrender import to_pyrender_camera

        return to_pyrender_camera(self)

    def project(self, points: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """``(pixels, depth)`` of world ``points`` (N,3): ``pixels`` (N,2) float64 image
        coordinates (x right, y down, pixel centres at +0.5, the rasterizer's convention) and
        ``depth`` (N,) float64 distance along the view axis (clip-space w). Points at or behind
        the eye (``depth <= 1e-9``) have no image: their pixels are NaN. The arithmetic is the
        compiled core's, operation for operation, so pixel bounds computed from it match its."""
        p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        vp = self.view_projection
        clip = p @ vp[:3, :3].T + vp[:3, 3]
        depth = p @ vp[3, :3] + vp[3, 3]
        front = depth > 1e-9
        wc = np.where(front, depth, 1.0)
        xy = np.empty((len(p), 2))
        xy[:, 0] = (clip[:, 0] / wc + 1.0) * 0.5 * self.width
        xy[:, 1] = (1.0 - clip[:, 1] / wc) * 0.5 * self.height
        xy[~front] = np.nan
        return xy, depth

    def resized(self, width: int, height: int) -> Camera:
        """The same camera (pose, field of view, clip planes) with an image of ``width`` x
        ``height`` pixels; only the size is checked (the rest was when this camera was made)."""
        width, height = _check_size(width, height)
        c = object.__new__(Camera)
        c.pose, c.yfov, c.znear, c.zfar, c.view = self.pose, self.yfov, self.znear, self.zfar, self.view
        c._size(width, height)
        return c

    def __repr__(self) -> str:
        return (
            f"Camera(yfov={self.yfov:.4g}, width={self.width}, height={self.height}, "
            f"znear={self.znear:g}, zfar={self.zfar:g})"
        )


def _readonly(a: np.ndarray | None) -> np.ndarray | None:
    if a is None:
        return None
    a = a.view()
    a.flags.writeable = False
    return a


class Draw:
    """One mesh to rasterize.

    ``vertices`` (V,3) float world positions; ``faces`` (F,3) int, counter-clockwise is front;
    ``rgba`` straight (non-premultiplied) linear colour: one (3,) or (4,), or per vertex (V,3) or
    (V,4), alpha in [0, 1] (alpha < 1 makes a fragment transparent, alpha 0 invisible);
    ``normals`` (V,3) for lambert shading (None: area-weighted vertex normals of the faces,
    computed when rendering); ``object_id`` int32 written to ``Frame.ids``; ``cull_back`` drops
    back faces; ``previous_vertices`` (V,3) world positions at the previous time, which give the
    velocity buffer (zero without them); ``shading`` "flat" or "lambert" for this mesh when it
    differs from the call's (None: the call's), so that one call sorts the transparent surfaces
    of meshes of both shading modes together.

    The arrays are stored as read-only float64 / int64 / float32 views or copies; the caller's
    arrays are never written.
    """

    def __init__(
        self,
        vertices: ArrayLike,
        faces: ArrayLike,
        rgba: ArrayLike,
        normals: ArrayLike | None = None,
        object_id: int = 0,
        cull_back: bool = True,
        previous_vertices: ArrayLike | None = None,
        shading: str | None = None,
    ) -> None:
        v = as_coords(vertices, "vertices", (None, 3))
        f = as_faces(faces, "faces", len(v))
        c = as_rgba(rgba, "rgba", len(v))
        n = None if normals is None else as_array(normals, "normals", np.float32, (len(v), 3))
        p = (
            None
            if previous_vertices is None
            else as_coords(previous_vertices, "previous_vertices", (len(v), 3))
        )
        self.object_id = as_int(object_id, "object_id", minimum=-(2**31), maximum=2**31 - 1)
        self.cull_back = as_bool(cull_back, "cull_back")
        self.shading = None if shading is None else as_choice(shading, "shading", _core.SHADINGS)
        self.vertices, self.faces, self.rgba = _readonly(v), _readonly(f), _readonly(c)
        self.normals, self.previous_vertices = _readonly(n), _readonly(p)

    @classmethod
    def _checked(cls, vertices, faces, rgba, normals, object_id: int, cull_back: bool) -> Draw:
        """A Draw of arrays the core has just made and checked (a MotionVolume's: float64
        (V,3), int64 (F,3) indices in range, float32 (V,4) straight RGBA in range, float32 (V,3)),
        without checking them again."""
        d = object.__new__(cls)
        d.vertices, d.faces, d.rgba = _readonly(vertices), _readonly(faces), _readonly(rgba)
        d.normals, d.previous_vertices = _readonly(normals), None
        d.object_id, d.cull_back, d.shading = int(object_id), bool(cull_back), None
        return d

    def __repr__(self) -> str:
        return f"Draw({len(self.vertices)} vertices, {len(self.faces)} faces, object_id={self.object_id})"


def _frame_array(value, name: str, dtype, shape) -> np.ndarray:
    """``as_array`` (any values allowed), taking an array that already is a non-empty C-contiguous
    ``dtype`` ndarray of ``shape`` as it is without the general checks (the same result: the
    renderers build every frame from such arrays)."""
    if (
        type(value) is np.ndarray
        and value.dtype == dtype
        and value.flags.c_contiguous
        and value.ndim == len(shape)
        and value.size
        and all(s is None or s == n for s, n in zip(shape, value.shape))
    ):
        return value
    return as_array(value, name, dtype, shape, finite=False)


class Frame:
    """A rendered frame.

    ``rgba`` (H,W,4) float32 premultiplied linear RGBA; ``depth`` (H,W) float32 view-axis
    distance of the nearest surface with alpha > 0, ``inf`` for background; ``ids`` (H,W) int32
    object id of that surface, -1 for background; ``velocity`` (H,W,2) float32 screen motion of
    that surface in pixels (+x right, +y down); ``stats`` dict (triangles, fragments, ms per
    stage). ``coverage`` is the alpha channel (H,W). ``outputs``: the ground-truth channels
    asked of [`render`][motionblur.render.render] with ``outputs=[...]`` (empty otherwise; see
    [`motionblur.ground_truth`][motionblur.ground_truth]), by name.

    Any code may build a Frame from numpy arrays: ``Frame(rgba, depth, ids, velocity, stats=None)``
    (dtypes are converted; the arrays are not copied when they already match). ``velocity=None``
    means no motion: the zeros are made when ``velocity`` is first read (``rasterize`` does so
    when no draw has previous vertices, and writes no velocity buffer).
    """

    rgba: NDArray[np.float32]
    depth: NDArray[np.float32]
    ids: NDArray[np.int32]
    stats: dict[str, Any]
    outputs: dict[str, Any]

    def __init__(
        self,
        rgba: ArrayLike,
        depth: ArrayLike,
        ids: ArrayLike,
        velocity: ArrayLike | None,
        stats: dict[str, Any] | None = None,
    ) -> None:
        rgba = _frame_array(rgba, "rgba", np.float32, (None, None, 4))
        h, w = rgba.shape[:2]
        self.rgba = rgba
        self.depth = _frame_array(depth, "depth", np.float32, (h, w))
        self.ids = _frame_array(ids, "ids", np.int32, (h, w))
        self._velocity: NDArray[np.float32] | None = None
        if velocity is not None:
            self._velocity = _frame_array(velocity, "velocity", np.float32, (h, w, 2))
        self.stats = dict(stats) if stats is not None else {}
        self.outputs = {}

    @property
    def velocity(self) -> NDArray[np.float32]:
        """(H,W,2) float32 screen motion in pixels (zeros made on first read when none was given)."""
        if self._velocity is None:
            self._velocity = np.zeros((self.height, self.width, 2), np.float32)
        return self._velocity

    @velocity.setter
    def velocity(self, value: ArrayLike) -> None:
        self._velocity = _frame_array(value, "velocity", np.float32, (self.height, self.width, 2))

    @property
    def width(self) -> int:
        return int(self.rgba.shape[1])

    @property
    def height(self) -> int:
        return int(self.rgba.shape[0])

    @property
    def coverage(self) -> NDArray[np.float32]:
        """(H,W) float32 alpha: the fraction of the pixel covered (premultiplied alpha)."""
        return self.rgba[..., 3]

    def __repr__(self) -> str:
        return f"Frame({self.width}x{self.height}, stats={self.stats})"

    def _repr_png_(self) -> bytes | None:
        """The frame as PNG bytes (what [`save_png`][motionblur.raster.Frame.save_png] writes), so that Jupyter and IPython
        show a Frame as its picture. None (IPython then shows the repr) when Pillow is missing
        or a pixel is NaN or inf."""
        import io

        try:
            from PIL import Image
        except ImportError:
            return None
        if not np.isfinite(self.rgba).all():
            return None
        buffer = io.BytesIO()
        Image.fromarray(self.to_srgb8(), mode="RGBA").save(buffer, format="PNG")
        return buffer.getvalue()

    def to_srgb8(self) -> np.ndarray:
        """(H,W,4) uint8: straight (un-premultiplied) colour, sRGB-encoded; alpha stays linear."""
        a = np.clip(self.rgba[..., 3:4], 0.0, 1.0)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):  # clipped below
            c = np.where(a > 0, self.rgba[..., :3] / np.maximum(a, 1e-30), 0.0)
        c = np.clip(np.nan_to_num(c), 0.0, 1.0)
        s = np.where(c <= 0.0031308, 12.92 * c, 1.055 * np.power(c, 1.0 / 2.4) - 0.055)
        out = np.concatenate([s, a], axis=-1)
        return np.round(out * 255.0).astype(np.uint8)

    def save_png(self, path: str | os.PathLike[str]) -> None:
        """Writes an 8-bit RGBA PNG (sRGB colour, straight alpha: [`to_srgb8`][motionblur.raster.Frame.to_srgb8], which clips
        colour and alpha to [0, 1]). Creates parent folders. PNG only: ``path`` must end in
        ``.png`` (any case), else ValueError (other formats would drop alpha or palettize
        silently; [`save_exr`][motionblur.raster.Frame.save_exr] keeps every value). ValueError naming ``rgba`` when a pixel
        is NaN or inf (nothing is written)."""
        path = as_path(path)
        if path.suffix.lower() != ".png":
            raise ValueError(
                f"path: save_png writes PNG files only; expected a name ending in .png, got {str(path)!r}"
            )
        if not np.isfinite(self.rgba).all():
            bad = int((~np.isfinite(self.rgba)).any(axis=-1).sum())
            raise ValueError(f"rgba: {bad} pixels are NaN or inf; a PNG cannot hold them (nothing written)")
        image = require("PIL.Image", "Frame.save_png")
        path.parent.mkdir(parents=True, exist_ok=True)
        image.fromarray(self.to_srgb8(), mode="RGBA").save(path, format="PNG")

    def save_exr(self, path: str | os.PathLike[str]) -> Path:
        """Writes an OpenEXR file: linear float ``R``, ``G``, ``B``, ``A`` (premultiplied), depth
        as ``Z``, ids as ``id`` and velocity as ``velocity.X`` / ``velocity.Y``, the stats in the
        header ([`motionblur.interop.exr`][motionblur.interop.exr]), and the ground-truth
        ``outputs`` as named channels (``sharp.<k>.R/G/B/A/Z/id``, ``flow.<k>.X/Y``,
        ``flow_backward.<k>.X/Y``, ``mean_motion.X/Y``, ``exposure.<id>.fraction/first/last``;
        k indexes ``stats["output_times"]``);
        every value round-trips bit-exactly through
        [`motionblur.read_image`][motionblur.read_image]. Creates parent folders; returns the path. EXR only:
        ``path`` must end in ``.exr`` (any case), else ValueError (as [`save_png`][motionblur.raster.Frame.save_png] checks
        ``.png``). Needs the ``OpenEXR`` package (``pip install "motionblur[interop]"``)."""
        from .interop.exr import write_exr

        path = as_path(path)
        if path.suffix.lower() != ".exr":
            raise ValueError(
                f"path: save_exr writes OpenEXR files only; expected a name ending in .exr, got {str(path)!r}"
            )
        extra = _output_channels(self.outputs) if self.outputs else None
        return write_exr(path, self.rgba, self.depth, self.ids, self.velocity, self.stats, extra)


def _output_channels(outputs: dict) -> dict[str, np.ndarray]:
    """Frame ``outputs`` as named (H,W) EXR channels: ``sharp.<k>.R/G/B/A/Z/id``,
    ``flow.<k>.X/Y``, ``flow_backward.<k>.X/Y`` (k the index into ``times``, which the frame's
    stats name), ``mean_motion.X/Y``, and whatever (H,W) planes ``channels`` holds (as read back
    by [`motionblur.read_image`][motionblur.read_image]). Trajectories are metadata, not
    channels (they are in the frame's stats)."""
    ch: dict[str, np.ndarray] = dict(outputs.get("channels", {}))
    for k, f in enumerate(outputs.get("sharp", [])):
        for i, c in enumerate("RGBA"):
            ch[f"sharp.{k}.{c}"] = f.rgba[..., i]
        ch[f"sharp.{k}.Z"] = f.depth
        ch[f"sharp.{k}.id"] = f.ids.view(np.uint32)
    for name in ("flow", "flow_backward"):
        for k, v in enumerate(outputs.get(name, [])):
            ch[f"{name}.{k}.X"], ch[f"{name}.{k}.Y"] = v[..., 0], v[..., 1]
    ex = outputs.get("exposure")
    if ex is not None:
        for j, i in enumerate(ex.ids):
            for name in ("fraction", "first", "last"):
                ch[f"exposure.{int(i)}.{name}"] = getattr(ex, name)[..., j]
    if "mean_motion" in outputs:
        ch["mean_motion.X"], ch["mean_motion.Y"] = (
            outputs["mean_motion"][..., 0],
            outputs["mean_motion"][..., 1],
        )
    return ch


def add_times_color(out: np.ndarray, scale: np.ndarray, color: np.ndarray) -> np.ndarray:
    """``out[..., k] += scale * color[k]`` for each channel k of ``out`` (H,W,C), in place, with
    ``scale`` (H,W) and ``color`` (C,): a channel at a time, as numpy broadcasts over a short last
    axis slowly (0.67 -> 0.08 ms for a 192x110 RGBA window); the same bits as the broadcast."""
    for k in range(out.shape[-1]):
        out[..., k] += scale * color[k]
    return out


def over_background(frame: Frame, background) -> Frame:
    """``frame`` composited over straight RGBA ``background`` (4,) (premultiplied *over*)."""
    bg = np.asarray(background, dtype=np.float32)
    if bg[3] == 0.0 and not bg[:3].any():
        return frame
    pre = np.concatenate([bg[:3] * bg[3], bg[3:]]).astype(np.float32)
    rgba = add_times_color(frame.rgba.copy(), np.float32(1.0) - frame.rgba[..., 3], pre)
    return Frame(rgba, frame.depth, frame.ids, frame.velocity, frame.stats)


def _lights(lights) -> list[tuple[tuple[float, ...], tuple[float, ...]]]:
    if lights is None:
        return []
    if isinstance(lights, (str, bytes)) or not hasattr(lights, "__iter__"):
        raise TypeError(f"lights: expected a sequence of lights, got {type(lights).__name__}")
    out = []
    for i, light in enumerate(lights):
        if hasattr(light, "direction") and hasattr(light, "intensity"):
            d, k = light.direction, light.intensity
        else:
            try:
                d, k = light
            except (TypeError, ValueError) as exc:
                raise TypeError(
                    f"lights: item {i} must have .direction and .intensity or be (direction, intensity)"
                ) from exc
        d = as_array(d, f"lights: item {i} direction", np.float64, (3,))
        m = float(np.abs(d).max())
        if not m > 0:
            raise ValueError(f"lights: item {i} has a zero direction")
        if not 1e-150 < m < 1e150:  # only the direction counts: keep its length finite
            d = d / m
        k = as_rgb(k, f"lights: item {i} intensity")
        out.append((tuple(map(float, d)), tuple(map(float, k))))
    return out


def _background(background, height: int, width: int) -> SimpleNamespace:
    """The ``rgba``, ``depth``, ``ids`` C-contiguous float32 / float32 / int32 arrays (as
    attributes, what the core reads) of a background given as
    an object with ``.rgba``, ``.depth``, ``.ids`` (a Frame) or as such a triple, shapes checked
    against ``height`` x ``width`` samples; new arrays or read-only views, never the caller's
    arrays made writable."""
    if hasattr(background, "rgba") and hasattr(background, "depth") and hasattr(background, "ids"):
        parts = (background.rgba, background.depth, background.ids)
    else:
        try:
            parts = tuple(background)
        except TypeError as exc:
            raise TypeError("background: expected a Frame or an (rgba, depth, ids) triple") from exc
        if len(parts) != 3:
            raise TypeError(f"background: expected an (rgba, depth, ids) triple, got {len(parts)} items")
    rgba = as_array(parts[0], "background rgba", np.float32, (height, width, 4))
    depth = as_array(parts[1], "background depth", np.float32, (height, width), finite=False)
    if not (depth > 0).all():
        bad = depth[~(depth > 0)][0]
        raise ValueError(f"background depth: must be > 0 (inf where empty), got {bad}")
    ids = as_array(parts[2], "background ids", np.int32, (height, width))
    return SimpleNamespace(rgba=_readonly(rgba), depth=_readonly(depth), ids=_readonly(ids))


def rasterize(
    camera: Camera,
    draws: Draw | Sequence[Draw],
    samples: int = 1,
    blend: str = "exact",
    shading: str = "flat",
    lights=(),
    ambient=0.0,
    background=None,
) -> Frame:
    """Rasterizes ``draws`` seen by ``camera`` into a Frame of ``camera.height`` x ``camera.width``.

    ``samples``: 1, 2 or 4 samples per pixel along each axis (box resolve). ``blend``: "exact"
    (transparent fragments composited per sample in depth order) or "unsorted" (in submission
    order). ``shading``: "flat" (the colour) or "lambert": colour * (ambient + sum over lights of
    intensity * max(0, n . -direction)), n the interpolated normal (turned towards the camera on
    back faces when culling is off). ``lights``: objects with ``.direction`` (3,) (the direction
    the light travels) and ``.intensity`` (float or RGB), or (direction, intensity) pairs.
    ``ambient``: float or RGB.

    ``background`` (default None: the frame starts empty): opaque surfaces the frame starts
    from, one entry per *sample* (``H*samples`` rows of ``W*samples``): a Frame (e.g. of an
    earlier ``rasterize`` call with ``samples=1`` and the same camera) or an ``(rgba, depth,
    ids)`` triple with ``rgba`` (Hs,Ws,4) float32 premultiplied linear RGBA (finite), ``depth``
    (Hs,Ws) float32 view-axis distance in scene units, > 0, ``inf`` where empty, and ``ids``
    (Hs,Ws) int32. Its depth pre-loads the z-buffer: the draws are depth-tested against it
    per sample and transparent fragments in front of it are composited over its colour, as if
    its surfaces had been drawn first in the same call (exactly so for opaque surfaces, up to
    depth ties within one float32 ulp), so only the new draws are rasterized. A sample of the
    background with a finite depth acts as an opaque surface at that depth whatever its alpha
    (draws behind it are hidden). Where no draw covers a sample the frame keeps the
    background's rgba, depth and id (velocity 0). The
    background arrays are read, never written. Wrong shapes, dtypes that do not convert, NaN
    colours and NaN or non-positive depths raise ValueError / TypeError naming ``background``.

    ``blend="exact"`` keeps at most ``FRAGMENT_CAP`` (32) transparent fragments of a sample in
    its list: a sample with more (a stack of more than 32 transparent surfaces) gets its 32
    nearest composited exactly over the farther ones merged into one layer, whose alpha is
    exact and whose colour is their alpha-weighted mean (the error is at most the spread of the
    merged colours times their alpha times what the 32 nearest let through); the frame's
    memory then stays bounded whatever the depth complexity, and its time proportional to the
    fragments. ``blend="unsorted"`` composites each fragment as it comes (no list).

    Memory: the frame's 32 bytes a pixel, about 100 bytes a vertex and a face, and the tiles'
    copies of the triangles (about 100 bytes for each 64x64-sample tile a triangle's box
    reaches) are checked against the memory budget (``motionblur.set_memory_budget``) before
    they are allocated: past it ``MemoryError`` names the arguments and the bytes.

    ``Frame.stats`` (a dict): ``triangles`` (after clipping, culling and dropping triangles
    that cover no sample), ``fragments`` (samples covered, both passes),
    ``approximated_samples`` (samples of the supersampled image whose transparent fragments
    past ``FRAGMENT_CAP`` were merged, 0 when the frame is exact), ``culled`` (back faces),
    ``clipped`` (faces clipped against the near/far planes or the guard band), and
    milliseconds per stage: ``ms_transform`` (vertices projected and snapped), ``ms_setup``
    (triangle set-up: clipping, culling, bounds, the covered box of small triangles),
    ``ms_bin`` (triangles binned into 64x64-sample tiles), ``ms_raster`` (the tiles, wall
    clock), ``ms_total`` (the core's whole frame) and ``ms`` (this call, from Python). The
    tiles' stages are thread time summed over the tiles (with several threads they add up to
    more than ``ms_raster``): ``ms_coverage`` (opaque pass: coverage and depth test),
    ``ms_shade`` (shading the opaque samples that stay visible), ``ms_transparent`` (transparent
    pass: coverage, depth test, shading and compositing) and ``ms_resolve`` (samples resolved
    into the frame's buffers).

    The GIL is released while rendering.
    """
    t0 = time.perf_counter()
    if not isinstance(camera, Camera):
        raise TypeError(f"camera: expected a motionblur.Camera, got {type(camera).__name__}")
    if isinstance(draws, Draw):
        draws = [draws]
    try:
        draws = list(draws)
    except TypeError as exc:
        raise TypeError("draws: expected a Draw or a sequence of Draws") from exc
    for i, d in enumerate(draws):
        if not isinstance(d, Draw):
            raise TypeError(f"draws: item {i} is a {type(d).__name__}, not a motionblur.Draw")
    samples = as_samples(samples, "samples")
    if max(camera.width, camera.height) * samples > _core.MAX_INTERNAL_SIDE:
        raise ValueError(f"samples: width and height times samples must be <= {_core.MAX_INTERNAL_SIDE}")
    as_choice(blend, "blend", _core.BLENDS)
    as_choice(shading, "shading", _core.SHADINGS)
    amb = as_rgb(ambient, "ambient")
    if background is not None:
        background = _background(background, camera.height * samples, camera.width * samples)
    options = {
        "view": camera.view,
        "projection": camera.projection,
        "width": camera.width,
        "height": camera.height,
        "samples": samples,
        "blend": blend,
        "shading": shading,
        "lights": _lights(lights),
        "ambient": tuple(map(float, amb)),
        "origin": (0, 0),
    }
    rgba, depth, ids, velocity, stats = _core._rasterize(draws, options, background)
    stats["ms"] = (time.perf_counter() - t0) * 1e3
    return Frame(rgba, depth, ids, velocity, stats)
