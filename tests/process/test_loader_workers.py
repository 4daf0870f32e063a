"""A DataLoader-like worker loop: persistent workers made by ``fork`` after the parent rendered
take indices from a queue, render in the child and return numpy arrays through a
``multiprocessing`` queue, across two epochs with the parent rendering in between (what a
PyTorch ``DataLoader(num_workers=2)`` does on Linux). Bit-identical to the parent's serial
render; every wait has a timeout."""

from __future__ import annotations

import multiprocessing
import os

import pytest
from _helpers import processes as work

TIMEOUT = 120
pytestmark = pytest.mark.filterwarnings("ignore:.*fork:DeprecationWarning")


def test_forked_loader_workers_return_the_parents_images():
    want = work.renders()
    n = len(want)
    ctx = multiprocessing.get_context("fork")
    index_q, result_q = ctx.Queue(), ctx.Queue()
    workers = [
        ctx.Process(target=work.loader_worker, args=(index_q, result_q), daemon=True) for _ in range(2)
    ]
    for p in workers:
        p.start()
    try:
        for epoch in range(2):
            for k in range(n):
                index_q.put(k)
            got = {}
            pids = set()
            for _ in range(n):
                k, pid, img = result_q.get(timeout=TIMEOUT)
                got[k] = img
                pids.add(pid)
            assert pids and os.getpid() not in pids
            assert work.same_bits([got[k] for k in range(n)], want), f"epoch {epoch}"
            assert work.same_bits(work.renders(), want)  # the parent renders between epochs
        for _ in workers:
            index_q.put(None)
        for p in workers:
            p.join(TIMEOUT)
            assert p.exitcode == 0
    finally:
        for p in workers:
            if p.is_alive():
                p.kill()
                p.join()
