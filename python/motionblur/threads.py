"""The threads the parallel kernels run on (docs: guide/conventions.md, "Sharing").

Every parallel kernel (rendering, contour edges, motion volumes, blur shells, image blurs, even
building a [`Mesh`][motionblur.Mesh]) runs in one thread pool of the process, built on first use
and built afresh in a child process made by ``fork`` (a ``multiprocessing`` fork pool, a
PyTorch ``DataLoader`` worker, ``os.fork()``), so a child renders in parallel too and gives the
parent's bits.

The number of threads, in order:

1. [`set_num_threads`][motionblur.threads.set_num_threads] (in this process; a forked child keeps its parent's count);
2. the environment variable ``MOTIONBLUR_NUM_THREADS``, read once, at the first parallel call
   or [`get_num_threads`][motionblur.threads.get_num_threads] of the process (a value that is not a whole number in
   1 to ``MAX_THREADS`` raises ``ValueError`` naming it there);
3. ``RAYON_NUM_THREADS``, as rayon reads it;
4. the cores this process may use.

Every result is the same bits whatever the count: it sets speed only. Several processes on one
machine (a process pool, Dask workers) each run their own pool, so give each
``cores // processes`` threads, e.g. with ``MOTIONBLUR_NUM_THREADS`` in their environment or
``set_num_threads`` in a pool initializer.
"""

from __future__ import annotations

from . import _core

__all__ = ["get_num_threads", "set_num_threads", "MAX_THREADS", "NUM_THREADS_ENV"]

#: The most threads [`set_num_threads`][motionblur.threads.set_num_threads] accepts.
MAX_THREADS: int = _core.MAX_THREADS
#: The environment variable read for the thread count at first use.
NUM_THREADS_ENV: str = "MOTIONBLUR_NUM_THREADS"


def get_num_threads() -> int:
    """The number of threads the parallel kernels of this process run on.

    Returns:
        int: the count set by [`set_num_threads`][motionblur.threads.set_num_threads], else ``MOTIONBLUR_NUM_THREADS`` (read by
        the first call of the process), else ``RAYON_NUM_THREADS``, else the usable cores.

    Raises:
        ValueError: ``MOTIONBLUR_NUM_THREADS`` is set to anything but a whole number in
            1 to ``MAX_THREADS`` (and [`set_num_threads`][motionblur.threads.set_num_threads] was not called).
    """
    return int(_core.get_num_threads())


def set_num_threads(n: int) -> int:
    """Run the parallel kernels of this process on ``n`` threads from the next call on.

    Args:
        n (int): the number of threads, ``1 <= n <= MAX_THREADS`` (1024). Results are the same
            bits for every ``n``.

    Returns:
        int: the previous count, so that ``old = set_num_threads(1)`` ... ``set_num_threads(old)``
        restores it.

    Raises:
        TypeError: ``n`` is not an integer (a float, a bool, a string).
        ValueError: ``n`` is not from 1 to ``MAX_THREADS``.
    """
    if isinstance(n, bool) or not hasattr(n, "__index__"):
        raise TypeError(f"n: expected an integer number of threads, got {type(n).__name__}")
    count = int(n.__index__())
    if not 1 <= count <= MAX_THREADS:
        raise ValueError(f"n: the number of threads must be from 1 to {MAX_THREADS}, got {count}")
    return int(_core.set_num_threads(count))
