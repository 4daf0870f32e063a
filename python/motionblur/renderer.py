"""``Renderer``: what the methods keep between frames, on an object the caller holds.

A real-time loop renders the same objects frame after frame, and several methods reuse what
they set up for the previous frame: the static layer (the objects that do not move, rasterized
once), the compiled painters of the time-sampling methods, per-mesh constants (normals, box
corners, centroids), the motion volume's contour tables and the blur shells. All of it lives on
a [`Renderer`][motionblur.renderer.Renderer]; `motionblur.render` uses the process's default one
(`default_renderer`), and a loop that wants its own (or wants to empty it) makes one.
"""

from __future__ import annotations

import contextvars
import threading
from collections import OrderedDict
from collections.abc import Callable
from typing import Any

__all__ = ["Renderer", "default_renderer", "current_renderer"]


class _Kept:
    """A small least-recently-used store of ``size`` entries, safe to share between threads."""

    def __init__(self, size: int):
        self.size = size
        self._items: OrderedDict = OrderedDict()
        # re-entrant: a weak reference's callback (an entry's object collected) may discard an
        # entry while this thread holds the lock
        self._lock = threading.RLock()

    def get(self, key, valid: Callable[[Any], bool] = lambda hit: True):
        """The entry of ``key`` (marked recently used) when ``valid(entry)``, else None."""
        with self._lock:
            hit = self._items.get(key)
            if hit is None or not valid(hit):
                return None
            if key in self._items:
                self._items.move_to_end(key)
            return hit

    def take(self, key):
        """The entry of ``key``, removed (None when there is none)."""
        with self._lock:
            return self._items.pop(key, None)

    def put(self, key, value) -> None:
        with self._lock:
            self._items[key] = value
            self._items.move_to_end(key)
            while len(self._items) > self.size:
                self._items.popitem(last=False)

    def discard(self, key) -> None:
        with self._lock:
            self._items.pop(key, None)

    def clear(self) -> None:
        with self._lock:
            self._items.clear()

    def __len__(self) -> int:
        return len(self._items)

    def __contains__(self, key) -> bool:
        return key in self._items


class Renderer:
    """Renders scenes and keeps, between frames, what the methods can reuse.

    ``Renderer().render(scene, method, **options)`` is `motionblur.render` (same
    arguments, same Frame) with this renderer's stores; `motionblur.render` itself uses
    `default_renderer`. Keep one per real-time loop: a frame whose static objects, camera
    and lights equal the previous frame's reuses its static layer; a painter, a contour table
    or a blur shell set up for a mesh is reused while that mesh (the same object) is rendered.

    What is kept, and for how long:

    - ``static_layers``: the static layer of a still camera (the last 4 fingerprints of
      objects, colours, placement, camera, lights and ``aa``), and once the ``velocity`` method
      has used it, a copy of its colour that method pastes each frame's moving objects into;
    - ``painters``: the compiled painters of accumulation and the colour renders (the last 4
      object sets);
    - ``mesh_constants``: per-mesh arrays (normals, box corners, centroids), each dropped with
      its mesh's vertex array;
    - ``contour_tables``: ``motion_volume``'s ``contour_table=True`` tables (the last 8 meshes);
    - ``shells``: ``blur_shell``'s shells (the last 8 meshes and options).

    Every entry is keyed by the identity of the objects it was made from and holds a
    reference (or a weak reference checked on use) to them, so an identity reused after garbage
    collection never finds another object's entry. [`clear`][motionblur.renderer.Renderer.clear] empties every store (memory
    back; the next frame sets everything up again). Renders in several threads may share one
    renderer."""

    def __init__(self) -> None:
        self.static_layers = _Kept(4)
        self.painters = _Kept(4)
        self.contour_tables = _Kept(8)
        self.shells = _Kept(8)
        self.mesh_constants: dict = {}

    def render(self, scene, method: str = "accumulation", **options):
        """`motionblur.render` ``(scene, method, **options)`` with this renderer's stores:
        returns its Frame, raises what it raises."""
        from .render import render

        token = _CURRENT.set(self)
        try:
            return render(scene, method, **options)
        finally:
            _CURRENT.reset(token)

    def clear(self) -> None:
        """Empty every store of this renderer."""
        for kept in (self.static_layers, self.painters, self.contour_tables, self.shells):
            kept.clear()
        self.mesh_constants.clear()

    def __repr__(self) -> str:
        return (
            f"Renderer(static_layers={len(self.static_layers)}, painters={len(self.painters)}, "
            f"meshes with constants={len(self.mesh_constants)}, contour_tables={len(self.contour_tables)}, "
            f"shells={len(self.shells)})"
        )


_CURRENT: contextvars.ContextVar[Renderer | None] = contextvars.ContextVar(
    "motionblur_renderer", default=None
)
_DEFAULT: list[Renderer] = []
_DEFAULT_LOCK = threading.Lock()


def default_renderer() -> Renderer:
    """The renderer `motionblur.render` uses (made at its first use)."""
    if not _DEFAULT:
        with _DEFAULT_LOCK:
            if not _DEFAULT:
                _DEFAULT.append(Renderer())
    return _DEFAULT[0]


def current_renderer() -> Renderer:
    """The renderer of the render running in this thread: the one whose [`Renderer.render`][motionblur.renderer.Renderer.render]
    called it, else `default_renderer`."""
    r = _CURRENT.get()
    return default_renderer() if r is None else r
