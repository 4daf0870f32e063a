"""Keep freed memory in the process between frames (glibc only), when the caller asks.

glibc's malloc serves blocks of 128 KiB and more (its threshold grows up to 32 MiB as such
blocks are freed) with fresh ``mmap`` pages and gives them back on ``free``, and it trims the top
of the heap once 128 KiB are free there. A renderer allocates frame-sized buffers every call (the
rasterizer's output, numpy temporaries), so every call may page-fault its buffers afresh.

[`tune_malloc`][motionblur._malloc.tune_malloc] raises both thresholds (blocks up to 64 MiB come from the heap; up to 256 MiB
of free heap is kept), so the pages are reused. Importing the package changes nothing: this is
a process-wide setting, and the process is the caller's. The cost is memory: the process keeps
up to the trim threshold of freed heap instead of returning it.
"""

from __future__ import annotations

import sys

__all__ = ["tune_malloc"]

#: glibc's mallopt parameters (malloc.h).
_M_TRIM_THRESHOLD = -1
_M_MMAP_THRESHOLD = -3

MMAP_THRESHOLD = 64 << 20
TRIM_THRESHOLD = 256 << 20

#: Whether [`tune_malloc`][motionblur._malloc.tune_malloc] changed the thresholds in this process.
applied = False


def tune_malloc(mmap_threshold: int = MMAP_THRESHOLD, trim_threshold: int = TRIM_THRESHOLD) -> bool:
    """Raise glibc's malloc thresholds for the whole process: blocks up to ``mmap_threshold``
    bytes (default 64 MiB) come from the heap instead of fresh ``mmap`` pages, and up to
    ``trim_threshold`` bytes (default 256 MiB) of freed heap are kept for reuse instead of being
    returned to the system. A real-time loop that renders large frames then reuses its buffers'
    pages instead of page-faulting them afresh every frame; the process keeps that much more
    memory. Returns True when applied, False on other C libraries or platforms (nothing
    changes). glibc's own ``MALLOC_MMAP_THRESHOLD_`` / ``MALLOC_TRIM_THRESHOLD_`` environment
    variables do the same without code."""
    global applied
    for name, v in (("mmap_threshold", mmap_threshold), ("trim_threshold", trim_threshold)):
        if isinstance(v, bool) or not isinstance(v, int) or not 0 <= v <= 2**31 - 1:
            raise ValueError(f"{name}: expected an int of bytes in [0, 2**31 - 1], got {v!r}")
    if not sys.platform.startswith("linux"):
        return False
    import ctypes

    try:
        mallopt = ctypes.CDLL("libc.so.6").mallopt
    except (OSError, AttributeError):
        return False
    mallopt.argtypes, mallopt.restype = (ctypes.c_int, ctypes.c_int), ctypes.c_int
    ok = mallopt(_M_MMAP_THRESHOLD, int(mmap_threshold)) == 1
    ok = mallopt(_M_TRIM_THRESHOLD, int(trim_threshold)) == 1 and ok
    applied = applied or ok
    return ok


#: The former name (0.1), kept for code that called it.
keep_freed_memory = tune_malloc
