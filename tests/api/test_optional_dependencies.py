"""A missing optional package names itself and the extra that installs it, and the demo checks
every package it needs before it writes anything.

A package is made missing the way Python itself reports one: ``sys.modules[name] = None`` makes
``import name`` raise ``ModuleNotFoundError`` (the real package stays installed for the rest of
the run).
"""

from __future__ import annotations

import sys

import numpy as np
import pytest

import motionblur as mb
from motionblur import MissingDependencyError, _optional
from motionblur.__main__ import main
from motionblur.dataset import make_dataset


def _hide(monkeypatch, name: str) -> None:
    for key in [k for k in sys.modules if k == name or k.startswith(name + ".")] + [name]:
        monkeypatch.setitem(sys.modules, key, None)


def _scene() -> mb.Scene:
    cam = mb.Camera(mb.look_at((0, 0, 4), (0, 0, 0)), 0.7, 32, 24)
    cube = mb.Object(mb.meshes.box((0.6, 0.6, 0.6)), motion=mb.Motion.linear([-0.5, 0, 0], [0.5, 0, 0]))
    return mb.Scene([cube], cam)


def _frame() -> mb.Frame:
    return mb.render(_scene(), "accumulation", samples=2)


CASES = {
    "mitsuba": ("mitsuba", "reference", lambda tmp: mb.reference.mitsuba(_scene(), times=1, spp=1)),
    "tqdm": ("tqdm", "reference", lambda tmp: mb.reference.mitsuba(_scene(), times=1, spp=1)),
    "flip_evaluator": ("flip-evaluator", "metrics", lambda tmp: mb.metrics.flip(_frame(), _frame())),
    "pyrender": ("pyrender", "pyrender", lambda tmp: mb.reference.pyrender(_scene())),
    "PIL": ("pillow", "interop", lambda tmp: _frame().save_png(tmp / "new" / "a.png")),
    "OpenEXR": ("OpenEXR", "interop", lambda tmp: _frame().save_exr(tmp / "new" / "a.exr")),
    "trimesh": ("trimesh", "interop", lambda tmp: mb.Mesh(*mb.meshes.box()).to_trimesh()),
    "pygltflib": ("pygltflib", "interop", lambda tmp: mb.Scene.from_gltf(_any_file(tmp))),
    "imageio_ffmpeg": (
        "imageio-ffmpeg",
        "video",
        lambda tmp: make_dataset("cube", tmp / "new", frames=(0, 1), preview="mp4", progress=False),
    ),
}


def _any_file(tmp):
    path = tmp / "a.gltf"
    path.write_text("{}")
    return path


@pytest.mark.parametrize("module", sorted(CASES))
def test_a_missing_package_names_the_package_and_the_extra(monkeypatch, tmp_path, module):
    pip, extra, call = CASES[module]
    _hide(monkeypatch, module)
    with pytest.raises(MissingDependencyError) as err:
        call(tmp_path)
    text = str(err.value)
    assert f"{pip!r}" in text and f"motionblur[{extra}]" in text, text
    assert isinstance(err.value, ModuleNotFoundError)  # code that catches the usual error still does
    assert not (tmp_path / "new").exists(), "nothing is written before the check"


@pytest.mark.parametrize("module", ["mitsuba", "flip_evaluator", "matplotlib", "PIL", "tqdm"])
def test_the_demo_checks_every_package_before_it_writes(monkeypatch, tmp_path, capsys, module):
    _hide(monkeypatch, module)
    out = tmp_path / "demo"
    assert main(["demo", "--out", str(out)]) == 1
    err = capsys.readouterr().err
    assert _optional.PACKAGES[module][0] in err and "pip install" in err, err
    assert not out.exists(), "the demo created its folder before finding the package missing"


def test_require_all_lists_every_missing_package_in_one_message(monkeypatch):
    for m in ("mitsuba", "matplotlib"):
        _hide(monkeypatch, m)
    with pytest.raises(MissingDependencyError) as err:
        _optional.require_all(["numpy", "mitsuba", "matplotlib"], "this task")
    text = str(err.value)
    assert "this task needs" in text and "mitsuba" in text and "matplotlib" in text
    assert "motionblur[bench,reference]" in text


def test_a_package_whose_own_dependency_is_missing_keeps_pips_message(monkeypatch):
    monkeypatch.setitem(sys.modules, "numpy.not_a_module", None)
    with pytest.raises(ModuleNotFoundError) as err:
        _optional.require("numpy.not_a_module")
    assert not isinstance(err.value, MissingDependencyError) or "numpy" in str(err.value)


def test_pyrender_under_osmesa_asks_for_a_newer_pyopengl(monkeypatch):
    import OpenGL

    monkeypatch.setenv("PYOPENGL_PLATFORM", "osmesa")
    monkeypatch.setattr(OpenGL, "__version__", "3.1.0")
    with pytest.raises(RuntimeError, match=r"pip install 'pyopengl>=3.1.5'"):
        mb.reference.pyrender(_scene())
    monkeypatch.setattr(OpenGL, "__version__", "3.1.10")
    _optional.require_osmesa_pyopengl()  # the version installed here passes
    monkeypatch.setenv("PYOPENGL_PLATFORM", "egl")
    monkeypatch.setattr(OpenGL, "__version__", "3.1.0")
    _optional.require_osmesa_pyopengl()  # only OSMesa's binding is broken in 3.1.0


def test_present_packages_import_as_usual():
    assert _optional.require("numpy") is np
    assert _optional.missing(["numpy", "trimesh", "surely_not_a_package_here"]) == [
        "surely_not_a_package_here"
    ]
