"""The package raises glibc's malloc thresholds on import (motionblur._malloc), unless told not to."""

from __future__ import annotations

import os
import platform
import subprocess
import sys

CODE = "import motionblur, motionblur._malloc as m; print(m.applied)"


def _run(**env):
    e = {k: v for k, v in os.environ.items() if not k.startswith(("MALLOC_", "MOTIONBLUR_SYSTEM_MALLOC"))}
    e.update(env)
    out = subprocess.run([sys.executable, "-c", CODE], env=e, capture_output=True, text=True, check=True)
    return out.stdout.strip()


def test_applied_on_import_and_opt_out():
    """On glibc the thresholds are raised on import unless told not to; elsewhere nothing changes."""
    glibc = str(platform.libc_ver()[0] == "glibc")
    assert _run() == glibc
    assert _run(MOTIONBLUR_SYSTEM_MALLOC="1") == "False"
    # the user's own glibc tunables win
    assert _run(MALLOC_MMAP_THRESHOLD_="131072") == "False"
    assert _run(MOTIONBLUR_SYSTEM_MALLOC="0") == glibc


def test_keep_freed_memory_reports_whether_it_applied():
    from motionblur import _malloc

    glibc = sys.platform.startswith("linux") and platform.libc_ver()[0] == "glibc"
    assert _malloc.keep_freed_memory() is glibc
