"""``render(scene, method=..., **options) -> Frame`` and the registry of rendering methods.

Every method lives in its own module of :mod:`motionblur.methods` and registers itself with
:func:`register`::

    @register("accumulation", sweep=[{"samples": n} for n in (1, 4, 16)], applies=lambda scene: True)
    def accumulation(scene, samples=16, ...) -> Frame: ...

``sweep`` lists the option sets the speed-against-error report (:mod:`motionblur.evaluation`)
runs for the method on every built-in scene where ``applies(scene)`` is true. Importing
:mod:`motionblur` imports :mod:`motionblur.methods`, which registers every built-in method; this
module knows none of them. The layers the methods share are in :mod:`motionblur.methods._layers`.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field

from .raster import Frame, over_background
from .scene import Scene

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
    return [n for n, m in METHODS.items() if m.applies(scene)]


def render(scene: Scene, method: str = "accumulation", **options) -> Frame:
    """Render ``scene`` with the registered ``method`` (``accumulation``, ``motion_volume``, ...).

    Returns a :class:`Frame` of ``scene.camera`` size: ``rgba`` (H,W,4) float32 premultiplied
    linear RGBA composited over ``scene.background``, ``depth`` (H,W) float32, ``ids`` (H,W) int32
    (object index in ``scene.objects``, -1 background), ``velocity`` (H,W,2) and ``stats`` with
    ``method``, ``options`` and ``ms`` (wall time of the whole call). Unknown methods and options
    raise ValueError / TypeError.
    """
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


# The methods' layer helpers are in motionblur.methods._layers. ``motionblur.render.<name>`` still
# reaches them for old imports, loaded on first use so that this module imports no method.
_MOVED = frozenset(
    {
        "Layer", "Static", "aligned_window", "clear_static_cache", "composite", "downsample",
        "object_draw", "paste", "raster_layer", "raw_layer", "resolve", "resolve_arrays",
        "static_layer", "supersampled", "window_projection",
    }
)  # fmt: skip


def __getattr__(name: str):
    if name in _MOVED:
        from .methods import _layers

        return getattr(_layers, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted([*globals(), *_MOVED])
