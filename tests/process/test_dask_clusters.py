"""Dask ``LocalCluster``s after the parent rendered: worker processes (started by spawn, Dask's
default, and by fork) and worker threads in this process render the parent's bits."""

from __future__ import annotations

import os

import dask
import distributed
import pytest
from _helpers import processes as work

TIMEOUT = 120
pytestmark = [pytest.mark.dask, pytest.mark.filterwarnings("ignore:.*fork:DeprecationWarning")]

CLUSTERS = {
    "spawned-processes": ({"n_workers": 2, "threads_per_worker": 1, "processes": True}, "spawn"),
    "forked-processes": ({"n_workers": 2, "threads_per_worker": 1, "processes": True}, "fork"),
    "threads": ({"n_workers": 1, "threads_per_worker": 4, "processes": False}, "spawn"),
}


@pytest.mark.parametrize("kind", CLUSTERS)
def test_a_local_cluster_renders_the_parents_bits(kind):
    kwargs, method = CLUSTERS[kind]
    want = work.renders()
    n = len(want)
    with dask.config.set({"distributed.worker.multiprocessing-method": method}):
        with distributed.LocalCluster(dashboard_address=None, **kwargs) as cluster:
            with distributed.Client(cluster) as client:
                futures = client.map(work.render_with_pid, range(2 * n), pure=False)
                distributed.wait(futures, timeout=TIMEOUT)
                results = client.gather(futures)
    pids = {pid for pid, _ in results}
    if kwargs["processes"]:
        assert os.getpid() not in pids
    else:
        assert pids == {os.getpid()}
    assert work.same_bits([img for _, img in results], want + want)
