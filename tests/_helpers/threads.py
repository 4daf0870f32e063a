"""Shared checks: results independent of the thread count, and the GIL released while Rust runs."""

from __future__ import annotations

import os
import subprocess
import sys
import threading
import time
from pathlib import Path


def digests(script: str, threads=(1, 2, 3), timeout: float = 300) -> list[str]:
    """The stdout of ``python -c script`` (a hex digest) under each MOTIONBLUR_NUM_THREADS value."""
    out = []
    tests = str(Path(__file__).resolve().parents[1])  # the script imports the helpers as the tests do
    path = os.pathsep.join([tests, *filter(None, [os.environ.get("PYTHONPATH")])])
    for n in threads:
        env = dict(os.environ, MOTIONBLUR_NUM_THREADS=str(n), PYTHONPATH=path)
        r = subprocess.run(
            [sys.executable, "-c", script], env=env, capture_output=True, text=True, timeout=timeout
        )
        assert r.returncode == 0, r.stderr
        out.append(r.stdout.strip())
    return out


def ticks_during(call, repeat: int = 3) -> int:
    """How often a Python thread ticking every 0.5 ms ran while ``call()`` ran ``repeat`` times
    in this thread: with the GIL held it could tick only between the calls."""
    ticks = []
    stop = threading.Event()

    def ticker():
        while not stop.is_set():
            ticks.append(time.perf_counter())
            time.sleep(0.0005)

    t = threading.Thread(target=ticker)
    t.start()
    time.sleep(0.01)
    n0 = len(ticks)
    for _ in range(repeat):
        call()
    stop.set()
    t.join()
    return len(ticks) - n0
