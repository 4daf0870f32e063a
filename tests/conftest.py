"""Shared fixtures, and the project's rule that no test is ever skipped.

The tests are grouped by stage: ``core/`` (the compiled kernels: mesh, contour, volume, raster,
image, shell), ``methods/`` (the rendering methods and the layers they share), ``peers/`` (the
whole chain against pyrender and Mitsuba 3), ``evaluation/`` (the speed-against-error report)
``api/`` (the package, scenes, stubs, array layouts, README, import cycles, packaging),
``interop/`` (trimesh, glTF, pyrender cameras, Mitsuba dictionaries, EXR files) and
``process/`` (fork, spawn and forkserver pools, bare forks, loader workers, Dask clusters and
threads, each against the serial bits, every wait with a timeout). Helpers the
tests share (numpy twins, the pyrender peer, thread-count checks) are in ``_helpers/``.

The markers ``mitsuba`` and ``pyrender`` (see pyproject.toml) name the tests that run a peer, so
``pytest -m "not mitsuba"`` leaves them out on purpose. A peer that cannot run fails: a test
that would be skipped is reported failed instead.
"""

from __future__ import annotations

import numpy as np
import pytest


@pytest.fixture
def rng() -> np.random.Generator:
    """A random generator seeded with 0, the same stream in every test that asks for it."""
    return np.random.default_rng(0)


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item, call):
    outcome = yield
    report = outcome.get_result()
    if report.skipped and not hasattr(report, "wasxfail"):
        reason = report.longrepr[2] if isinstance(report.longrepr, tuple) else str(report.longrepr)
        report.outcome = "failed"
        report.longrepr = f"skipped ({reason}), and this project never skips: make it run or fail"
