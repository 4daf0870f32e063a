"""``render(scene, method=..., **options) -> Frame`` and the registry of rendering methods.

Every method lives in its own module of :mod:`motionblur.methods` and registers itself with
:func:`register`::

    @register("accumulation", sweep=[{"samples": n} for n in (1, 4, 16)], applies=lambda scene: True)
    def accumulation(scene, samples=16, ...) -> Frame: ...

``sweep`` lists the option sets the speed-against-error report (``motionblur.bench``) runs for
the method on every built-in scene where ``applies(scene)`` is true.

This module also holds the layer helpers the methods share: drawing objects at a time through
one rasterizer call per shading mode, compositing layers per sample by depth, supersampling by
rendering at ``samples`` times the size and box-filtering down, and the background.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from . import _core
from .raster import Camera, Draw, Frame, rasterize
from .scene import Object, Scene

__all__ = ["render", "register", "METHODS", "MethodSpec", "methods_for"]


@dataclass
class MethodSpec:
    """A registered method: its function ``fn(scene, **options) -> Frame``, the option sets
    ``sweep`` the benchmark runs, ``applies(scene) -> bool`` and a one-line description."""

    name: str
    fn: Callable[..., Frame]
    sweep: list[dict] = field(default_factory=list)
    applies: Callable[[Scene], bool] = lambda scene: True
    doc: str = ""


#: Every rendering method, by name (filled by ``@register`` when :mod:`motionblur.methods` loads).
METHODS: dict[str, MethodSpec] = {}


def register(name: str, sweep=(), applies: Callable[[Scene], bool] | None = None):
    """Decorator: register ``fn(scene, **options) -> Frame`` as method ``name`` (see the module docs)."""
    if not isinstance(name, str) or not name:
        raise TypeError("name: expected a non-empty string")

    def deco(fn):
        doc = (fn.__doc__ or "").strip().splitlines()
        METHODS[name] = MethodSpec(
            name=name,
            fn=fn,
            sweep=[dict(s) for s in sweep],
            applies=applies if applies is not None else (lambda scene: True),
            doc=doc[0] if doc else "",
        )
        return fn

    return deco


def methods_for(scene: Scene) -> list[str]:
    """Names of the registered methods that apply to ``scene``."""
    _load()
    return [n for n, m in METHODS.items() if m.applies(scene)]


def _load() -> None:
    from . import methods  # noqa: F401  (imports every method module, which registers itself)


def render(scene: Scene, method: str = "accumulation", **options) -> Frame:
    """Render ``scene`` with the registered ``method`` (``accumulation``, ``motion_volume``, ...).

    Returns a :class:`Frame` of ``scene.camera`` size: ``rgba`` (H,W,4) float32 premultiplied
    linear RGBA composited over ``scene.background``, ``depth`` (H,W) float32, ``ids`` (H,W) int32
    (object index in ``scene.objects``, -1 background), ``velocity`` (H,W,2) and ``stats`` with
    ``method``, ``options`` and ``ms`` (wall time of the whole call). Unknown methods and options
    raise ValueError / TypeError.
    """
    _load()
    if not isinstance(scene, Scene):
        raise TypeError(f"scene: expected a motionblur.Scene, got {type(scene).__name__}")
    if not isinstance(method, str):
        raise TypeError(f"method: expected a string, got {type(method).__name__}")
    if method not in METHODS:
        raise ValueError(f"method: unknown method {method!r}; expected one of {', '.join(sorted(METHODS))}")
    t0 = time.perf_counter()
    frame = METHODS[method].fn(scene, **options)
    frame = over_background(frame, scene.background)
    frame.stats["method"] = method
    frame.stats["options"] = dict(options)
    frame.stats["ms"] = (time.perf_counter() - t0) * 1e3
    return frame


# ---------------------------------------------------------------- layers shared by the methods


def over_background(frame: Frame, background) -> Frame:
    """``frame`` composited over straight RGBA ``background`` (4,) (premultiplied *over*)."""
    bg = np.asarray(background, dtype=np.float32)
    if bg[3] == 0.0 and not bg[:3].any():
        return frame
    pre = np.concatenate([bg[:3] * bg[3], bg[3:]]).astype(np.float32)
    rgba = frame.rgba + (1.0 - frame.rgba[..., 3:4]) * pre
    return Frame(rgba, frame.depth, frame.ids, frame.velocity, frame.stats)


def supersampled(camera: Camera, samples: int) -> Camera:
    """``camera`` at ``samples`` times its width and height (pixel centres = the sub-samples)."""
    if samples == 1:
        return camera
    return Camera(
        camera.pose, camera.yfov, camera.width * samples, camera.height * samples, camera.znear, camera.zfar
    )


def downsample(a: np.ndarray, samples: int) -> np.ndarray:
    """Box-filter (H*s, W*s, ...) down to (H, W, ...) (mean over each s x s block)."""
    if samples == 1:
        return a
    h, w = a.shape[0] // samples, a.shape[1] // samples
    return a.reshape(h, samples, w, samples, *a.shape[2:]).mean(axis=(1, 3), dtype=np.float64).astype(a.dtype)


def resolve(layer: Layer, samples: int) -> Frame:
    """A full-size Frame from a supersampled layer: colour box-filtered, depth and ids of the
    nearest sample of each pixel."""
    rgba = downsample(layer.rgba, samples)
    if samples == 1:
        depth, ids = layer.depth, layer.ids
    else:
        h, w = rgba.shape[:2]
        d = layer.depth.reshape(h, samples, w, samples).transpose(0, 2, 1, 3).reshape(h, w, -1)
        k = np.argmin(d, axis=2)
        depth = np.take_along_axis(d, k[..., None], 2)[..., 0]
        i = layer.ids.reshape(h, samples, w, samples).transpose(0, 2, 1, 3).reshape(h, w, -1)
        ids = np.take_along_axis(i, k[..., None], 2)[..., 0]
    return Frame(rgba, depth, ids, np.zeros((*rgba.shape[:2], 2), np.float32))


@dataclass
class Layer:
    """One sample per pixel: ``rgba`` (H,W,4) float32 premultiplied, ``depth`` (H,W) float32 (inf
    where empty), ``ids`` (H,W) int32."""

    rgba: np.ndarray
    depth: np.ndarray
    ids: np.ndarray

    @classmethod
    def empty(cls, h: int, w: int) -> Layer:
        return cls(
            np.zeros((h, w, 4), np.float32),
            np.full((h, w), np.inf, np.float32),
            np.full((h, w), -1, np.int32),
        )


def composite(a: Layer, b: Layer) -> Layer:
    """Per sample, the nearer layer *over* the farther one (exact for opaque surfaces and for one
    transparent surface per layer and sample)."""
    front = (a.depth <= b.depth)[..., None]
    near = np.where(front, a.rgba, b.rgba)
    far = np.where(front, b.rgba, a.rgba)
    rgba = near + (1.0 - near[..., 3:4]) * far
    depth = np.minimum(a.depth, b.depth)
    ids = np.where(front[..., 0], a.ids, b.ids)
    return Layer(rgba, depth, ids)


def object_draw(obj: Object, t: float, object_id: int, vertices=None) -> Draw:
    """A Draw of ``obj`` at shutter time ``t`` (world vertices), id ``object_id``."""
    v = obj.world_vertices(t) if vertices is None else vertices
    return Draw(v, obj.mesh.faces, obj.rgba, object_id=object_id)


def raster_layer(
    camera: Camera, scene: Scene, draws: list[tuple[Object, Draw]], view=None, projection=None
) -> Layer:
    """Rasterize ``draws`` (pairs of the object and its Draw) with one sample per pixel, one
    rasterizer call per shading mode, composited by depth. ``view``/``projection`` (4,4) override
    the camera's (the image size stays the camera's)."""
    groups: dict[str, list[Draw]] = {}
    for obj, d in draws:
        groups.setdefault(obj.shading, []).append(d)
    out = None
    for shading, ds in groups.items():
        if view is None and projection is None:
            f = rasterize(camera, ds, samples=1, shading=shading, lights=scene.lights, ambient=scene.ambient)
            layer = Layer(f.rgba, f.depth, f.ids)
        else:
            layer = raw_layer(
                camera.width,
                camera.height,
                camera.view if view is None else view,
                camera.projection if projection is None else projection,
                ds,
                shading,
                _lights(scene, None),
                scene.ambient,
            )
        out = layer if out is None else composite(out, layer)
    if out is None:
        out = Layer.empty(camera.height, camera.width)
    return out


def _lights(scene: Scene, rotation) -> list:
    """Scene lights as the rasterizer takes them, directions optionally rotated by ``rotation`` (3,3)."""
    out = []
    for light in scene.lights:
        d = light.direction if rotation is None else rotation @ light.direction
        out.append((tuple(map(float, d)), tuple(map(float, light.intensity))))
    return out


def raw_layer(width, height, view, projection, draws, shading, lights, ambient) -> Layer:
    """Direct call of the compiled rasterizer (no checks beyond the core's): one sample per pixel."""
    rgba, depth, ids, _velocity, _stats = _core._rasterize(
        np.ascontiguousarray(view, dtype=np.float64),
        np.ascontiguousarray(projection, dtype=np.float64),
        int(width),
        int(height),
        [d._args() for d in draws],
        1,
        "exact",
        shading,
        lights,
        tuple(map(float, np.broadcast_to(ambient, (3,)))),
    )
    return Layer(rgba, depth, ids)


def window_projection(projection: np.ndarray, width: int, height: int, window) -> np.ndarray:
    """Projection (4,4) that renders only the pixel rectangle ``window = (x0, y0, x1, y1)`` of a
    ``width`` x ``height`` image (row 0 at the top) into an image of (x1-x0) x (y1-y0) pixels,
    with the same pixel centres."""
    x0, y0, x1, y1 = window
    xl, xr = 2.0 * x0 / width - 1.0, 2.0 * x1 / width - 1.0
    yt, yb = 1.0 - 2.0 * y0 / height, 1.0 - 2.0 * y1 / height
    s = np.eye(4)
    s[0, 0] = 2.0 / (xr - xl)
    s[0, 3] = -(xr + xl) / (xr - xl)
    s[1, 1] = 2.0 / (yt - yb)
    s[1, 3] = -(yt + yb) / (yt - yb)
    return s @ projection
