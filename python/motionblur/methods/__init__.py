"""Rendering methods, one module each; importing this package registers all of them.

Adding a method is adding a module here that decorates its function with
:func:`motionblur.render.register`. Every module of the package whose name does not start
with an underscore is imported automatically. The modules that do start with one hold what
the methods share, and a method imports them, never another method: ``_layers`` (rasterizing
into layers, compositing, supersampling, the static layer kept across frames), ``_painter``
(objects drawn at any shutter time, per-mesh constants) and ``_volume_colors`` (the colours of
motion volumes).
"""

from __future__ import annotations

import importlib
import pkgutil

from ._layers import clear_static_cache

_METHOD_MODULES = [info.name for info in pkgutil.iter_modules(__path__) if not info.name.startswith("_")]

__all__ = [*_METHOD_MODULES, "clear_static_cache"]

for _name in _METHOD_MODULES:
    importlib.import_module(f"{__name__}.{_name}")
