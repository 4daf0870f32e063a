"""glibc's malloc thresholds are the process's: importing the package leaves them alone, and
motionblur.tune_malloc() raises them when the caller asks."""

from __future__ import annotations

import os
import platform
import subprocess
import sys

import pytest


def _run(code: str) -> str:
    e = {k: v for k, v in os.environ.items() if not k.startswith("MALLOC_")}
    out = subprocess.run([sys.executable, "-c", code], env=e, capture_output=True, text=True, check=True)
    return out.stdout.strip()


def test_import_changes_nothing_and_tune_malloc_is_an_explicit_opt_in():
    glibc = sys.platform.startswith("linux") and platform.libc_ver()[0] == "glibc"
    code = (
        "import sys, motionblur as mb; print('motionblur._malloc' in sys.modules); "
        "from motionblur import _malloc; print(_malloc.applied); print(mb.tune_malloc()); print(_malloc.applied)"
    )
    assert _run(code).split() == ["False", "False", str(glibc), str(glibc)]


def test_tune_malloc_checks_its_arguments():
    import motionblur as mb

    for bad in (-1, 2**31, 1.5, True):
        with pytest.raises(ValueError, match="mmap_threshold"):
            mb.tune_malloc(mmap_threshold=bad)
