"""Arrays in memory that the ranks of a node share (``solver.dynamics.node_memory``)."""

import os

import numpy as np
import pytest
import threadpoolctl
from mpi4py import MPI

from solver.dynamics.node_memory import NodeMemory

pytestmark = pytest.mark.mpi


@pytest.mark.parametrize("room", [None, 0], ids=["shared", "no room in /dev/shm"])
def test_every_rank_reads_what_the_writer_wrote(monkeypatch, room):
    """Written by the node's first rank between ``begin`` and ``end``, an array holds the same
    values on every rank of the node, also after it grew and shrank; where the node's shared
    memory has no room, in arrays of each rank's own."""
    if room is not None:
        monkeypatch.setattr(NodeMemory, "_shared_room", lambda self: room)
    memory = NodeMemory(MPI.COMM_WORLD)
    try:
        for n in (3, 50, 20, 400):
            a = memory.get("a", (n, n), np.float32)
            memory.begin()
            if memory.writer:
                a[:] = np.arange(n * n, dtype=np.float32).reshape(n, n) + n
            memory.end()
            assert np.array_equal(a, np.arange(n * n).reshape(n, n) + n)
    finally:
        memory.free()


def test_the_writer_takes_a_thread_per_rank_of_its_node():
    """BLAS (SciPy's, of the factorisations) takes a thread per rank of the node, at most one per
    core; the limit of one per rank (``common.backend``) holds again after it."""
    memory = NodeMemory(MPI.COMM_WORLD)
    cores = len(os.sched_getaffinity(0))

    def threads() -> int:  # the most of any BLAS loaded (SciPy's among them)
        return max(
            i["num_threads"] for i in threadpoolctl.threadpool_info() if i["user_api"] == "blas"
        )

    with memory.threads():
        assert threads() == min(memory.comm.size, cores)
    assert threads() == 1
    memory.free()
