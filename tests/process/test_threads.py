"""Threads and thread counts: many Python threads rendering shared scenes at once, the count
changed while they render, every count giving the same bits, and the arguments checked."""

from __future__ import annotations

import threading
from concurrent.futures import ThreadPoolExecutor

import pytest
from _helpers import processes as work

import motionblur as mb

TIMEOUT = 120


def test_many_threads_rendering_shared_scenes_give_the_serial_bits():
    want = work.renders()
    n = len(want)
    with ThreadPoolExecutor(8) as ex:
        got = list(ex.map(work.render, range(4 * n), timeout=TIMEOUT))
    assert work.same_bits(got, want * 4)


def test_changing_the_count_while_threads_render(num_threads):
    want = work.renders()
    n = len(want)
    stop = threading.Event()

    def toggle():
        k = 0
        while not stop.is_set():
            mb.set_num_threads(1 + k % 3)
            k += 1

    t = threading.Thread(target=toggle)
    t.start()
    try:
        with ThreadPoolExecutor(4) as ex:
            got = list(ex.map(work.render, range(3 * n), timeout=TIMEOUT))
    finally:
        stop.set()
        t.join(TIMEOUT)
    assert work.same_bits(got, want * 3)


@pytest.mark.parametrize("n", [1, 2, 3, 5])
def test_every_count_gives_the_same_bits(num_threads, n):
    num_threads(2)
    want = work.renders()
    assert mb.set_num_threads(n) == 2
    assert mb.get_num_threads() == n
    assert work.same_bits(work.renders(), want)
    assert mb.threads.get_num_threads() == n


def test_the_pool_has_the_count_set(num_threads):
    num_threads(3)
    work.render(0)
    assert work.pool_threads() >= 3  # the old pool's threads may still be leaving


@pytest.mark.parametrize(
    "bad, error, text",
    [
        (0, ValueError, "n: the number of threads must be from 1 to 1024, got 0"),
        (-2, ValueError, "n: the number of threads must be from 1 to 1024, got -2"),
        (1025, ValueError, "got 1025"),
        (10**30, ValueError, "got 1000000000000000000000000000000"),
        (2.0, TypeError, "n: expected an integer number of threads, got float"),
        ("2", TypeError, "got str"),
        (True, TypeError, "got bool"),
        (None, TypeError, "got NoneType"),
    ],
)
def test_bad_counts_are_refused_naming_n(num_threads, bad, error, text):
    before = num_threads(2)
    with pytest.raises(error, match="^n: ") as e:
        mb.set_num_threads(bad)
    assert text in str(e.value)
    assert mb.get_num_threads() == before


def test_numpy_integers_are_counts(num_threads):
    import numpy as np

    num_threads(2)
    assert mb.set_num_threads(np.int64(1)) == 2
    assert mb.get_num_threads() == 1
    assert mb.threads.MAX_THREADS == 1024
