"""PETSc vectors and matrices from per-point contributions of the contact terms.

The contact residual and Jacobian are sums over slave quadrature points of small dense
blocks on each point's dofs (slave cell and paired master facet). Here: the grouped sums
of point products (one batched product per group of points sharing their dofs), the
vector assembly, and the COO assembly of matrices whose sparsity pattern is cached by
name and reused while the dof blocks stay the same. Global (unrolled) dof indices, owned
rows; PETSc sums duplicate entries, also across ranks.
"""

import itertools

import numpy as np
import numpy.typing as npt
from mpi4py import MPI
from petsc4py import PETSc


__all__ = ["PointMatrices", "assemble_point_vector", "grouped_products"]

_pattern_tags = itertools.count()  # unique tags of the cached matrices' sparsity patterns


def grouped_products(key: npt.NDArray, L: npt.NDArray, R: npt.NDArray):
    """Sum of L_q^T R_q over the points q of each group of equal ``key``.

    L (q, k, m), R (q, k, n). Returns the index of each group's first point and the sums
    (groups, m, n), groups in increasing key order: the points of a group are stacked into
    one (k x group size) product (groups padded with zero rows to the largest).
    """
    order = np.argsort(key, kind="stable")
    sorted_key = key[order]
    starts = np.flatnonzero(np.r_[True, sorted_key[1:] != sorted_key[:-1]])
    counts = np.diff(np.r_[starts, len(key)])
    group = np.repeat(np.arange(len(starts)), counts)
    position = np.arange(len(key)) - starts[group]
    shape = (len(starts), counts.max(), L.shape[1])
    Lp = np.zeros(shape + L.shape[2:])
    Rp = np.zeros(shape + R.shape[2:])
    Lp[group, position] = L[order]
    Rp[group, position] = R[order]
    K = Lp.reshape(len(starts), -1, L.shape[2]).transpose(0, 2, 1) @ Rp.reshape(
        len(starts), -1, R.shape[2]
    )
    return order[starts], K


def assemble_point_vector(
    b: PETSc.Vec, size: int, rows: list[npt.NDArray], vals: list[npt.NDArray]
) -> None:
    """Fill the ghosted PETSc vector ``b`` (``dolfinx.fem.petsc.create_vector`` of the space)
    with the values ``vals`` summed into the global rows ``rows`` (lists of arrays, one pair per
    chunk of points); ``size``: global length."""
    with b.localForm() as loc:
        loc.set(0.0)
    if rows:
        rows, vals = np.concatenate(rows), np.concatenate(vals)
        touched = np.flatnonzero(np.bincount(rows, minlength=size))
        b.setValues(
            touched.astype(PETSc.IntType),
            np.bincount(rows, vals, minlength=size)[touched],
            addv=PETSc.InsertMode.ADD_VALUES,
        )
    b.assemblyBegin()
    b.assemblyEnd()


class PointMatrices:
    """Square AIJ matrices (block size 3) of local/global ``sizes`` assembled from dense blocks.

    ``assemble(blocks, vals, cache)``: ``blocks`` is a list of (groups, d) arrays of global
    dofs, each group's d x d block filled from ``vals`` (all blocks' values, row-major, in
    order). With ``cache`` the matrix and its COO pattern are kept under that name and reused
    while the blocks are unchanged (on every rank: the COO preallocation is collective); the
    cached matrix itself is returned (overwritten by the next call under that name), tagged with
    its pattern (attribute ``coo_pattern``: equal tags, equal sparsity), which lets a solver
    refill a factorised sum in place.
    """

    def __init__(self, comm: MPI.Comm, sizes: tuple[int, int]):
        self.comm, self.sizes = comm, sizes
        self._cached: dict[str, tuple] = {}

    def assemble(
        self, blocks: list[npt.NDArray], vals: npt.NDArray, cache: str | None = None
    ) -> PETSc.Mat:
        cached = self._cached.get(cache)
        same = (
            cached is not None
            and len(cached[0]) == len(blocks)
            and all(np.array_equal(a, b) for a, b in zip(cached[0], blocks))
        )
        if self.comm.allreduce(same, op=MPI.LAND):  # the COO preallocation is collective
            A = cached[1]
        else:
            A = PETSc.Mat().create(comm=self.comm)
            A.setSizes((self.sizes, self.sizes), bsize=3)
            A.setType(PETSc.Mat.Type.AIJ)
            rows = [np.repeat(d, d.shape[1], axis=1).ravel() for d in blocks]
            cols = [np.tile(d, (1, d.shape[1])).ravel() for d in blocks]
            rows = np.concatenate(rows) if rows else np.zeros(0)
            cols = np.concatenate(cols) if cols else np.zeros(0)
            A.setPreallocationCOO(rows.astype(PETSc.IntType), cols.astype(PETSc.IntType))
            if cache is not None:
                if cached is not None:
                    cached[1].destroy()
                self._cached[cache] = (blocks, A, next(_pattern_tags))
                A.setAttr("coo_pattern", self._cached[cache][2])  # same tag: same sparsity
        A.setValuesCOO(vals, addv=PETSc.InsertMode.INSERT_VALUES)
        A.assemble()
        return A
