"""Contiguous shares of n entries (or rows) among the ranks of a communicator: dense work that
every rank holds the data of (products with a dense matrix, columns of a solve) is computed
share by share, each rank its own entries of the result, and joined on every rank
(``solver.dynamics.traction_jacobian``)."""

import numpy as np
import numpy.typing as npt
from mpi4py import MPI

__all__ = ["Shares"]


class Shares:
    """Entries [start, stop) of n are this rank's; rank r holds n r / size to n (r + 1) / size."""

    def __init__(self, comm: MPI.Comm, n: int):
        self.comm, self.n = comm, n
        self.bounds = np.array([n * r // comm.size for r in range(comm.size + 1)])
        self.start, self.stop = (int(b) for b in self.bounds[comm.rank : comm.rank + 2])
        self.part = slice(self.start, self.stop)

    def gather(self, part: npt.NDArray) -> npt.NDArray:
        """The n entries, on every rank, from each rank's share (float64): ``part`` holds this
        rank's entries along its first axis (entries of a vector, or rows of the same shape)."""
        part = np.ascontiguousarray(part, dtype=np.float64)
        if self.comm.size == 1:
            return part
        row = int(np.prod(part.shape[1:]))
        out = np.empty((self.n, *part.shape[1:]))
        counts = row * np.diff(self.bounds)
        self.comm.Allgatherv(part, [out, (counts, row * self.bounds[:-1])])
        return out
