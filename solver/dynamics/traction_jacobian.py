"""The linear systems of the contact points' semismooth Newton (``solver.dynamics.point_newton``):
(I + G_aa D_a) dy_a = r on the active points a, with the dense compliance G (dimensionless) and
the law's derivative D (3 x 3 per point, ``solver.contact.law``).

The Jacobian changes little from one Newton iteration to the next (slip directions turn, a few
points open or close) and little between pairings. FGMRES preconditioned by the single-precision
LU factors of an earlier Jacobian J_0 = I + G_00 D_0 (active set a_0) solves the system in a few
products with G_aa. When the active set a differs from a_0 by a few points, or a few points'
derivatives moved far from D_0 (between stick and slip), the preconditioner is J_0 updated for
them (Woodbury; exactly for the G the factors were made with): on the union U of a and a_0,

    P = I + G_UU D',   D' = D at the changed points of a (closed or moved), 0 at those that
                       opened, D_0 at the other points of a_0,

is the reference R = I + G_UU D_r (D_r = D_0 on a_0, 0 elsewhere: block lower triangular, solved
with the factors of J_0) plus a term of rank 3 |changed points|, G_Uc (D' - D_r)_c. P restricted to
a is the Jacobian at the present set with D_0 at the points kept and the changed points' D of
when the update was made, so FGMRES only corrects the smaller turns of the slip directions. The
factors are renewed when more than ``max_update`` of the points changed, or when FGMRES does not
converge in ``max_krylov`` iterations (if it fails with new factors too, a double-precision
solve). FGMRES (flexible) because a solve in single precision is not exactly linear.

The factors are those of J_0 reduced by the kernel of D_0: a slipping point's multiplier does
not respond to its trial traction changing along the slip direction q (D q = 0), nor does the
multiplier of a point tied only normally to a tangential change. In each point's basis of the
directions D_0 keeps and its kernel, J_0 is block lower triangular with the identity on the
kernel, and only the kept block is factorised (``ReducedFactors``): 3 rows per stuck point, 2
per slipping point, 1 per point tied only normally.

On several ranks every rank holds G; the products with G (FGMRES's operator, the residual's
G lambda and the Newton direction's rows off the active set) are computed in contiguous shares
of their entries, each rank its own, and joined (``solver.dynamics.shares``); FGMRES runs on the
ranks' shares of its vectors, so that all ranks take the same iterations. The columns of a
Woodbury update are solved in shares as well. The factors are computed once per node, by its
first rank with a BLAS thread per rank of the node, in memory that the node's ranks share
(``solver.dynamics.node_memory``); the preconditioner's triangular solves are repeated on every
rank.
"""

from collections.abc import Callable
from typing import cast

import numpy as np
import numpy.typing as npt
import scipy.linalg
import scipy.sparse
from mpi4py import MPI
from petsc4py import PETSc

from common.timing import count
from solver.dynamics.node_memory import NodeMemory
from solver.dynamics.shares import Shares
from solver.dynamics.workspace import Workspace, transpose

__all__ = ["ReducedFactors", "TractionJacobian", "kernel_basis"]

Solve = Callable[[npt.NDArray], npt.NDArray]


def _dofs(points: npt.NDArray) -> npt.NDArray:
    """The 3 rows of each point."""
    return (3 * points[:, None] + np.arange(3)).ravel()


def _flush_subnormal(a: npt.NDArray) -> None:
    """Entries below 1e-20 of a C-order matrix set to 0, in blocks of rows (small temporaries):
    single-precision products with subnormal numbers are slow."""
    for start in range(0, a.shape[0], 256):
        rows = a[start : start + 256]
        rows[np.abs(rows) < 1e-20] = 0.0


def kernel_basis(D: npt.NDArray, tol: float = 1e-8) -> tuple[npt.NDArray, npt.NDArray]:
    """Per point an orthonormal basis Q (|a|, 3, 3) of R^3 whose first columns span the range of
    D^T and the others the kernel of D (singular values below ``tol`` times the largest), and
    the mask of the first ones (|a|, 3). D q = 0 for a slipping point's slip direction q, and for
    both tangents of a point tied only normally; a stuck point (D = I) has no kernel."""
    _, singular, vt = np.linalg.svd(D)
    kept = singular > tol * singular[:, :1]
    return vt.transpose(0, 2, 1).copy(), kept


class ReducedFactors:
    """J_0^-1 from single-precision LU factors of J_0 = I + G_00 D_0 reduced by the kernel of D_0.
    In each point's basis Q (``kernel_basis``), with k the directions D_0 keeps and z its kernel,
    Q^T J_0 Q = [[M, 0], [C, I]]: the kernel's columns of G_00 D_0 Q vanish. So J_0^-1 r =
    Q (a, r_z - C a) with M a = r_k, r_k and r_z the parts of Q^T r, and only M (k x k: 3, 2
    and 1 rows for a stuck, slipping and normally tied point) is factorised (``lu``: the
    factors of M^T)."""

    def __init__(
        self,
        basis: npt.NDArray,
        keep: npt.NDArray,
        null: npt.NDArray,
        lu: tuple[npt.NDArray, npt.NDArray],
        couplings: npt.NDArray,
    ):
        # Q^T with its rows in the order (k, z), as a sparse matrix
        order = np.concatenate([keep, null])
        QT = basis.transpose(0, 2, 1).reshape(-1, 3)[order]
        columns = 3 * (order // 3)[:, None] + np.arange(3)
        n = len(order)
        self.rotation = scipy.sparse.csr_matrix(
            (QT.ravel(), columns.ravel(), 3 * np.arange(n + 1)), shape=(n, n)
        )
        self.k, self.lu, self.couplings = len(keep), lu, couplings

    def solve(self, r: npt.NDArray) -> npt.NDArray:
        """J_0^-1 r (a vector or columns)."""
        rotated = self.rotation @ r
        kept = scipy.linalg.lu_solve(
            self.lu, rotated[: self.k].astype(np.float32), trans=1, check_finite=False
        )
        rotated[self.k :] -= self.couplings @ kept
        rotated[: self.k] = kept
        return self.rotation.T @ rotated


class _Operator:
    """y = x + G_aa (D x) (PETSc python matrix context, vectors in ``shares``); ``rows`` is
    G_aa^T (C order, single precision: the product is a Newton direction's, its residual is
    checked in double)."""

    def __init__(self, rows: npt.NDArray, D: npt.NDArray, shares: Shares):
        self.rows, self.D, self.shares = rows, D, shares

    def mult(self, mat, x, y):
        v = self.shares.gather(x.array_r)
        Dv = (self.D @ v.reshape(-1, 3, 1)).ravel().astype(np.float32)
        part = self.shares.part
        y.array[:] = v[part] + Dv @ self.rows[:, part]


class _Preconditioner:
    """Applies a preconditioner ``solve(r) -> z`` (PETSc python preconditioner context, vectors
    in ``shares``; every rank solves for all entries)."""

    def __init__(self, solve: Solve, shares: Shares):
        self.solve, self.shares = solve, shares

    def apply(self, pc, x, y):
        y.array[:] = self.solve(self.shares.gather(x.array_r))[self.shares.part]


class _Update:
    """The kept factors of J_0 = I + G_00 D_0 (points a_0) updated to the active set a and to the
    derivative D at the points ``changed`` (those that opened or closed, and those whose D moved
    far from D_0): the inverse of P restricted to a (module docstring), for right-hand sides on a."""

    def __init__(
        self,
        solve_0: Solve,
        reference: npt.NDArray,
        D_0: npt.NDArray,
        active: npt.NDArray,
        D: npt.NDArray,
        changed: npt.NDArray,
        GT: npt.NDArray,
        comm: MPI.Comm,
    ):
        union = np.union1d(reference, active)
        closed = np.setdiff1d(active, reference)
        self.solve_0, self.n = solve_0, 3 * len(union)
        self.at_0 = _dofs(np.searchsorted(union, reference))
        self.at_active = _dofs(np.searchsorted(union, active))
        self.at_closed = _dofs(np.searchsorted(union, closed))
        self.at_changed = _dofs(np.searchsorted(union, changed))
        self.D_0 = D_0
        # G_{closed, a_0}: the closed points' rows of R below J_0
        self.G_c0 = GT[np.ix_(_dofs(reference), _dofs(closed))].T.astype(np.float64)
        # the update's columns G_Uc (D' - D_r)_c, D' = D on a (0 off it), D_r = D_0 on a_0
        dD = np.zeros((len(changed), 3, 3))
        in_active = np.isin(changed, active)
        dD[in_active] = D[np.searchsorted(active, changed[in_active])]
        in_reference = np.isin(changed, reference)
        dD[in_reference] -= D_0[np.searchsorted(reference, changed[in_reference])]
        # R^-1 U, the changed points' columns in shares among the ranks
        shares = Shares(comm, len(changed))
        mine = changed[shares.part]
        W = np.zeros((len(mine), 3, self.n))
        if len(mine):
            G_Uc = GT[np.ix_(_dofs(mine), _dofs(union))].T.reshape(self.n, len(mine), 3)
            U = np.einsum("uci,cij->ucj", G_Uc, dD[shares.part]).reshape(self.n, 3 * len(mine))
            W[:] = self._reference_solve(U).T.reshape(W.shape)
        self.W = shares.gather(W).reshape(3 * len(changed), self.n).T
        capacitance = self.W[self.at_changed]
        capacitance[np.diag_indices_from(capacitance)] += 1.0
        self.capacitance = scipy.linalg.lu_factor(capacitance, check_finite=False)

    def _reference_solve(self, r: npt.NDArray) -> npt.NDArray:
        """R^-1 r for r on U (vector or columns)."""
        z = r.copy()
        z[self.at_0] = self.solve_0(r[self.at_0])
        if len(self.at_closed):
            z_0 = z[self.at_0]
            Dz_0 = (self.D_0 @ z_0.reshape(len(self.D_0), 3, -1)).reshape(z_0.shape)
            z[self.at_closed] -= self.G_c0 @ Dz_0
        return z

    def solve(self, r: npt.NDArray) -> npt.NDArray:
        """P^-1 r on the active set (Woodbury)."""
        r_U = np.zeros(self.n)
        r_U[self.at_active] = r
        z = self._reference_solve(r_U)
        z -= self.W @ scipy.linalg.lu_solve(
            self.capacitance, z[self.at_changed], check_finite=False
        )
        return z[self.at_active]


class TractionJacobian:
    """Solves (I + G_aa D_a) dy_a = r for a compliance G (3 np x 3 np) and active points a.

    ``G`` is replaced (:meth:`set_compliance`) when the pairing changes; the factors then stay as
    a preconditioner. Counters: ``factorizations``, ``updates``, ``krylov_iterations`` and
    ``dense_solves``; ``factor_rows``: the rows of the last factors.

    Args:
        comm: the ranks that share the products (each with the same G and right-hand sides).
        max_krylov: FGMRES iterations with the kept factors before they are renewed.
        rtol: relative residual of the solves, at least 1e-6: their products are in single
            precision (the Newton iteration checks its own residual in double, so this only
            sets how close each step is to the exact Newton step; 1e-4 takes the Newton
            iterations of 1e-6 to the accuracy the outer iteration asks, in fewer FGMRES
            iterations, docs/contact.md section 6a).
        max_update: the kept factors are updated for at most this fraction of their points
            changing (a rank-3 term per point), renewed beyond it.
        turn: a point whose D differs from the kept factors' by more than this (Frobenius norm;
            D is dimensionless, I at a stuck point) is updated as changed.
    """

    def __init__(
        self,
        comm: MPI.Comm = MPI.COMM_SELF,
        max_krylov: int = 30,
        rtol: float = 1e-4,
        max_update: float = 0.1,
        turn: float = 0.25,
    ):
        if not rtol >= 1e-6:
            raise ValueError(f"rtol must be >= 1e-6 (single-precision products), got {rtol}")
        self.comm = comm
        self.max_krylov, self.rtol = max_krylov, rtol
        self.max_update, self.turn = max_update, turn
        self.G: npt.NDArray = np.zeros((0, 0))
        self._GT: npt.NDArray = np.zeros((0, 0))
        self._GT32: npt.NDArray = np.zeros((0, 0), dtype=np.float32)  # for the Newton directions
        self._shares = Shares(comm, 0)  # of the entries of G's products
        self._block: tuple[bytes, npt.NDArray] | None = None  # G_aa^T of the last active set
        self._work = Workspace()  # of G_aa^T
        self._node = NodeMemory(comm)  # of the factors
        self._lu: ReducedFactors | None = None  # the factors of J_0
        self._lu_points = np.zeros(0, dtype=np.int64)  # a_0 and D_0 of the kept factors
        self._lu_D = np.zeros((0, 3, 3))
        # the factors updated to an active set and changed points
        self._update: tuple[tuple[bytes, bytes], _Update] | None = None
        self.factorizations = 0
        self.factor_rows = 0
        self.updates = 0  #: Woodbury updates of the kept factors to another active set
        self.krylov_iterations = 0
        self.dense_solves = 0  #: double-precision solves where FGMRES failed with new factors

    def set_compliance(self, G: npt.NDArray) -> None:
        """A new G of the same points, or of more points appended to them (the factors are kept
        as a preconditioner; nothing is done for the present G). G in Fortran order is not
        copied."""
        if G is self.G:
            return
        self.G = G
        self._GT = np.ascontiguousarray(G.T)
        self._GT32 = self._GT.astype(np.float32)
        _flush_subnormal(self._GT32)
        self._shares = Shares(self.comm, G.shape[0])
        self._block = None
        self._update = None

    def free(self) -> None:
        """Release the factors' shared memory (collective; the object is not used after it)."""
        self._lu = None
        self._update = None
        self._node.free()

    def reset(self) -> None:
        """Other points: no G and no factors (the counters are kept)."""
        self.set_compliance(np.zeros((0, 0)))
        self._lu = None

    def times(self, v: npt.NDArray, active: npt.NDArray) -> npt.NDArray:
        """G v (3 np) for v zero off the ``active`` points."""
        if not len(active):
            return np.zeros(self._GT.shape[1])
        part = self._shares.part
        out = np.zeros(part.stop - part.start)
        # run by run of consecutive points, on G^T's rows in place (a copy of them costs more)
        breaks = np.flatnonzero(np.diff(active) != 1) + 1
        starts = 3 * active[np.r_[0, breaks]]
        ends = 3 * (active[np.r_[breaks - 1, len(active) - 1]] + 1)
        for start, end in zip(starts, ends):
            out += v[start:end] @ self._GT[start:end, part]
        return self._shares.gather(out)

    def direction(self, active: npt.NDArray, D: npt.NDArray, phi: npt.NDArray) -> npt.NDArray:
        """The Newton direction dy (3 np) with (I + G D) dy = -phi, D (|a|, 3, 3) the law's
        derivative at the active points (sorted; zero at the others): their block by
        :meth:`solve`, the other rows explicitly (in single precision, as the block)."""
        cols = _dofs(active)
        dy_a = self.solve(active, D, -phi[cols])
        w = np.zeros(len(phi), dtype=np.float32)  # D dy at the active points
        w[cols] = (D @ dy_a.reshape(-1, 3, 1)).ravel()
        part = self._shares.part
        dy = self._shares.gather(-phi[part] - w @ self._GT32[:, part])
        dy[cols] = dy_a
        return dy

    def _block_rows(self, active: npt.NDArray) -> npt.NDArray:
        """G_aa^T (C order, single precision), cached for the last active set."""
        key = active.tobytes()
        if self._block is None or self._block[0] != key:
            cols = _dofs(active)
            picked = self._work.get("rows", (len(cols), self._GT32.shape[1]), np.float32)
            np.take(self._GT32, cols, axis=0, out=picked, mode="clip")  # clip: unbuffered
            block = self._work.get("block", (len(cols), len(cols)), np.float32)
            self._block = (key, np.take(picked, cols, axis=1, out=block, mode="clip"))
        return self._block[1]

    def _jacobian(self, active: npt.NDArray, D: npt.NDArray, rows: npt.NDArray) -> npt.NDArray:
        """J = I + G_aa D (Fortran order) from ``rows`` = G_aa^T (C order), in their precision."""
        n = rows.shape[0]
        # J^T = D^T G_aa^T block row by block row; J in Fortran order is its transpose
        DT = D.transpose(0, 2, 1).astype(rows.dtype)
        J = np.matmul(DT, rows.reshape(len(active), 3, n)).reshape(n, n).T
        J[np.diag_indices_from(J)] += 1.0
        return J

    def factorise(self, active: npt.NDArray, D: npt.NDArray) -> ReducedFactors:
        """New single-precision LU factors of J = I + G_aa D for the active points (sorted),
        reduced by the kernel of D (``ReducedFactors``), kept as the preconditioner (collective)."""
        rows = self._block_rows(active)
        node = self._node
        node.begin()
        # the node's first rank's basis for all (the factors are made with it)
        basis = np.empty((len(active), 3, 3))
        kept = np.empty((len(active), 3), dtype=np.int8)
        if node.writer:
            basis[:], kept[:] = kernel_basis(D)
        node.comm.Bcast(basis)
        node.comm.Bcast(kept)
        keep, null = np.flatnonzero(kept.ravel()), np.flatnonzero(kept.ravel() == 0)
        # once per node, in the memory of the factors it replaces (M^T in C order); the pivots
        # are each rank's own (SciPy's lu_solve shifts them in place during a solve)
        factors = node.get("factors", (len(keep), len(keep)), np.float32)
        couplings = node.get("couplings", (len(null), len(keep)), np.float32)
        pivots = np.empty(len(keep), dtype=np.int32)
        if node.writer:
            H = self._rotated(D, basis, keep, rows)
            np.take(H, keep, axis=0, out=factors, mode="clip")  # M - I, in C order
            factors[np.diag_indices_from(factors)] += 1.0
            np.take(H, null, axis=0, out=couplings, mode="clip")
            _flush_subnormal(factors)
            _flush_subnormal(couplings)
            with node.threads():  # factors of M^T (M in C order is M^T in Fortran order)
                lu, pivots[:] = scipy.linalg.lu_factor(
                    factors.T, overwrite_a=True, check_finite=False
                )
            if not np.shares_memory(lu, factors):
                factors.T[:] = lu
        node.end()
        node.comm.Bcast(pivots)
        self._lu = ReducedFactors(basis, keep, null, (factors.T, pivots), couplings)
        self._lu_points, self._lu_D = active.copy(), D.copy()
        self._update = None
        self.factorizations += 1
        self.factor_rows = len(keep)
        count("traction factorisations")
        count("traction factor rows", len(keep))
        return self._lu

    def _rotated(
        self, D: npt.NDArray, basis: npt.NDArray, keep: npt.NDArray, rows: npt.NDArray
    ) -> npt.NDArray:
        """H = Q^T G_aa D Q_k (n x k, C order, single precision) from ``rows`` = G_aa^T (C order)
        and the points' bases Q (Q_k: the directions kept): G_aa's columns combined point by
        point, transposed in blocks, then its rows."""
        points, n, k = len(basis), rows.shape[0], len(keep)
        DQT = np.matmul(D, basis).transpose(0, 2, 1).astype(np.float32)
        XT = self._work.get("rotated", (points, 3, n), np.float32)
        np.matmul(DQT, rows.reshape(points, 3, n), out=XT)  # (G_aa D Q)^T
        XT_k = self._work.get("kept rows", (k, n), np.float32)
        np.take(XT.reshape(n, n), keep, axis=0, out=XT_k, mode="clip")
        X = transpose(XT_k, self._work.get("kept columns", (n, k), np.float32))
        QT = basis.transpose(0, 2, 1).astype(np.float32)
        H = self._work.get("reduced", (points, 3, k), np.float32)
        return np.matmul(QT, X.reshape(points, 3, k), out=H).reshape(n, k)

    def _factors(self, active: npt.NDArray, D: npt.NDArray) -> Solve | None:
        """The preconditioner's solve from the kept factors for the active set, or None where
        there are none or too many points changed."""
        if self._lu is None:
            return None
        factors, reference = self._lu, self._lu_points
        kept, in_active, in_reference = np.intersect1d(
            active, reference, assume_unique=True, return_indices=True
        )
        moved = np.linalg.norm(D[in_active] - self._lu_D[in_reference], axis=(1, 2)) > self.turn
        changed = np.union1d(np.setxor1d(active, reference, assume_unique=True), kept[moved])
        if not len(changed):
            return factors.solve
        if len(changed) > self.max_update * len(reference):
            return None
        key = (active.tobytes(), changed.tobytes())
        if self._update is None or self._update[0] != key:
            update = _Update(
                factors.solve, reference, self._lu_D, active, D, changed, self._GT32, self.comm
            )
            self._update = (key, update)
            self.updates += 1
            count("traction updates")
        return self._update[1].solve

    def _krylov(
        self, active: npt.NDArray, D: npt.NDArray, r: npt.NDArray, preconditioner: Solve
    ) -> tuple[npt.NDArray, bool]:
        """FGMRES with the preconditioner: the solution and whether it converged."""
        shares = Shares(self.comm, len(r))
        size = (shares.stop - shares.start, len(r))
        operator = _Operator(self._block_rows(active), D, shares)
        comm = cast(PETSc.Comm, self.comm)  # petsc4py takes mpi4py's communicators
        A = PETSc.Mat().createPython((size, size), operator, comm=comm)
        ksp = PETSc.KSP().create(comm)
        b = PETSc.Vec().createMPI(size, comm=comm)
        b.array[:] = r[shares.part]
        x = b.duplicate()
        pc = ksp.getPC()
        try:
            A.setUp()
            ksp.setOperators(A)
            ksp.setType(PETSc.KSP.Type.FGMRES)
            ksp.setGMRESRestart(self.max_krylov)
            ksp.setTolerances(rtol=self.rtol, atol=0.0, max_it=self.max_krylov)
            pc.setType(PETSc.PC.Type.PYTHON)
            pc.setPythonContext(_Preconditioner(preconditioner, shares))
            ksp.solve(b, x)
            iterations = ksp.getIterationNumber()
            self.krylov_iterations += iterations
            count("traction krylov", iterations)
            return shares.gather(x.array_r), cast(int, ksp.getConvergedReason()) > 0
        finally:
            # the PC too: petsc4py would hand a parallel PC (and the factors its context holds)
            # that outlives its KSP to the communicator's garbage, freed only by a clean-up
            for obj in (x, b, ksp, pc, A):
                obj.destroy()

    def solve(self, active: npt.NDArray, D: npt.NDArray, r: npt.NDArray) -> npt.NDArray:
        """dy_a with (I + G_aa D) dy_a = r for the active points (sorted) and D (|a|, 3, 3)."""
        preconditioner = self._factors(active, D)
        if preconditioner is not None:
            dy, converged = self._krylov(active, D, r, preconditioner)
            if converged:
                return dy
        factors = self.factorise(active, D)
        dy, converged = self._krylov(active, D, r, factors.solve)
        if not converged:  # J too ill-conditioned for single-precision factors
            cols = _dofs(active)
            J = self._jacobian(active, D, self._GT[np.ix_(cols, cols)])
            dy = scipy.linalg.solve(J, r, check_finite=False)
            self.dense_solves += 1
            self.comm.Bcast(dy)  # the same on every rank
        return dy
