"""Keep freed memory in the process between frames (glibc only).

glibc's malloc serves blocks of 128 KiB and more (its threshold grows up to 32 MiB as such
blocks are freed) with fresh ``mmap`` pages and gives them back on ``free``, and it trims the top
of the heap once 128 KiB are free there. A renderer allocates frame-sized buffers every call (the
rasterizer's output, numpy temporaries), so every call would page-fault its buffers afresh
(the README's "Memory and speed" gives what that costs).

:func:`keep_freed_memory` raises both thresholds (blocks up to 64 MiB come from the heap; up to
256 MiB of free heap is kept), so the pages are reused. The package calls it on import unless the
environment sets ``MOTIONBLUR_SYSTEM_MALLOC=1``, or the malloc tunables are set already
(``MALLOC_MMAP_THRESHOLD_`` or ``MALLOC_TRIM_THRESHOLD_``, which then stay the user's). The cost
is memory: a process keeps up to the trim threshold of freed heap instead of returning it.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import os
import sys

#: glibc's mallopt parameters (malloc.h).
_M_TRIM_THRESHOLD = -1
_M_MMAP_THRESHOLD = -3

MMAP_THRESHOLD = 64 << 20
TRIM_THRESHOLD = 256 << 20

#: Whether :func:`keep_freed_memory` changed the thresholds in this process.
applied = False


def keep_freed_memory(mmap_threshold: int = MMAP_THRESHOLD, trim_threshold: int = TRIM_THRESHOLD) -> bool:
    """Raise glibc's mmap and trim thresholds (bytes) for this process; True when applied
    (False on other C libraries or platforms, where nothing changes)."""
    global applied
    if not sys.platform.startswith("linux"):
        return False
    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6")
        mallopt = libc.mallopt
    except (OSError, AttributeError):
        return False
    mallopt.argtypes, mallopt.restype = (ctypes.c_int, ctypes.c_int), ctypes.c_int
    ok = mallopt(_M_MMAP_THRESHOLD, int(mmap_threshold)) == 1
    ok = mallopt(_M_TRIM_THRESHOLD, int(trim_threshold)) == 1 and ok
    applied = applied or ok
    return ok


def _on_import() -> None:
    env = os.environ
    if env.get("MOTIONBLUR_SYSTEM_MALLOC", "") not in ("", "0"):
        return
    if "MALLOC_MMAP_THRESHOLD_" in env or "MALLOC_TRIM_THRESHOLD_" in env:
        return
    keep_freed_memory()


_on_import()
