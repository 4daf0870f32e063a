"""Fixtures of the process-model tests: a thread count set for one test and restored after."""

from __future__ import annotations

import pytest

import motionblur as mb


@pytest.fixture
def num_threads():
    """``num_threads(n)`` sets this process's count for the test; the old count is restored."""
    old = mb.get_num_threads()

    def set_to(n: int) -> int:
        mb.set_num_threads(n)
        return n

    yield set_to
    mb.set_num_threads(old)
