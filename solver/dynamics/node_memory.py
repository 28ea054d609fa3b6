"""Arrays in memory that the ranks of a node share (MPI shared-memory windows).

Dense work whose result every rank needs whole (the single-precision factors of the contact
points' inner problem, ``solver.dynamics.traction_jacobian``) is done once per node: its first
rank writes the result with a BLAS thread per rank of the node, while the others wait without
spinning and then read the same memory (docs/contact.md, section 6a).
"""

import os
import time
from typing import cast

import numpy as np
import numpy.typing as npt
import threadpoolctl
from mpi4py import MPI

from solver.dynamics.workspace import ROOM

__all__ = ["NodeMemory", "idle_wait"]


def idle_wait(request: MPI.Request, interval: float = 1e-4) -> None:
    """Wait for ``request``, sleeping ``interval`` [s] between tests (MPI's blocking calls poll,
    which keeps a core busy)."""
    while not request.Test():
        time.sleep(interval)


class NodeMemory:
    """Named arrays in memory shared by the ranks of ``comm`` on one node, written by the node's
    first rank (``writer``). Every method is collective over the node's ranks."""

    def __init__(self, comm: MPI.Comm):
        #: the ranks of this node
        self.comm = cast(MPI.Intracomm, comm.Split_type(MPI.COMM_TYPE_SHARED))
        self.writer = self.comm.rank == 0
        self._windows: dict[str, tuple[MPI.Win, npt.NDArray]] = {}

    def get(self, name: str, shape: tuple[int, ...], dtype: type) -> npt.NDArray:
        """An uninitialised C-order array of this shape, in the memory of the last one of its
        name where it fits."""
        size = int(np.prod(shape))
        kept = self._windows.get(name)
        if kept is None or kept[1].size < size or kept[1].dtype != dtype:
            if kept is not None:
                kept[0].Free()
            length = int(ROOM * size)
            item = np.dtype(dtype).itemsize
            window = MPI.Win.Allocate_shared(
                length * item if self.writer else 0, item, comm=self.comm
            )
            memory, _ = window.Shared_query(0)
            kept = self._windows[name] = (window, np.ndarray(length, dtype, buffer=memory))
        return kept[1][:size].reshape(shape)

    def threads(self) -> threadpoolctl.threadpool_limits:
        """A context in which BLAS takes a thread per rank of the node, at most one per core
        that this process may run on (for the writer, while the others wait)."""
        cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else 1
        return threadpoolctl.threadpool_limits(max(1, min(self.comm.size, cores)), "blas")

    def begin(self) -> None:
        """Before the writer writes: every rank is done reading the arrays."""
        if self.comm.size > 1:
            self.comm.Barrier()

    def end(self) -> None:
        """After the writer wrote: the others, waiting without spinning, may read."""
        if self.comm.size > 1:
            idle_wait(self.comm.Ibarrier())

    def free(self) -> None:
        """Release the windows (the arrays must no longer be used)."""
        for window, _ in self._windows.values():
            window.Free()
        self._windows.clear()
