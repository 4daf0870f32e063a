"""Rendering methods, one module each; importing this package registers all of them.

Adding a method is adding a module here that decorates its function with
:func:`motionblur.render.register`. Every module of the package whose name does not start
with an underscore is imported automatically.
"""

from __future__ import annotations

import importlib
import pkgutil

__all__ = [info.name for info in pkgutil.iter_modules(__path__) if not info.name.startswith("_")]

for _name in __all__:
    importlib.import_module(f"{__name__}.{_name}")
