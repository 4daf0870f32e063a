"""A clean public namespace: ``dir()`` of the package and of every submodule lists its API only.

A module's globals also hold what it imported for its own use (``np``, ``os``, ``math``), the
``annotations`` feature of ``from __future__ import annotations`` and private helpers; tab
completion in Jupyter and ``dir()`` would show them all. `tidy` gives every module of the
package a module-level ``__dir__`` (PEP 562) that returns its public names only: ``__all__``
where the module has one, else the public names it defines itself; plus its public submodules
and the dunder names. Nothing is deleted: ``module.np`` still works for code that uses it.
"""

from __future__ import annotations
import __future__

import importlib
import pkgutil
import sys
from types import ModuleType

__all__ = ["tidy", "public_names"]


def _defined_here(module: ModuleType, name: str, value: object) -> bool:
    if isinstance(value, ModuleType):  # a submodule of this one is public, any other module is not
        return value.__name__.startswith(module.__name__ + ".") and not name.startswith("_")
    if isinstance(value, __future__._Feature):  # type: ignore[attr-defined]
        return False
    home = getattr(value, "__module__", None)
    if home is None or not callable(value):  # constants and data defined at module level
        return not isinstance(value, type(sys))
    return home == module.__name__


def public_names(module: ModuleType) -> list[str]:
    """The names `tidy` lets ``dir(module)`` show (sorted)."""
    g = vars(module)
    names = {n for n in g if n.startswith("__") and n.endswith("__") and n != "__builtins__"}
    exported = g.get("__all__")
    if exported is not None:
        names.update(str(n) for n in exported)
        names.update(n for n, v in g.items() if isinstance(v, ModuleType) and _defined_here(module, n, v))
    else:
        names.update(n for n, v in g.items() if not n.startswith("_") and _defined_here(module, n, v))
    return sorted(names)


def tidy(package: str, lazy=(), walk: bool = False) -> None:
    """Give the module or package ``package`` and every submodule of it loaded now a
    ``__dir__`` listing `public_names` (read when called, so names set later show).
    ``lazy``: names the module serves through its ``__getattr__`` at first use, listed too;
    ``walk``: import every submodule first (but ``__main__``; none of them imports an optional
    dependency at import time). A module loaded later tidies itself (it calls this at its end)."""
    root = sys.modules[package]
    if walk:
        for info in pkgutil.walk_packages(root.__path__, package + "."):
            if info.name.rsplit(".", 1)[-1] != "__main__":  # runpy warns when `python -m` finds it loaded
                importlib.import_module(info.name)
    for name, module in list(sys.modules.items()):
        if module is None or not (name == package or name.startswith(package + ".")):
            continue
        own = vars(module).get("__dir__")
        if callable(own) and getattr(own, "_tidy", False):
            continue
        extra = set(lazy) if module is root else set()
        if callable(own):  # names the module serves through its own __getattr__ stay
            extra.update(n for n in own() if n not in vars(module))

        def __dir__(module=module, extra=frozenset(extra)) -> list[str]:
            return sorted(set(public_names(module)) | extra)

        __dir__._tidy = True  # type: ignore[attr-defined]
        module.__dir__ = __dir__  # type: ignore[method-assign]
