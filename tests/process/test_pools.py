"""multiprocessing pools of every start method, started after the parent rendered (issue #26).

The parent renders first, so its thread pool is up: a child made by ``fork`` inherits the pool's
bookkeeping but none of its threads, and used to wait forever for them at its first parallel
call. Every pool must finish (a timeout fails the test instead of stalling it) with the parent's
serial bits.
"""

from __future__ import annotations

import multiprocessing
import os

import pytest
from _helpers import processes as work

import motionblur as mb

TIMEOUT = 120  # seconds; a task takes milliseconds
N = len(work.TASKS)
# Python 3.12+ warns that fork() in a multi-threaded process may deadlock the child: that is
# what these tests prove does not happen here.
pytestmark = pytest.mark.filterwarnings("ignore:.*fork:DeprecationWarning")


@pytest.mark.parametrize("method", ["fork", "spawn", "forkserver"])
def test_a_pool_started_after_the_parent_rendered_gives_the_parents_bits(method):
    want = work.renders()
    shapes = [work.volume_shape(k) for k in range(4)]  # the repro, in the parent first
    with multiprocessing.get_context(method).Pool(2) as pool:
        got = pool.map_async(work.render, range(2 * N)).get(timeout=TIMEOUT)
        got_shapes = pool.map_async(work.volume_shape, range(4)).get(timeout=TIMEOUT)
    assert work.same_bits(got, want + want)
    assert got_shapes == shapes


def test_a_fork_child_builds_its_own_pool_of_the_parents_size(num_threads):
    n = num_threads(3)
    want = work.render(1)
    assert work.pool_threads() >= n
    with multiprocessing.get_context("fork").Pool(2) as pool:
        reports = pool.map_async(work.child_report, [1, 1, 1, 1]).get(timeout=TIMEOUT)
    for pid, count, threads, img in reports:
        assert pid != os.getpid()
        assert count == n  # the child keeps its parent's count ...
        assert threads == n  # ... and runs on threads of its own
        assert work.same_bits([img], [want])


def test_a_pool_initializer_sets_each_workers_count():
    before = mb.get_num_threads()
    want = work.renders()
    with multiprocessing.get_context("fork").Pool(2, initializer=work.set_threads, initargs=(1,)) as pool:
        reports = pool.map_async(work.child_report, range(N)).get(timeout=TIMEOUT)
    assert [r[1] for r in reports] == [1] * N
    assert [r[2] for r in reports] == [1] * N
    assert work.same_bits([r[3] for r in reports], want)
    assert mb.get_num_threads() == before  # the children's counts are their own
