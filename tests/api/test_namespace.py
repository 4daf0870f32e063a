"""A clean public namespace: ``dir()`` of the package and of every submodule shows its API, not
the modules it imported for itself (``np``, ``os``), ``annotations`` or private helpers."""

from __future__ import annotations

import importlib
import pkgutil
from types import ModuleType

import pytest

import motionblur as mb

MODULES = ["motionblur"] + sorted(
    info.name for info in pkgutil.walk_packages(mb.__path__, "motionblur.") if "._" not in info.name
)
NOISE = {"np", "os", "sys", "math", "time", "annotations", "Path", "inspect", "json", "warnings", "dataclass"}


def test_every_public_module_is_walked():
    assert {"motionblur.scene", "motionblur.interop.gltf", "motionblur.evaluation.bench"} <= set(MODULES)


@pytest.mark.parametrize("name", MODULES)
def test_dir_shows_the_api_only(name):
    module = importlib.import_module(name)
    names = dir(module)
    assert not NOISE & set(names), f"{name}: {sorted(NOISE & set(names))}"
    for n in names:
        if n.startswith("__"):
            continue
        assert not n.startswith("_"), f"{name}.{n} is private"
        value = getattr(module, n)  # every name shown exists
        if isinstance(value, ModuleType):
            assert value.__name__.startswith("motionblur."), f"{name}.{n} is the module {value.__name__}"
    for n in getattr(module, "__all__", []):
        assert n in names, f"{name}.{n} is in __all__ but not in dir()"


def test_the_top_level_shows_its_api_and_public_subpackages():
    names = set(dir(mb))
    assert {
        "render",
        "Scene",
        "Camera",
        "Frame",
        "read_image",
        "to_mitsuba_dict",
        "interop",
        "image",
    } <= names
    assert not {"tidy", "annotations", "_geometry", "_malloc"} & names
