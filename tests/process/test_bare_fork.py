"""A bare ``os.fork()`` after the parent rendered: the child renders on a pool of its own and
sends its arrays back through a pipe, bit-identical to the parent's serial render (issue #26).
Each child is killed and the test failed after a timeout, so a hang cannot stall the suite."""

from __future__ import annotations

import os

import numpy as np
import pytest
from _helpers import processes as work

import motionblur as mb

pytestmark = pytest.mark.filterwarnings("ignore:.*fork:DeprecationWarning")


def test_a_forked_child_renders_the_parents_bits():
    want = work.renders()
    got = work.in_fork(work.renders)
    assert work.same_bits(got, want)


def test_the_child_runs_its_own_pool_at_the_parents_count(num_threads):
    n = num_threads(3)
    want = work.render(0)
    pid, count, threads, img = work.in_fork(work.child_report, 0)
    assert pid != os.getpid() and count == n and threads == n
    assert work.same_bits([img], [want])


def test_a_grandchild_renders_too():
    want = work.renders(3)
    got = work.in_fork(work.renders_in_a_grandchild, 3)
    assert work.same_bits(got, want)


def test_the_child_may_change_its_count_and_the_parent_keeps_its_own(num_threads):
    num_threads(2)
    want = work.renders()

    def child():
        old = mb.set_num_threads(1)
        one = work.renders()
        mb.set_num_threads(3)
        three = work.renders()
        return old, one, three, work.pool_threads()

    old, one, three, threads = work.in_fork(child)
    assert old == 2 and threads == 3
    assert work.same_bits(one, want) and work.same_bits(three, want)
    assert mb.get_num_threads() == 2


def test_every_kind_of_kernel_in_the_child():
    """Beyond rendering: mesh queries, contour edges, tables, spin volumes, the silhouette of
    motion and the image filters, each called in the parent first and then in the child."""

    def sweep():
        v, f = mb.meshes.icosphere(4)
        mesh = mb.Mesh(v, f)
        table = mb.ContourTable(mesh, 8, seed=1)
        img = work.render(0)
        out = [
            mesh.vertex_normals(),
            mesh.edges(),
            mb.contour_edges(mesh, [1, 0.2, 0]),
            mb.spin_volume(mesh, [0, 1, 0], 0.5).vertices,
            table.lookup([1, 0.5, 0])[1],
            mb.image.box_blur(img, (1.0, 0.3), 5.0),
            mb.image.glow(img[..., 3], (1.0, 0.3), 4.0),
            mb.image.pyramid_blur(img, 2),
        ]
        return [np.asarray(a) for a in out]

    want = sweep()
    got = work.in_fork(sweep)
    assert work.same_bits(got, want)
