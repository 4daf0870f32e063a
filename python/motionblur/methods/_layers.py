"""The layers every rendering method shares.

A `Layer` is one sample per pixel: colour, depth and object id. The methods draw objects
at a time into layers through one rasterizer call (`raster_layer`, each object with its own
shading mode, or `raw_layer` for the bare compiled call), composite layers per sample by depth
(`composite`), supersample by rendering at ``samples`` times the size and resolving down
(`supersampled`, `resolve`), and keep the static objects' layer across frames
(`static_layer`), pasting what they redraw into it (`paste`).
"""

from __future__ import annotations

import copy
import threading
from contextlib import contextmanager
from dataclasses import dataclass

import numpy as np

from .. import _core
from ..raster import Camera, Draw, Frame, rasterize
from ..renderer import current_renderer
from ..scene import Object, Scene

__all__ = [
    "Layer",
    "composite",
    "object_draw",
    "raster_layer",
    "raw_layer",
    "window_projection",
    "supersampled",
    "downsample",
    "resolve_arrays",
    "resolve",
    "Static",
    "static_layer",
    "clear_static_cache",
    "aligned_window",
    "paste",
]


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
    transparent surface per layer and sample); a new Layer. One pass in Rust."""
    rgba = np.array(b.rgba, dtype=np.float32, order="C")
    depth = np.array(b.depth, dtype=np.float32, order="C")
    ids = np.array(b.ids, dtype=np.int32, order="C")
    c = np.ascontiguousarray
    out = Layer(rgba, depth, ids)
    _core._composite(Layer(c(a.rgba), c(a.depth), c(a.ids)), out)
    return out


def object_draw(obj: Object, t: float, object_id: int, vertices=None) -> Draw:
    """A Draw of ``obj`` at shutter time ``t`` (world vertices), id ``object_id``."""
    v = obj.world_vertices(t) if vertices is None else vertices
    return Draw(v, obj.mesh.faces, obj.rgba, object_id=object_id)


def raster_layer(
    camera: Camera,
    scene: Scene,
    draws: list[tuple[Object, Draw]],
    view=None,
    projection=None,
    background=None,
    samples: int = 1,
    background_origin=(0, 0),
) -> Layer:
    """Rasterize ``draws`` (pairs of the object and its Draw) in one rasterizer call, each draw
    with its object's shading mode. ``view``/``projection`` (4,4) override the camera's (the image
    size stays the camera's). ``samples`` (1, 2 or 4) per pixel along each axis, box-resolved
    by the rasterizer (depth and id of each pixel's nearest sample). ``background``: an opaque
    Layer, one entry per sample, the draws are rasterized over (the rasterizer's
    ``background``: exact per-sample depth test and transparency): the camera's size times
    ``samples``, or a larger Layer whose sample ``background_origin`` (x0, y0) lies under the
    frame's first sample (a window of a kept layer, read without a copy). Returns a Layer of the
    camera's size."""
    call = _one_call(draws)
    out = None
    if call is not None:
        shading, ds = call
        if view is None and projection is None:
            if background is not None and tuple(background_origin) != (0, 0):
                raise ValueError("background_origin: needs view or projection (the raw rasterizer call)")
            f = rasterize(
                camera, ds, samples=samples, shading=shading, lights=scene.lights, ambient=scene.ambient,
                background=background,
            )  # fmt: skip
            out = Layer(f.rgba, f.depth, f.ids)
        else:
            out = raw_layer(
                camera.width,
                camera.height,
                camera.view if view is None else view,
                camera.projection if projection is None else projection,
                ds,
                shading,
                _lights(scene, None),
                scene.ambient,
                background=background,
                samples=samples,
                background_origin=background_origin,
            )
    if out is None:
        if background is None:
            out = Layer.empty(camera.height, camera.width)
        else:
            (x0, y0), hs, ws = background_origin, camera.height * samples, camera.width * samples
            window = Layer(
                background.rgba[y0 : y0 + hs, x0 : x0 + ws],
                background.depth[y0 : y0 + hs, x0 : x0 + ws],
                background.ids[y0 : y0 + hs, x0 : x0 + ws],
            )
            out = _copy(window) if samples == 1 else Layer(*resolve_arrays(window, samples))
    return out


def _one_call(draws: list[tuple[Object, Draw]]) -> tuple[str, list[Draw]] | None:
    """The draws as one rasterizer call (its shading mode, its draws), None when there are none:
    of their one shading mode, or, with two, a "lambert" call with the flat ones marked flat
    (so that the depth test and the transparent sort are per sample, whatever the modes)."""
    modes = {obj.shading for obj, _ in draws}
    if not modes:
        return None
    if len(modes) == 1:
        return modes.pop(), [d for _, d in draws]
    return "lambert", [d if obj.shading == "lambert" else _with_shading(d, obj.shading) for obj, d in draws]


def _with_shading(draw: Draw, shading: str) -> Draw:
    """A shallow copy of ``draw`` (its read-only arrays shared) drawn with ``shading``."""
    out = copy.copy(draw)
    out.shading = shading
    return out


def _copy(layer: Layer) -> Layer:
    return Layer(
        np.array(layer.rgba, np.float32), np.array(layer.depth, np.float32), np.array(layer.ids, np.int32)
    )


def _lights(scene: Scene, rotation) -> list:
    """Scene lights as the rasterizer takes them, directions optionally rotated by ``rotation`` (3,3)."""
    out = []
    for light in scene.lights:
        d = light.direction if rotation is None else rotation @ light.direction
        out.append((tuple(map(float, d)), tuple(map(float, light.intensity))))
    return out


def raw_layer(
    width,
    height,
    view,
    projection,
    draws,
    shading,
    lights,
    ambient,
    background=None,
    samples: int = 1,
    background_origin=(0, 0),
) -> Layer:
    """Direct call of the compiled rasterizer (no checks beyond the core's): ``samples`` per
    pixel along each axis, over the opaque Layer ``background`` (one entry per sample) when
    given: the frame's samples are its window from sample ``background_origin`` (x0, y0),
    read in place when its arrays are C-contiguous float32 / float32 / int32 (else copied);
    never written."""
    if background is not None:
        c = np.ascontiguousarray
        background = Layer(
            c(background.rgba, dtype=np.float32), c(background.depth, dtype=np.float32),
            c(background.ids, dtype=np.int32),
        )  # fmt: skip
    rgba, depth, ids, _velocity, _stats = _core._rasterize(
        draws,
        {
            "view": np.ascontiguousarray(view, dtype=np.float64),
            "projection": np.ascontiguousarray(projection, dtype=np.float64),
            "width": int(width),
            "height": int(height),
            "samples": int(samples),
            "blend": "exact",
            "shading": shading,
            "lights": lights,
            "ambient": tuple(map(float, np.broadcast_to(ambient, (3,)))),
            "origin": tuple(map(int, background_origin)),
        },
        background,
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


# ---------------------------------------------------------------- supersampling


def supersampled(camera: Camera, samples: int) -> Camera:
    """``camera`` at ``samples`` times its width and height (pixel centres = the sub-samples)."""
    if samples == 1:
        return camera
    return camera.resized(camera.width * samples, camera.height * samples)


def downsample(a: np.ndarray, samples: int) -> np.ndarray:
    """Box-filter (H*s, W*s, ...) down to (H, W, ...) (mean over each s x s block), float32."""
    if samples == 1:
        return a
    out = None
    for dy in range(samples):
        for dx in range(samples):
            part = a[dy::samples, dx::samples]
            out = part.astype(np.float32, copy=True) if out is None else np.add(out, part, out=out)
    out *= np.float32(1.0 / (samples * samples))
    return out


def resolve_arrays(layer: Layer, samples: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(rgba, depth, ids) at pixel size from a supersampled layer: colour box-filtered, depth and
    ids of the nearest sample of each pixel (the first in row order on ties)."""
    if samples == 1:
        return layer.rgba, layer.depth, layer.ids
    h, w = layer.depth.shape[0] // samples, layer.depth.shape[1] // samples
    rgba = np.empty((h, w, 4), np.float32)
    depth = np.empty((h, w), np.float32)
    ids = np.empty((h, w), np.int32)
    _resolve_into(layer, samples, rgba, depth, ids, 0, 0)
    return rgba, depth, ids


def _resolve_into(layer: Layer, samples: int, rgba, depth, ids, x0: int, y0: int) -> None:
    """Resolve the supersampled ``layer`` into the pixel arrays at pixel (x0, y0), in place (Rust)."""
    c = np.ascontiguousarray
    _core._resolve(
        Layer(c(layer.rgba, dtype=np.float32), c(layer.depth, dtype=np.float32), c(layer.ids, dtype=np.int32)),
        samples, Layer(rgba, depth, ids), (x0, y0),
    )  # fmt: skip


def resolve(layer: Layer, samples: int) -> Frame:
    """A full-size Frame from a supersampled layer (see `resolve_arrays`)."""
    rgba, depth, ids = resolve_arrays(layer, samples)
    return Frame(rgba, depth, ids, np.zeros((*rgba.shape[:2], 2), np.float32))


# ---------------------------------------------------------------- the static layer, kept across frames


def clear_static_cache() -> None:
    """Forget the static layers kept across frames (of the renderer running, else of the default
    one: `motionblur.Renderer.clear` empties all of a renderer's stores)."""
    current_renderer().static_layers.clear()


def _fingerprint(scene: Scene, camera: Camera, objects, aa: int) -> tuple:
    parts = []
    for k, o in objects:
        motion = None
        if o.motion is not None:
            motion = id(o.motion) if o.motion.is_deforming else o.motion.transform_at(0.0).tobytes()
        parts.append((k, id(o.mesh), o.shading, o.color.tobytes(), motion))
    lights = tuple((li.direction.tobytes(), li.intensity.tobytes()) for li in scene.lights)
    cam = (camera.view.tobytes(), camera.projection.tobytes(), camera.width, camera.height)
    return (cam, aa, tuple(parts), lights, scene.ambient.tobytes())


class Static:
    """The static layer of a frame: ``layer`` (supersampled Layer) and its resolved pixels
    ``rgba``, ``depth``, ``ids`` (read-only; copy before writing); ``cached`` tells whether it
    came from the cache."""

    def __init__(self, layer: Layer, aa: int, cached: bool = False):
        self.layer = layer
        self.rgba, self.depth, self.ids = resolve_arrays(layer, aa)
        self.opaque = True
        self.cached = cached
        # `pasted`'s colour, kept with the layer, and the window pasted in it last
        self._pasted: np.ndarray | None = None
        self._window = None
        self._lock = threading.Lock()

    @contextmanager
    def pasted(self, window, part: np.ndarray):
        """The static colour with ``part`` pasted in ``window`` (y0, y1, x0, x1), to be read
        (not written, not kept) while the context lasts: a copy of the colour kept with the
        layer (one more frame of memory), whose previous window is put back before the new one
        is pasted, so a frame costs its window's copies instead of a frame-sized copy into
        fresh pages. A fresh copy when another thread holds the kept one."""
        y0, y1, x0, x1 = window
        if not self._lock.acquire(blocking=False):
            rgba = self.rgba.copy()
            rgba[y0:y1, x0:x1] = part
            yield rgba
            return
        try:
            if self._pasted is None:
                self._pasted = self.rgba.copy()
            elif self._window is not None:
                b0, b1, a0, a1 = self._window
                self._pasted[b0:b1, a0:a1] = self.rgba[b0:b1, a0:a1]
            self._window = window
            self._pasted[y0:y1, x0:x1] = part
            yield self._pasted
        finally:
            self._lock.release()


def static_layer(scene: Scene, camera: Camera, objects, aa: int) -> Static:
    """The static objects ``objects`` (pairs (index, Object), placed at t = 0) rasterized by the
    supersampled ``camera``; kept (up to 4 entries) across frames while the objects, their colours
    and placement, the camera, the lights and ``aa`` stay the same, as a real-time loop reuses
    the static part of its frame."""
    key = _fingerprint(scene, camera, objects, aa)
    kept = current_renderer().static_layers
    hit = kept.get(key)
    if hit is not None:
        hit[0].cached = True
        return hit[0]
    layer = raster_layer(camera, scene, [(o, object_draw(o, 0.0, k)) for k, o in objects])
    st = Static(layer, aa)
    st.opaque = not any(o.is_transparent for _, o in objects)
    # keep the objects alive with the entry, so the ids in the key stay theirs
    kept.put(key, (st, [o for _, o in objects]))
    return st


def aligned_window(win, aa: int, width: int, height: int):
    """``win`` (x0, y0, x1, y1) in supersampled pixels grown to multiples of ``aa``."""
    x0, y0, x1, y1 = win
    x0, y0 = (x0 // aa) * aa, (y0 // aa) * aa
    x1, y1 = min(width, -(-x1 // aa) * aa), min(height, -(-y1 // aa) * aa)
    return x0, y0, x1, y1


def paste(static: Static, window, layer: Layer, aa: int) -> Frame:
    """A Frame: the static pixels with the supersampled ``layer`` of ``window`` (aligned to
    ``aa``) resolved and pasted in."""
    rgba, depth, ids = static.rgba.copy(), static.depth.copy(), static.ids.copy()
    x0, y0, x1, y1 = (v // aa for v in window)
    if aa == 1:
        rgba[y0:y1, x0:x1], depth[y0:y1, x0:x1], ids[y0:y1, x0:x1] = layer.rgba, layer.depth, layer.ids
    else:
        _resolve_into(layer, aa, rgba, depth, ids, x0, y0)
    return Frame(rgba, depth, ids, np.zeros((*rgba.shape[:2], 2), np.float32))
