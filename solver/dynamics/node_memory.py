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
        self._splits = comm.size > 1  # a communicator of its own, freed by ``free``
        node = comm.Split_type(MPI.COMM_TYPE_SHARED) if self._splits else comm
        self.comm = cast(MPI.Intracomm, node)  #: the ranks of this node
        self.writer = self.comm.rank == 0
        self._windows: dict[str, tuple[MPI.Win | None, npt.NDArray]] = {}
        self._private: list[npt.NDArray] = []  # arrays of each rank's own to broadcast at end

    def get(self, name: str, shape: tuple[int, ...], dtype: type) -> npt.NDArray:
        """An uninitialised C-order array of this shape, in the memory of the last one of its
        name where it fits. Where the node's shared memory has no room for it (``/dev/shm``,
        where MPI implementations keep it, holds less than twice its size: Docker's default
        is 64 MB), it is each rank's own and :meth:`end` broadcasts it from the writer."""
        size = int(np.prod(shape))
        if size == 0:  # no window: MPI implementations differ on windows of no memory
            return np.empty(shape, dtype)
        kept = self._windows.get(name)
        if kept is None or kept[1].size < size or kept[1].dtype != dtype:
            if kept is not None and kept[0] is not None:
                kept[0].Free()
            length = int(ROOM * size)
            kept = self._windows[name] = self._allocate(length, np.dtype(dtype))
        array = kept[1][:size].reshape(shape)
        if kept[0] is None and self.comm.size > 1:
            self._private.append(array)
        return array

    def _allocate(self, length: int, dtype: np.dtype) -> tuple[MPI.Win | None, npt.NDArray]:
        """A window of ``length`` entries shared by the node's ranks, or (None, an array of this
        rank's own) where the node's shared memory has no room for it."""
        room = self._shared_room() if self.writer else None
        if self.comm.size == 1 or not self.comm.bcast(
            room is None or room >= 2 * length * dtype.itemsize
        ):
            return None, np.empty(length, dtype)
        window = MPI.Win.Allocate_shared(
            length * dtype.itemsize if self.writer else 0, dtype.itemsize, comm=self.comm
        )
        memory, _ = window.Shared_query(0)
        return window, np.ndarray(length, dtype, buffer=memory)

    def _shared_room(self) -> int | None:
        """Free bytes of ``/dev/shm`` (None where there is none)."""
        try:
            stat = os.statvfs("/dev/shm")
        except OSError:
            return None
        return stat.f_bavail * stat.f_frsize

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
        """After the writer wrote: the others, waiting without spinning, may read (the arrays
        of each rank's own got since the last call are broadcast from the writer)."""
        if self.comm.size > 1:
            idle_wait(self.comm.Ibarrier())
            for array in self._private:
                self.comm.Bcast(array)
        self._private.clear()

    def free(self) -> None:
        """Release the windows and the node's communicator (the object is not used after it)."""
        for window, _ in self._windows.values():
            if window is not None:
                window.Free()
        self._windows.clear()
        if self._splits:
            self.comm.Free()
            self._splits = False
