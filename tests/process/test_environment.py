"""``MOTIONBLUR_NUM_THREADS`` in a fresh interpreter: read once at the first parallel call (or
``get_num_threads``), ahead of ``RAYON_NUM_THREADS``, overridden by ``set_num_threads``; bad
values raise ``ValueError`` naming the variable; every count renders the same bits."""

from __future__ import annotations

import hashlib
import os
import subprocess
import sys
from pathlib import Path

import pytest
from _helpers import processes as work

TESTS = str(Path(__file__).resolve().parents[1])
DIGEST = """
import hashlib
import motionblur as mb
from _helpers import processes as work
h = hashlib.sha256()
for img in work.renders():
    h.update(img.tobytes())
print(mb.get_num_threads(), work.pool_threads(), h.hexdigest())
"""


def _run(script: str, **env: str) -> str:
    clean = {k: v for k, v in os.environ.items() if k not in ("MOTIONBLUR_NUM_THREADS", "RAYON_NUM_THREADS")}
    path = os.pathsep.join([TESTS, *filter(None, [os.environ.get("PYTHONPATH")])])
    r = subprocess.run(
        [sys.executable, "-c", script],
        env={**clean, "PYTHONPATH": path, **env},
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert r.returncode == 0, r.stderr
    return r.stdout.strip()


def _digest() -> str:
    h = hashlib.sha256()
    for img in work.renders():
        h.update(img.tobytes())
    return h.hexdigest()


@pytest.mark.parametrize("n", [1, 2, 3])
def test_the_variable_sets_the_count_and_the_bits_stay(n):
    count, threads, digest = _run(DIGEST, MOTIONBLUR_NUM_THREADS=str(n)).split()
    assert (int(count), int(threads)) == (n, n)
    assert digest == _digest()


def test_it_comes_before_rayons_variable_and_the_default():
    assert _run(DIGEST, MOTIONBLUR_NUM_THREADS="2", RAYON_NUM_THREADS="3").split()[:2] == ["2", "2"]
    assert _run(DIGEST, RAYON_NUM_THREADS="3").split()[:2] == ["3", "3"]
    count, threads, _ = _run(DIGEST).split()  # the cores this process may use
    assert count == threads and 1 <= int(count) <= len(os.sched_getaffinity(0))
    assert _run(DIGEST, MOTIONBLUR_NUM_THREADS=" ").split()[0] == count  # blank: as if unset


def test_it_is_read_at_first_use_not_at_import():
    script = """
import os
import motionblur as mb
os.environ["MOTIONBLUR_NUM_THREADS"] = "3"      # after the import, before the first use
mb.Mesh(*mb.meshes.icosphere(2)).vertex_normals()
first = mb.get_num_threads()
os.environ["MOTIONBLUR_NUM_THREADS"] = "1"      # after the first use: not read again
print(first, mb.get_num_threads())
"""
    assert _run(script, MOTIONBLUR_NUM_THREADS="2") == "3 3"


def test_set_num_threads_overrides_it():
    script = "import motionblur as mb; print(mb.set_num_threads(1), mb.get_num_threads())"
    assert _run(script, MOTIONBLUR_NUM_THREADS="3") == "3 1"


@pytest.mark.parametrize("bad", ["0", "-1", "abc", "2.5", "1e3", "1025", "99999999999999999999999"])
def test_bad_values_raise_naming_the_variable(bad):
    script = """
import motionblur as mb
errors = []
for call in (mb.get_num_threads, lambda: mb.render(mb.SCENES["cube"](32, 24), "accumulation")):
    try:
        call()
    except ValueError as e:
        errors.append(str(e))
mb.set_num_threads(2)  # a valid count set in code replaces it
frame = mb.render(mb.SCENES["cube"](32, 24), "accumulation")
print(len(errors), errors[0] == errors[-1], mb.get_num_threads(), frame.rgba.shape)
print(errors[0])
"""
    summary, message = _run(script, MOTIONBLUR_NUM_THREADS=bad).splitlines()
    assert summary == "2 True 2 (24, 32, 4)"
    assert (
        message == f'MOTIONBLUR_NUM_THREADS: expected a whole number of threads from 1 to 1024, got "{bad}"'
    )
