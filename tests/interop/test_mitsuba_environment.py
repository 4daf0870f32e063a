"""Mitsuba's first use reads DRJIT_LIBLLVM_PATH and never writes it; an llvm variant that cannot
load LLVM raises a RuntimeError that says to set the variable."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

CODE = """
import os, mitsuba as mi
from motionblur.interop import mitsuba as m
before = dict(os.environ)
variant = m.mitsuba_variant()
try:
    m.set_variant(mi, variant)
    print(variant, "loaded")
except RuntimeError as e:
    print(variant, "RuntimeError:", e)
print("environment untouched:", dict(os.environ) == before)
"""


def _run(**env) -> str:
    e = {k: v for k, v in os.environ.items() if k != "DRJIT_LIBLLVM_PATH"}
    e.update(env)
    return subprocess.run(
        [sys.executable, "-c", CODE], env=e, capture_output=True, text=True, timeout=300
    ).stdout


@pytest.mark.mitsuba
def test_a_library_that_cannot_load_names_the_variable_and_nothing_is_written():
    out = _run(DRJIT_LIBLLVM_PATH="/etc/hostname")  # exists, is no libLLVM
    assert "llvm_ad_rgb RuntimeError" in out and "set DRJIT_LIBLLVM_PATH" in out, out
    assert "environment untouched: True" in out, out


@pytest.mark.mitsuba
def test_without_the_variable_the_environment_stays_unset():
    out = _run()
    assert "environment untouched: True" in out, out
    assert ("loaded" in out) or ("set DRJIT_LIBLLVM_PATH" in out), out
