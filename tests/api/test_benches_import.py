"""Every benchmark script loads: ``make bench`` runs them all and stops at the first failure, and
it is not part of ``make test``, so a moved helper (bench_shell imported tests/_shell_twin.py
after the house move put it in tests/_helpers/) would break the bench unnoticed.

Each script is loaded under another name than ``__main__`` (its imports and definitions run,
its measurements do not) and must define ``main``."""

from __future__ import annotations

import runpy
from pathlib import Path

import pytest

BENCHES = sorted((Path(__file__).resolve().parents[2] / "benches").glob("bench_*.py"))


def test_there_are_benchmarks():
    assert len(BENCHES) >= 8, BENCHES


@pytest.mark.parametrize("path", BENCHES, ids=lambda p: p.stem)
def test_the_benchmark_loads(path):
    names = runpy.run_path(str(path), run_name="bench_loaded")
    assert callable(names.get("main")), f"{path.name}: no main()"
