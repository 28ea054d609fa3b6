"""The linear systems of the contact points' semismooth Newton (``solver.dynamics.point_newton``):
(I + G_aa D_a) dy_a = r on the active points a, with the dense compliance G (dimensionless) and
the law's derivative D (3 x 3 per point, ``solver.contact.law``).

The Jacobian changes little from one Newton iteration to the next (slip directions turn, a few
points change state) and little between pairings. FGMRES preconditioned by the single-precision
LU factors of an earlier Jacobian on the same active set solves the system in a few products
with G_aa; the factors are renewed when the active set changes or FGMRES does not converge in
``max_krylov`` iterations (if it fails with new factors too, a double-precision solve). FGMRES
(flexible) because a solve in single precision is not exactly linear.
"""

from typing import cast

import numpy as np
import numpy.typing as npt
import scipy.linalg
from petsc4py import PETSc

__all__ = ["TractionJacobian"]


def _dofs(points: npt.NDArray) -> npt.NDArray:
    """The 3 rows of each point."""
    return (3 * points[:, None] + np.arange(3)).ravel()


class _Operator:
    """y = x + G_aa (D x) (PETSc python matrix context); ``rows`` is G_aa^T (C order)."""

    def __init__(self, rows: npt.NDArray, D: npt.NDArray):
        self.rows, self.D = rows, D

    def mult(self, mat, x, y):
        v = x.array_r
        y.array[:] = v + (self.D @ v.reshape(-1, 3, 1)).ravel() @ self.rows


class _Factors:
    """Applies single-precision LU factors (PETSc python preconditioner context)."""

    def __init__(self, lu):
        self.lu = lu

    def apply(self, pc, x, y):
        z = scipy.linalg.lu_solve(self.lu, x.array_r.astype(np.float32), check_finite=False)
        y.array[:] = z


class TractionJacobian:
    """Solves (I + G_aa D_a) dy_a = r for a compliance G (3 np x 3 np) and active points a.

    ``G`` is replaced (:meth:`set_compliance`) when the pairing changes; the factors then stay as
    a preconditioner. Counters: ``factorizations``, ``krylov_iterations`` and ``direct_solves``.

    Args:
        max_krylov: FGMRES iterations with the kept factors before they are renewed.
        rtol: relative residual of the solves (the Newton iteration checks its own residual, so
            this only sets how close each step is to the exact Newton step).
    """

    def __init__(self, max_krylov: int = 30, rtol: float = 1e-6):
        self.max_krylov, self.rtol = max_krylov, rtol
        self.G: npt.NDArray = np.zeros((0, 0))
        self._GT: npt.NDArray = np.zeros((0, 0))
        self._rows: dict[bytes, npt.NDArray] = {}  # G^T's rows of an active set
        self._block: tuple[bytes, npt.NDArray] | None = None  # G_aa^T of the last active set
        self._lu = None
        self._lu_active: bytes | None = None
        self.factorizations = 0
        self.krylov_iterations = 0
        self.direct_solves = 0  #: double-precision solves where FGMRES with new factors failed

    def set_compliance(self, G: npt.NDArray) -> None:
        """A new G of the same points, or of more points appended to them (the factors are kept
        as a preconditioner). G in Fortran order is not copied."""
        self.G = G
        self._GT = np.ascontiguousarray(G.T)
        self._rows.clear()
        self._block = None

    def reset(self) -> None:
        """Other points: no G and no factors (the counters are kept)."""
        self.set_compliance(np.zeros((0, 0)))
        self._lu, self._lu_active = None, None

    def rows(self, active: npt.NDArray) -> npt.NDArray:
        """G^T's rows of the ``active`` points (3 |active| x 3 np), cached."""
        key = active.tobytes()
        if key not in self._rows:
            if len(self._rows) > 3:
                self._rows.clear()
            self._rows[key] = self._GT[_dofs(active)]
        return self._rows[key]

    def times(self, v: npt.NDArray, active: npt.NDArray) -> npt.NDArray:
        """G v (3 np) for v zero off the ``active`` points."""
        return v[_dofs(active)] @ self.rows(active)

    def _block_rows(self, active: npt.NDArray) -> npt.NDArray:
        """G_aa^T (C order), cached for the last active set."""
        key = active.tobytes()
        if self._block is None or self._block[0] != key:
            # take gives C order in one pass (rows[:, dofs] is not C-ordered)
            self._block = (key, self.rows(active).take(_dofs(active), axis=1))
        return self._block[1]

    def _jacobian(self, active: npt.NDArray, D: npt.NDArray) -> npt.NDArray:
        """J = I + G_aa D (Fortran order)."""
        rows = self._block_rows(active)
        n = rows.shape[0]
        # J^T = D^T G_aa^T block row by block row; J in Fortran order is its transpose
        J = (D.transpose(0, 2, 1) @ rows.reshape(len(active), 3, n)).reshape(n, n).T
        J[np.diag_indices_from(J)] += 1.0
        return J

    def _factorise(self, active: npt.NDArray, D: npt.NDArray) -> None:
        """Single-precision LU factors of J = I + G_aa D."""
        J = self._jacobian(active, D)
        J[np.abs(J) < 1e-20] = 0.0  # no subnormal numbers in single precision: slow
        self._lu = scipy.linalg.lu_factor(
            J.astype(np.float32, order="F"), overwrite_a=True, check_finite=False
        )
        self._lu_active = active.tobytes()
        self.factorizations += 1

    def _krylov(self, active: npt.NDArray, D: npt.NDArray, r: npt.NDArray):
        """FGMRES with the kept factors: the solution and whether it converged."""
        n = len(r)
        comm = PETSc.COMM_SELF
        A = PETSc.Mat().createPython((n, n), _Operator(self._block_rows(active), D), comm=comm)
        ksp = PETSc.KSP().create(comm)
        b = PETSc.Vec().createSeq(n, comm=comm)
        b.array[:] = r
        x = b.duplicate()
        try:
            A.setUp()
            ksp.setOperators(A)
            ksp.setType(PETSc.KSP.Type.FGMRES)
            ksp.setGMRESRestart(self.max_krylov)
            ksp.setTolerances(rtol=self.rtol, atol=0.0, max_it=self.max_krylov)
            pc = ksp.getPC()
            pc.setType(PETSc.PC.Type.PYTHON)
            pc.setPythonContext(_Factors(self._lu))
            ksp.solve(b, x)
            self.krylov_iterations += ksp.getIterationNumber()
            return x.array_r.copy(), cast(int, ksp.getConvergedReason()) > 0
        finally:
            for obj in (x, b, ksp, A):
                obj.destroy()

    def solve(self, active: npt.NDArray, D: npt.NDArray, r: npt.NDArray) -> npt.NDArray:
        """dy_a with (I + G_aa D) dy_a = r for the active points (sorted) and D (|a|, 3, 3)."""
        if self._lu is not None and self._lu_active == active.tobytes():
            dy, converged = self._krylov(active, D, r)
            if converged:
                return dy
        self._factorise(active, D)
        dy, converged = self._krylov(active, D, r)
        if not converged:  # J too ill-conditioned for single-precision factors
            self.direct_solves += 1
            return scipy.linalg.solve(self._jacobian(active, D), r, check_finite=False)
        return dy
