"""Work for the process-model tests (tests/process/): small renders that a child process, a Dask
worker or a thread repeats, importable by module name so that spawn, forkserver and Dask
workers find them. Each task ``k`` renders one (scene, method) of :data:`TASKS`; the tests
compare the child's bits with the serial render of the parent."""

from __future__ import annotations

import os
import pickle
import select
import signal
import threading
import time
import traceback
from pathlib import Path

import numpy as np

import motionblur as mb

W, H = 64, 48
#: (built-in scene, method, options): rigid and deforming scenes, the methods that share the
#: rasterizer, the analytic kernel, the motion volume, the blur shell, the image-space blur and
#: auto's plan.
TASKS = [
    ("cube", "accumulation", {"samples": 8}),
    ("cube", "analytic", {}),
    ("cube", "motion_volume", {}),
    ("bending_arm", "blur_shell", {}),
    ("spinning_propeller", "accumulation", {"samples": 4}),
    ("bending_arm", "analytic", {}),
    ("bending_arm", "opaque_image", {}),
    ("cube", "auto", {}),
]

_SCENES: dict[str, mb.Scene] = {}
_LOCK = threading.Lock()


def scene(name: str) -> mb.Scene:
    """The built-in scene ``name`` at W x H, built once per process."""
    with _LOCK:
        if name not in _SCENES:
            _SCENES[name] = mb.SCENES[name](W, H)
        return _SCENES[name]


def render(k: int) -> np.ndarray:
    """The RGBA image of task ``k`` (modulo the number of tasks)."""
    name, method, options = TASKS[k % len(TASKS)]
    return mb.render(scene(name), method, **options).rgba


def renders(n: int = len(TASKS)) -> list[np.ndarray]:
    """Tasks 0..n-1 rendered here, one after another."""
    return [render(k) for k in range(n)]


def volume_shape(k: int) -> tuple[int, ...]:
    """The issue's repro: a motion volume of a 20480-face sphere in direction k."""
    v, f = mb.meshes.icosphere(5)
    return tuple(mb.motion_volume(mb.Mesh(v, f), [1, 0.1 * k, 0], 2).vertices.shape)


def render_with_pid(k: int) -> tuple[int, np.ndarray]:
    """(this process's pid, task k's image)."""
    return os.getpid(), render(k)


def _comm(task: Path) -> str:
    try:
        return (task / "comm").read_text()
    except (FileNotFoundError, ProcessLookupError):  # the thread ended between listing and reading
        return ""


def _named_workers() -> int:
    return sum(_comm(t).startswith("motionblur-") for t in Path("/proc/self/task").iterdir())


def pool_threads() -> int:
    """How many threads of this process are workers of motionblur's pool (named motionblur-N). A
    worker names itself when it first runs, so on a loaded machine the count is read again until
    it reaches the pool's size (``get_num_threads()``) or 10 s pass."""
    n, deadline = mb.get_num_threads(), time.monotonic() + 10.0
    while _named_workers() < n and time.monotonic() < deadline:
        time.sleep(0.01)
    return _named_workers()


def child_report(k: int) -> tuple[int, int, int, np.ndarray]:
    """(pid, get_num_threads, pool worker threads after the render, task k's image)."""
    img = render(k)
    return os.getpid(), mb.get_num_threads(), pool_threads(), img


def set_threads(n: int) -> None:
    """A pool initializer: n threads in each worker process."""
    mb.set_num_threads(n)


def same_bits(got: list[np.ndarray], want: list[np.ndarray]) -> bool:
    """Every image identical to the bit (NaNs included)."""
    return len(got) == len(want) and all(
        a.dtype == b.dtype and a.shape == b.shape and np.array_equal(a, b, equal_nan=True)
        for a, b in zip(got, want)
    )


class ChildFailed(AssertionError):
    """A forked child raised, died, or did not finish in time."""


def in_fork(fn, *args, timeout: float = 120):
    """``fn(*args)`` run in a child made by a bare ``os.fork()``: the child pickles the result
    into a pipe and leaves with ``os._exit``; the parent reads it before ``timeout`` seconds,
    else kills the child and raises :class:`ChildFailed` (so a hang fails instead of stalling)."""
    r, w = os.pipe()
    pid = os.fork()
    if pid == 0:  # the child: never returns into the caller's stack (pytest, a pool worker)
        code = 1
        try:
            os.close(r)
            try:
                payload = pickle.dumps((True, fn(*args)))
            except BaseException:
                payload = pickle.dumps((False, traceback.format_exc()))
            with os.fdopen(w, "wb") as f:
                f.write(payload)
            code = 0
        finally:
            os._exit(code)
    os.close(w)
    deadline = time.monotonic() + timeout
    chunks = []
    try:
        with os.fdopen(r, "rb", buffering=0) as f:
            while True:
                left = deadline - time.monotonic()
                if left <= 0 or not select.select([f], [], [], left)[0]:
                    raise ChildFailed(f"the forked child {pid} did not finish in {timeout} s")
                chunk = f.read(1 << 20)
                if not chunk:
                    break
                chunks.append(chunk)
        while True:
            done, status = os.waitpid(pid, os.WNOHANG)
            if done:
                break
            if time.monotonic() > deadline:
                raise ChildFailed(f"the forked child {pid} did not exit in {timeout} s")
            time.sleep(0.01)
    except BaseException:
        os.kill(pid, signal.SIGKILL)
        os.waitpid(pid, 0)
        raise
    if os.waitstatus_to_exitcode(status) != 0 or not chunks:
        raise ChildFailed(f"the forked child {pid} exited with status {os.waitstatus_to_exitcode(status)}")
    ok, value = pickle.loads(b"".join(chunks))
    if not ok:
        raise ChildFailed(f"the forked child raised:\n{value}")
    return value


def renders_in_a_grandchild(n: int) -> list[np.ndarray]:
    """Tasks 0..n-1 rendered here, then by a child forked from here (a fork of a fork); the
    grandchild's images, checked against this process's."""
    want = renders(n)
    got = in_fork(renders, n)
    if not same_bits(got, want):
        raise AssertionError("the grandchild's images differ from its parent's")
    return got


def loader_worker(index_queue, result_queue) -> None:
    """A DataLoader-like worker loop: render each index it is given until None."""
    while (k := index_queue.get()) is not None:
        result_queue.put((k, os.getpid(), render(k)))
