"""The pyrender peer reads PYOPENGL_PLATFORM and never writes it: with neither the variable nor a
display it raises a RuntimeError naming the variable, before anything imports OpenGL."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

CODE = """
import os, motionblur as mb
before = dict(os.environ)
scene = mb.SCENES["cube"](width=32, height=24)
try:
    mb.reference.pyrender(scene)
    print("rendered")
except RuntimeError as e:
    print("RuntimeError:", e)
print("environment untouched:", dict(os.environ) == before)
"""


def _run(**env) -> str:
    e = {k: v for k, v in os.environ.items() if k not in ("PYOPENGL_PLATFORM", "DISPLAY")}
    e.update(env)
    r = subprocess.run([sys.executable, "-c", CODE], env=e, capture_output=True, text=True, timeout=300)
    return r.stdout + r.stderr


@pytest.mark.pyrender
def test_without_a_platform_or_display_it_names_the_variable_and_writes_nothing():
    out = _run()
    assert "RuntimeError: reference.pyrender: no GL platform: set PYOPENGL_PLATFORM=osmesa" in out, out
    assert "environment untouched: True" in out, out


@pytest.mark.pyrender
def test_with_osmesa_it_renders_and_writes_nothing():
    out = _run(PYOPENGL_PLATFORM="osmesa")
    assert "rendered" in out and "environment untouched: True" in out, out
