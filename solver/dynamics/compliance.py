"""The contact compliance G = E A^-1 F^T W of a set of contact points, from fixed LU factors of a
linear operator A on the contact zone (docs/dynamics.md, "Newton on the contact points").

The trial tractions P of the contact points q (3 per point, ``solver.contact.nitsche``) change
as dP = E du, and the points' multipliers lambda act on the structure as the load F^T W lambda,
W = diag(w / gamma). With both operators split into a slave part and the master part M (the
master displacement at the paired point, which moves with the pairing),

    E = E_s + M,   F = F_s + M,

the compliance of the points

    G = E A^-1 F^T W = Q_ss + Q_sb M_b^T W' + M_b R_bs + M_b Z_bb M_b^T W'

(M_b: M on the master band b, the master dofs the points can pair with) needs,
once per A, the dense blocks Q_ss = E_s X_F, Q_sb = E_s X_b, R_bs = X_F[b] and Z_bb = X_b[b] of
the solutions X_F = A^-1 F_s^T W and X_b = A^-1 I_b: 3 |points| + |b| solves with multiple
right-hand sides (on several ranks each rank solves a share of them with its own copy of the
factors). Each pairing then costs only sparse-dense products. G is dimensionless, the
blocks are held on every rank; the points are ordered rank by rank, three rows per point.
"""

from collections.abc import Sequence
from typing import cast

import numpy as np
import numpy.typing as npt
from mpi4py import MPI
from petsc4py import PETSc

from common.timing import timed
from solver.contact.model import PointOperators
from solver.dynamics.linear_algebra import direct_solver, solve_columns
from solver.dynamics.workspace import GrowingMatrix, Workspace, transpose

__all__ = ["ContactCompliance", "MasterOperator"]


class MasterOperator:
    """The points' master parts on the band, M_b (3 |points| x |band|): each point's 3 rows act on
    the 3 x 9 dofs of its paired master facet. Products are taken facet by facet (the points
    paired with one facet share its dofs) as dense matrix products.

    Args:
        index: band positions of each point's master dofs (np, nd).
        values: each point's master part (np, 3, nd) [Pa/m].
        band: the band's size.
    """

    def __init__(self, index: npt.NDArray, values: npt.NDArray, band: int):
        self.shape = (3 * len(index), band)
        order = np.lexsort(index.T[::-1]) if len(index) else np.zeros(0, dtype=np.int64)
        key = index[order]
        first = np.r_[True, np.any(key[1:] != key[:-1], axis=1)] if len(key) else np.zeros(0, bool)
        bounds = np.r_[np.flatnonzero(first), len(key)]
        #: per master facet: the rows of its points, their band columns, the dense block
        self.groups: list[tuple[npt.NDArray, npt.NDArray, npt.NDArray]] = []
        for a, b in zip(bounds[:-1], bounds[1:]):
            points = order[a:b]
            rows = (3 * points[:, None] + np.arange(3)).ravel()
            self.groups.append((rows, key[a], values[points].reshape(len(rows), -1)))

    def times(self, X: npt.NDArray) -> npt.NDArray:
        """M_b X for X (|band|, ...) [or a vector]."""
        out = np.zeros((self.shape[0],) + X.shape[1:])
        for rows, cols, block in self.groups:
            out[rows] = block @ X[cols]
        return out

    def transpose_times(self, v: npt.NDArray) -> npt.NDArray:
        """M_b^T v for a vector v (3 |points|)."""
        out = np.zeros(self.shape[1])
        for rows, cols, block in self.groups:
            out[cols] += v[rows] @ block  # a group's columns are distinct
        return out


def _gather_rows(comm: MPI.Comm, local: npt.NDArray) -> npt.NDArray:
    """Rows held by the ranks, stacked rank by rank (on every rank)."""
    return np.concatenate(comm.allgather(np.ascontiguousarray(local)))


def _gather_columns(comm: MPI.Comm, columns: npt.NDArray, out: npt.NDArray) -> npt.NDArray:
    """The columns of a matrix held by the ranks in contiguous shares (rank by rank), on every
    rank, as rows: ``columns`` this rank's share as rows, ``out`` (all columns x rows, C order)
    receives them and is returned."""
    counts = np.array(comm.allgather(columns.shape[0])) * columns.shape[1]
    comm.Allgatherv(np.ascontiguousarray(columns), (out, counts))  # MPI reads the memory as is
    return out


def _full_copy(mat: PETSc.Mat) -> PETSc.Mat:
    """A sequential copy of all of a (distributed) AIJ matrix on every rank (collective)."""
    rows, cols = (PETSc.IS().createStride(n, 0, 1, comm=PETSc.COMM_SELF) for n in mat.getSize())
    (copy,) = mat.createSubMatrices(rows, cols)
    rows.destroy()
    cols.destroy()
    return copy


class ContactCompliance:
    """LU factors of the zone operator A and the compliance blocks of contact points.

    The point set and the band only grow (:meth:`extend`); A is symmetric (the Newmark operator
    of a symmetric structure and the linear Nitsche part), so that new points and band dofs
    need the solutions of their own columns only: A^-1 F_N^T W, A^-1 E_N^T and A^-1 I_bN.
    The distributed factors of A serve the solves of the Newton iterations (:meth:`solve`); on
    several ranks the blocks' columns are solved with a sequential copy of A and its factors on
    every rank (:meth:`_column_solver`), which costs a second set of factors per rank.

    Args:
        A: the operator on the zone (zone numbering: the zone's dofs rank by rank), symmetric.
        zone_dofs: the zone's global dofs (of the full space) in zone order, on every rank.
        lu_solver: PETSc factorisation package; PETSc options under the prefix ``compliance_``
            apply to the distributed factorisation (e.g. ``-compliance_mat_mumps_icntl_7 5``),
            those under ``compliance_columns_`` to the ranks' sequential copies.
        width: right-hand sides per multiple-right-hand-side solve (fewer when a rank's share of
            the columns is smaller, except with SuperLU_DIST, whose repeated solves need the
            same width); MUMPS takes them sparse.
    """

    def __init__(self, A: PETSc.Mat, zone_dofs: npt.NDArray, lu_solver: str, width: int = 64):
        self.A = A
        self.comm: MPI.Comm = A.getComm().tompi4py()
        self.zone_dofs = zone_dofs
        self.start, self.end = A.getOwnershipRange()
        self.width = width
        self._fixed_width = lu_solver == "superlu_dist"
        self._sparse = lu_solver == "mumps"  # sparse right-hand sides (solve_columns)
        self._package = lu_solver
        self.lu = direct_solver(self.comm, A, lu_solver, prefix="compliance_")
        self.lu.setUp()
        self._copy: PETSc.KSP | None = None  # the column solves' factors (_column_solver)
        self.points = 0  #: contact points of the blocks (all ranks)
        #: master band: global dofs in the order of the blocks' band rows and columns
        self.band = np.zeros(0, dtype=np.int64)
        self._counts = [0] * self.comm.size  # points per rank
        self._to_block = np.zeros(0, dtype=np.int64)  # block row of each rank-major row
        self._E: PETSc.Mat | None = None
        self._F: PETSc.Mat | None = None
        self._gathered = Workspace()  # the column solves' results, gathered
        self.reset()

    def zone_index(self, dofs: npt.NDArray) -> npt.NDArray:
        """Zone indices of global dofs (all of which must be zone dofs)."""
        index = np.minimum(np.searchsorted(self.zone_dofs, dofs), len(self.zone_dofs) - 1)
        if not np.array_equal(self.zone_dofs[index], dofs):
            raise ValueError("contact operators reach dofs outside the condensed zone")
        return index

    def to_block(self, rank_major: npt.NDArray) -> npt.NDArray:
        """Rows of the points gathered rank by rank (3 per point) in the blocks' order."""
        out = np.empty_like(rank_major)
        out[self._to_block] = rank_major
        return out

    def reset(self) -> None:
        """No points and no band (the factors are kept)."""
        self.points, self.band, self._counts = 0, np.zeros(0, dtype=np.int64), [0] * self.comm.size
        self._to_block = np.zeros(0, dtype=np.int64)
        self._blocks = {name: GrowingMatrix() for name in ("Q_ss", "Q_sb", "R_bs", "Z_bb")}
        self._Q_bs: npt.NDArray | None = None  # Q_sb^T, C-ordered, made when G needs it
        self._band_rows()

    @property
    def Q_ss(self) -> npt.NDArray:
        """E_s X_F (3 |points| x 3 |points|)."""
        return self._blocks["Q_ss"].array

    @property
    def Q_sb(self) -> npt.NDArray:
        """E_s X_b (3 |points| x |band|)."""
        return self._blocks["Q_sb"].array

    @property
    def R_bs(self) -> npt.NDArray:
        """X_F on the band (|band| x 3 |points|)."""
        return self._blocks["R_bs"].array

    @property
    def Z_bb(self) -> npt.NDArray:
        """X_b on the band (|band| x |band|)."""
        return self._blocks["Z_bb"].array

    def points_to_block(self, rank_major: npt.NDArray) -> npt.NDArray:
        """Per-point values gathered rank by rank in the blocks' point order."""
        out = np.empty_like(rank_major)
        out[self._to_block[::3] // 3] = rank_major
        return out

    # -- the blocks ---------------------------------------------------------------------------
    def restrict(self, ops: PointOperators, keep: npt.NDArray, keep_band: npt.NDArray) -> None:
        """Keep this rank's points where ``keep`` (over its points, in order; ``ops``: the kept
        points' operators) and the band dofs where ``keep_band`` (the same on every rank): the
        blocks' rows and columns of the others are dropped, no solve."""
        comm = self.comm
        counts = comm.allgather(int(np.count_nonzero(keep)))
        kept_rows = np.repeat(np.concatenate(comm.allgather(keep)), 3)
        block = self._to_block[kept_rows]  # the kept rows' blocks rows, rank by rank
        order = np.sort(block)
        self._to_block = np.searchsorted(order, block)
        self._counts, self.points = counts, sum(counts)
        blocks = self._blocks
        blocks["Q_ss"].set(self.Q_ss[np.ix_(order, order)])
        blocks["Q_sb"].set(self.Q_sb[np.ix_(order, keep_band)])
        blocks["R_bs"].set(self.R_bs[np.ix_(keep_band, order)])
        blocks["Z_bb"].set(self.Z_bb[np.ix_(keep_band, keep_band)])
        self._Q_bs = None
        self.band = self.band[keep_band]
        self._band_rows()
        self._point_matrices(ops)

    def _point_matrices(self, ops: PointOperators) -> None:
        """E_s and F_s W of all points (rows rank by rank) from this rank's points' operators."""
        for mat in (self._E, self._F):
            if mat is not None:
                mat.destroy()
        firsts = np.cumsum([0] + [3 * c for c in self._counts])
        rows = firsts[self.comm.rank] + np.arange(3 * self._counts[self.comm.rank])
        cols = self.zone_index(ops.slave_dofs.ravel()).reshape(ops.slave_dofs.shape)
        m = 3 * self.points
        self._E = self._point_matrix(rows, cols, ops.E_slave, m)
        self._F = self._point_matrix(rows, cols, ops.F_slave * ops.weight[:, None, None], m)

    @timed("compliance")
    def extend(self, ops: PointOperators, new: int, band: npt.NDArray) -> None:
        """Add this rank's last ``new`` points of ``ops`` (the operators of all of its points, the
        earlier ones first) and the master dofs ``band`` (global, the same on every rank, none
        already in the band) to the blocks: 2 |new points| (|new points| if there were none) +
        |band| solves."""
        comm = self.comm
        counts = comm.allgather(len(ops.weight))
        added = comm.allgather(new)
        old_counts = [c - a for c, a in zip(counts, added)]
        if old_counts != self._counts:
            raise ValueError("extend: the earlier points must come first, unchanged")
        m_old, m_new = 3 * self.points, 3 * sum(added)
        # block order: the earlier points, then the new points rank by rank
        firsts = np.cumsum([0] + [3 * c for c in counts])
        to_block = np.empty(3 * sum(counts), dtype=np.int64)
        old_firsts = np.cumsum([0] + [3 * c for c in old_counts])
        new_firsts = m_old + np.cumsum([0] + [3 * a for a in added])
        for r in range(comm.size):
            earlier = self._to_block[old_firsts[r] : old_firsts[r + 1]]
            later = new_firsts[r] + np.arange(3 * added[r])
            to_block[firsts[r] : firsts[r + 1]] = np.concatenate([earlier, later])
        self._counts, self._to_block, self.points = counts, to_block, sum(counts)
        self._point_matrices(ops)
        cols = self.zone_index(ops.slave_dofs.ravel()).reshape(ops.slave_dofs.shape)
        weighted = ops.F_slave * ops.weight[:, None, None]
        # the new points alone, rank by rank (their order in the blocks)
        first_new = counts[comm.rank] - new
        new_rows = new_firsts[comm.rank] - m_old + np.arange(3 * new)
        E_new = self._point_matrix(new_rows, cols[first_new:], ops.E_slave[first_new:], m_new)
        F_new = self._point_matrix(new_rows, cols[first_new:], weighted[first_new:], m_new)
        nb_old = len(self.band)
        band = np.asarray(band, dtype=np.int64)
        self.band = np.concatenate([self.band, band])
        self._band_rows()
        nb = len(self.band)
        m = 3 * self.points
        # the earlier blocks in their top-left corners, the new rows and columns zero
        blocks = self._blocks
        Q_ss, Q_sb = blocks["Q_ss"].grow(m, m), blocks["Q_sb"].grow(m, nb)
        R_bs, Z_bb = blocks["R_bs"].grow(nb, m), blocks["Z_bb"].grow(nb, nb)
        new_points, new_band = slice(m_old, m), slice(nb_old, nb)
        # A^-1 F_N^T W: the new points' columns of Q_ss and R_bs
        EX, _, Xb = self._solve(m_new, F_new)
        transpose(EX, out=Q_ss[:, new_points])
        transpose(Xb, out=R_bs[:, new_points])
        if m_old:  # A^-1 E_N^T: the new points' rows of Q_ss and Q_sb (A symmetric)
            _, FX, Xb = self._solve(m_new, E_new)
            Q_ss[new_points, :m_old] = FX[:, :m_old]
            Q_sb[new_points, :nb_old] = Xb[:, :nb_old]
        if nb > nb_old:  # A^-1 I_bN: the new band's columns of Q_sb and Z_bb, rows of R_bs
            EX, FX, Xb = self._solve(nb - nb_old, None, unit=nb_old)
            transpose(EX, out=Q_sb[:, new_band])
            transpose(Xb, out=Z_bb[:, new_band])
            Z_bb[new_band, :nb_old] = Xb[:, :nb_old]
            R_bs[new_band, :m_old] = FX[:, :m_old]
        E_new.destroy()
        F_new.destroy()
        self._Q_bs = None

    def _matrices(self) -> tuple[PETSc.Mat, PETSc.Mat]:
        """E_s and F_s W of the points (rows rank by rank)."""
        if self._E is None or self._F is None:
            raise RuntimeError("ContactCompliance: no points added yet")
        return self._E, self._F

    def _band_rows(self) -> None:
        """The band's zone rows (``_band_zone``, in band order) and this rank's of them (local
        indices ``_band_local``, at the band positions ``_band_owned``)."""
        band_rows = self.zone_index(self.band) if len(self.band) else np.zeros(0, np.int64)
        owned = (band_rows >= self.start) & (band_rows < self.end)
        self._band_owned = np.flatnonzero(owned)
        self._band_local = band_rows[owned] - self.start
        self._band_zone = band_rows
        self._band_order = np.argsort(_gather_rows(self.comm, self._band_owned), kind="stable")
        self._band_sort = np.argsort(self.band, kind="stable")

    def _gather_band(self, local: npt.NDArray) -> npt.NDArray:
        """The band rows of this rank's rows ``local`` gathered, in band order."""
        return _gather_rows(self.comm, local[self._band_local])[self._band_order]

    def _point_matrix(self, rows, cols, values, m: int) -> PETSc.Mat:
        """The AIJ matrix (m x zone) with the points' 3 rows each on their zone columns."""
        mat = PETSc.Mat().create(comm=self.A.getComm())
        mat.setSizes(((len(rows), m), (self.end - self.start, self.A.getSize()[0])))
        mat.setType(PETSc.Mat.Type.AIJ)
        r = np.repeat(rows.reshape(-1, 3), cols.shape[1], axis=1).ravel()
        c = np.repeat(cols, 3, axis=0).ravel()
        mat.setPreallocationCOO(
            cast(Sequence[int], r.astype(PETSc.IntType)),
            cast(Sequence[int], c.astype(PETSc.IntType)),
        )
        mat.setValuesCOO(values.ravel())
        mat.assemble()
        return mat

    def _solve(
        self, n: int, B: PETSc.Mat | None, unit: int = 0
    ) -> tuple[npt.NDArray, npt.NDArray, npt.NDArray]:
        """For the n solutions X = A^-1 C of the columns of B^T (B given) or of the unit
        vectors of band dofs unit, unit + 1, ... (B None): (E X, F W X) in the blocks' row order
        and X on the band, in band order, on every rank, each transposed (n rows, C order).
        Each rank solves a contiguous share of the columns with its full copy of the factors
        (:meth:`_column_solver`) and the shares are gathered (into kept arrays: the results hold
        until the next call)."""
        share = np.array_split(np.arange(n), self.comm.size)[self.comm.rank]
        first = share[0] if len(share) else 0
        if B is not None:  # B's rows are the columns to solve for, its columns zone dofs
            B_full = _full_copy(B)
            indptr, zone, values = B_full.getValuesCSR()
            B_full.destroy()
            rhs = np.repeat(np.arange(len(indptr) - 1), np.diff(indptr))

        def entries(c0: int, c1: int):
            if B is not None:
                inside = slice(indptr[first + c0], indptr[first + c1])
                return zone[inside], rhs[inside] - first - c0, values[inside]
            j = np.arange(c0, c1)
            return self._band_zone[unit + first + j], j - c0, np.ones(c1 - c0)

        EX: list[npt.NDArray] = []
        FX: list[npt.NDArray] = []
        Xb: list[npt.NDArray] = []

        def consume(X: PETSc.Mat, c0: int, c1: int) -> None:
            for mat, out in ((E, EX), (F, FX)):
                product = mat.matMult(X)
                out.append(self.to_block(product.getDenseArray()[:, : c1 - c0]))
                product.destroy()
            Xb.append(X.getDenseArray()[self._band_zone, : c1 - c0])

        A, factor = self._column_solver()
        width = self.width if self._fixed_width else max(1, min(self.width, len(share)))
        E, F = (_full_copy(mat) for mat in self._matrices())
        try:
            solve_columns(factor, A, len(share), entries, consume, width, self._sparse)
        finally:
            for mat in (E, F):
                mat.destroy()

        def joined(name: str, parts: list[npt.NDArray], rows: int) -> npt.NDArray:
            columns = np.vstack([part.T for part in parts]) if parts else np.zeros((0, rows))
            return _gather_columns(self.comm, columns, self._gathered.get(name, (n, rows)))

        m = 3 * self.points
        return joined("EX", EX, m), joined("FX", FX, m), joined("Xb", Xb, len(self.band))

    def _column_solver(self) -> tuple[PETSc.Mat, PETSc.Mat]:
        """The operator and LU factors of :meth:`_solve`: on several ranks a full copy of A and
        its factors on every rank, made at the first call (each rank's column solves then need
        no communication; with MUMPS about 4 times fewer seconds per column on 2 ranks for the
        compliance blocks of the converged joint than with the distributed factors), on one
        rank A's own."""
        if self.comm.size == 1:
            return self.A, self.lu.getPC().getFactorMatrix()
        if self._copy is None:
            A = _full_copy(self.A)
            copy = direct_solver(MPI.COMM_SELF, A, self._package, prefix="compliance_columns_")
            A.destroy()
            try:
                copy.setUp()
                factorised = True
            except PETSc.Error:
                factorised = False
            if not self.comm.allreduce(factorised, op=MPI.LAND):  # fail on every rank alike
                copy.destroy()
                raise RuntimeError(
                    "the sequential factorisation of the contact zone's operator failed on some "
                    "rank (memory?); run on fewer ranks per node"
                )
            self._copy = copy
        return self._copy.getOperators()[0], self._copy.getPC().getFactorMatrix()

    # -- per pairing ----------------------------------------------------------------------------
    def master_operator(self, dofs: npt.NDArray, values: npt.NDArray) -> "MasterOperator | None":
        """M_b (3 |points| x |band|): all points' master parts (``PointOperators.master_dofs`` and
        ``master``, in the blocks' point order) on the band; None if a dof lies outside it."""
        n = len(dofs)
        if n and len(self.band) == 0:
            return None
        sorted_band = self.band[self._band_sort]
        position = np.minimum(np.searchsorted(sorted_band, dofs.ravel()), len(self.band) - 1)
        if n and not np.array_equal(sorted_band[position], dofs.ravel()):
            return None
        index = self._band_sort[position].reshape(dofs.shape) if n else dofs
        return MasterOperator(index, values, len(self.band))

    @timed("compliance")
    def matrix(self, M_b: "MasterOperator", weight: npt.NDArray) -> npt.NDArray:
        """G (3 |points| x 3 |points|, Fortran order: its transpose's rows are contiguous) for
        the master operator M_b and the points' weights w / gamma (``PointOperators.weight``,
        gathered) [m^3/Pa]: Q_ss + M_b R_bs + (Q_sb M_b^T + M_b Z_bb M_b^T) W, built as
        G^T = W (M_b Q_sb^T + M_b Z_bb M_b^T) + (Q_ss + M_b R_bs)^T (Z_bb is symmetric)."""
        Q_bs = self._Q_bs if self._Q_bs is not None else transpose(self.Q_sb)
        self._Q_bs = Q_bs
        GT = M_b.times(Q_bs)
        GT += M_b.times(transpose(M_b.times(self.Z_bb)))
        GT *= np.repeat(weight, 3)[:, None]
        GT += transpose(self.Q_ss + M_b.times(self.R_bs))
        return GT.T

    # -- per iteration --------------------------------------------------------------------------
    @timed("triangular solves")
    def solve(self, rhs: PETSc.Vec, out: PETSc.Vec) -> None:
        """out = A^-1 rhs (zone vectors)."""
        self.lu.solve(rhs, out)

    def apply_E(self, d: PETSc.Vec, M_b: "MasterOperator") -> npt.NDArray:
        """E d (3 |points|, on every rank) of a zone vector d."""
        if self.points == 0:
            return np.zeros(0)
        E, _ = self._matrices()
        y = E.createVecLeft()
        E.mult(d, y)
        Ed = self.to_block(_gather_rows(self.comm, y.array_r))
        y.destroy()
        return Ed + M_b.times(self._gather_band(d.array_r))

    def load(
        self, v: npt.NDArray, M_b: "MasterOperator", weight: npt.NDArray, out: PETSc.Vec
    ) -> None:
        """out = F^T W v (zone vector) [N] of tractions v (3 |points|, the same on every rank) [Pa]
        with the points' weights w / gamma [m^3/Pa]."""
        if self.points == 0:
            out.set(0.0)
            return
        _, F = self._matrices()
        x = F.createVecLeft()
        first = x.getOwnershipRange()[0]
        x.array[:] = v[self._to_block[first : first + x.getLocalSize()]]
        F.multTranspose(x, out)
        x.destroy()
        master = M_b.transpose_times(np.repeat(weight, 3) * v)
        out.array[self._band_local] += master[self._band_owned]

    def destroy(self) -> None:
        for obj in (self.lu, self._copy, self._E, self._F):
            if obj is not None:
                obj.destroy()
