"""The methods package: every method module is imported (so registered), and no method imports
another one (what they share lives in the modules whose names start with an underscore)."""

from __future__ import annotations

import pkgutil
from pathlib import Path

from _helpers.import_graph import python_graph

import motionblur as mb
from motionblur import methods

ROOT = Path(__file__).resolve().parents[2]


def _method_modules() -> list[str]:
    return [m.name for m in pkgutil.iter_modules(methods.__path__) if not m.name.startswith("_")]


def test_every_method_module_is_imported_by_the_package():
    assert _method_modules() == [n for n in methods.__all__ if n != "clear_static_cache"]
    registered = {spec.fn.__module__ for spec in mb.METHODS.values()}
    assert registered == {f"motionblur.methods.{n}" for n in _method_modules()}


def test_no_method_imports_another_method():
    graph = python_graph(ROOT / "python" / "motionblur", ROOT)
    folder = "python/motionblur/methods/"
    modules = {f"{folder}{n}.py" for n in _method_modules()}
    crossing = {(a, b): names for a in modules for b, names in graph[a].items() if b in modules}
    assert not crossing, crossing
