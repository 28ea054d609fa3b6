"""Linear-algebra pieces of the Newton solver and the time stepping: LU solvers, the block-LU
preconditioner of A + J_c and the operator A + J without products with A (PETSc python
contexts).
"""

from collections.abc import Callable, Sequence
from typing import cast

import numpy as np
import numpy.typing as npt
from petsc4py import PETSc

from common.timing import timed

__all__ = ["BlockLU", "SumOperator", "direct_solver", "forcing_term", "solve_columns"]


def direct_solver(
    comm, A: PETSc.Mat | None = None, package: str = "mumps", prefix: str | None = None
) -> PETSc.KSP:
    """A direct solver: a KSP that applies the LU factors of its operator (``A``, or set later),
    computed by the PETSc package ``package`` ("mumps", "superlu_dist", "petsc"). With
    ``prefix`` the user's PETSc options under that prefix apply (e.g.
    ``-dynamics_pc_factor_mat_solver_type``); without, none do."""
    ksp = PETSc.KSP().create(comm)
    if prefix is not None:
        ksp.setOptionsPrefix(prefix)
    ksp.setType(PETSc.KSP.Type.PREONLY)
    pc = ksp.getPC()
    pc.setType(PETSc.PC.Type.LU)
    pc.setFactorSolverType(package)
    if prefix is not None:
        ksp.setFromOptions()
    if A is not None:
        ksp.setOperators(A)
    return ksp


def solve_columns(
    factor: PETSc.Mat,
    A: PETSc.Mat,
    n: int,
    entries: Callable[[int, int], tuple[npt.NDArray, npt.NDArray, npt.NDArray]],
    consume: Callable[[PETSc.Mat, int, int], None],
    width: int,
    sparse: bool = False,
) -> None:
    """Solve A X = B for n columns of B with the LU ``factor`` of A, ``width`` right-hand sides at
    a time: ``entries(c0, c1)`` gives this rank's nonzeros of B's columns c0..c1 (local rows,
    columns counted from c0, values; each entry once), ``consume(X, c0, c1)`` takes the
    solutions (X's first c1 - c0 columns).

    ``sparse`` (MUMPS only): B is passed as a sparse matrix on the first rank, whose forward
    substitution MUMPS restricts to the nonzeros' part of the elimination tree (about 1.4 times
    fewer seconds per column for the compliance blocks of the converged joint than dense).
    Dense: every block has the same width, the last one padded with zero columns
    (SuperLU_DIST's parallel MatMatSolve corrupts memory when the number of right-hand sides
    changes between calls)."""
    comm = A.getComm()
    n_local, N = A.getLocalSize()[0], A.getSize()[0]
    start = A.getOwnershipRange()[0]
    X = PETSc.Mat().createDense(((n_local, N), (PETSc.DECIDE, width)), comm=comm)
    X.setUp()
    B = None if sparse else X.duplicate()
    for c0 in range(0, n, width):
        c1 = min(c0 + width, n)
        rows, cols, values = entries(c0, c1)
        if B is None:
            Bt = _first_rank_transpose(comm, width, N, start + rows, cols, values)
            rhs = PETSc.Mat().createTranspose(Bt)
            factor.matSolve(rhs, X)
            rhs.destroy()
            Bt.destroy()
        else:
            block = B.getDenseArray()
            block[:] = 0.0
            block[rows, cols] = values
            B.assemble()
            factor.matSolve(B, X)
        consume(X, c0, c1)
    X.destroy()
    if B is not None:
        B.destroy()


def _first_rank_transpose(
    comm: PETSc.Comm,
    width: int,
    N: int,
    rows: npt.NDArray,
    cols: npt.NDArray,
    values: npt.NDArray,
) -> PETSc.Mat:
    """B^T (width x N, AIJ) of the entries (global rows, columns, values) of every rank, all of
    it on the first rank (rows and columns), as MUMPS takes a sparse right-hand side."""
    mpi = comm.tompi4py()
    gathered = cast(list[tuple[npt.NDArray, ...]], mpi.gather((rows, cols, values), root=0))
    first = mpi.rank == 0
    Bt = PETSc.Mat().create(comm=comm)
    Bt.setSizes(((width if first else 0, width), (N if first else 0, N)))
    Bt.setType(PETSc.Mat.Type.AIJ)
    if first:
        r, c, v = (np.concatenate(a) for a in zip(*gathered))
    else:
        r = c = np.zeros(0, dtype=np.int64)
        v = np.zeros(0)
    Bt.setPreallocationCOO(
        cast(Sequence[int], c.astype(PETSc.IntType)), cast(Sequence[int], r.astype(PETSc.IntType))
    )
    Bt.setValuesCOO(cast(Sequence[float], v))
    Bt.assemble()
    return Bt


class BlockLU:
    """Preconditioner (PETSc python PC context) applying the LU factors of P = A + J_P, or with
    a zone those of its (zone, zone) block and the identity elsewhere, which is P^-1 itself
    when A is block diagonal with identity rows off the zone and J lives in the zone
    (``solver.dynamics.condensation``). ``zone``: this rank's zone dofs as local indices.

    ``lu``: the direct solver of the factors in use (the Newton solver sets it). It remembers
    its last input v and output z = P^-1 v, for ``SumOperator``."""

    def __init__(self, lu: PETSc.KSP | None, zone: np.ndarray | None):
        self.lu, self.zone = lu, zone
        self.last: tuple[int, PETSc.Vec] | None = None  # (handle of z, v)
        self._vz = self._zz = None

    def setUp(self, pc):  # the factorisation is FactorStore.factorise's
        if self.zone is not None and self._vz is None:
            self._vz, self._zz = self.lu.getOperators()[0].createVecs()

    @timed("triangular solves")
    def apply(self, pc, v, z):
        if self.zone is None:
            self.lu.solve(v, z)
        else:
            v.copy(z)
            self._vz.array[:] = v.array_r[self.zone]
            self.lu.solve(self._vz, self._zz)
            z.array[self.zone] = self._zz.array_r
        self.last = (z.handle, v)


class SumOperator:
    """Action of A + J (PETSc python matrix context). FGMRES multiplies each preconditioned
    vector z = P^-1 v right after making it; then (A + J) z = v + (J - J_P) z, with J_P the
    Jacobian in the factorised P = A + J_P, which needs no product with A (the bulk of the
    work; J lives on the interface). ``difference``: J - J_P assembled (one product instead of
    two), or None (then J and J_P are multiplied), or ``ZERO`` when J is J_P (no product at
    all). Round-off: that of the LU solve's residual."""

    ZERO = "zero"

    def __init__(
        self,
        A: PETSc.Mat,
        J: PETSc.Mat,
        J_P: PETSc.Mat,
        preconditioner: BlockLU,
        difference: PETSc.Mat | str | None = None,
    ):
        self.A, self.J, self.J_P, self.preconditioner = A, J, J_P, preconditioner
        self.difference = difference
        self._work = J.createVecLeft()

    def mult(self, mat, x, y):
        last = self.preconditioner.last
        if last is not None and last[0] == x.handle:
            if self.difference is self.ZERO:
                last[1].copy(y)
            elif self.difference is not None:
                self.difference.multAdd(x, last[1], y)
            else:
                self.J.multAdd(x, last[1], y)
                self.J_P.mult(x, self._work)
                y.axpy(-1.0, self._work)
        else:
            self.A.mult(x, y)
            self.J.multAdd(x, y, y)

    def destroy(self, mat):
        self._work.destroy()


def forcing_term(
    norms: list[float], eta_old: float, tol: float, forcing_max: float, krylov_rtol: float
) -> float:
    """GMRES relative tolerance eta_k of the next inexact Newton correction, stopping GMRES at
    ||F + (A + J_c) du|| <= eta_k ||F|| (Eisenstat and Walker 1996, choice 2, safeguarded).

    ``norms``: ||F_0||, ..., ||F_k|| [N]; ``eta_old``: the previous eta; ``tol``: the Newton
    tolerance [N]. eta_0 = 0.5 tol / ||F_0|| (a nearly linear step, e.g. a quiet vibration step,
    then converges in one iteration); eta_k = 0.9 (||F_k|| / ||F_{k-1}||)^2, at least
    0.9 eta_{k-1}^2 when that exceeds 0.1, capped at ``forcing_max``, and never tighter than
    needed to reach the Newton tolerance (0.5 tol / ||F_k||) nor than ``krylov_rtol``. Far from
    the solution a few GMRES iterations suffice; near it eta_k = O(||F_k||) keeps the rate
    quadratic. ``forcing_max = 0``: every correction to ``krylov_rtol`` (exact Newton).
    """
    if forcing_max == 0.0:
        return krylov_rtol
    if len(norms) == 1:
        eta = 0.5 * tol / norms[0]
    else:
        eta = 0.9 * (norms[-1] / norms[-2]) ** 2
        if 0.9 * eta_old**2 > 0.1:
            eta = max(eta, 0.9 * eta_old**2)
    eta = min(eta, forcing_max)
    return max(eta, 0.5 * tol / norms[-1], krylov_rtol)
