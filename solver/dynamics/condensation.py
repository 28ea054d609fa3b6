"""Static condensation of the linear bulk away from the contact surfaces.

In A u + r_c(u) = b (A: the Newmark effective stiffness, or K when quasi-static) the contact
residual r_c and its Jacobian only involve the dofs of the cells with a slave or master facet
(the zone Z); the other dofs (the bulk B) enter linearly. Eliminating them gives

    S u_Z + r_c(u_Z) = b_Z - A_ZB A_BB^-1 b_B,   S = A_ZZ - A_ZB A_BB^-1 A_BZ,
    u_B = A_BB^-1 (b_B - A_BZ u_Z).

A_ZB only couples the interface I (the Z dofs that bulk cells share: for the slip-joint the
rings where the contact zone meets the rest of each cone), so S is A_ZZ plus a dense block
on I x I, one per connected bulk part. The Newton solver is handed the full-size system

    A_hat = [[S, 0], [0, 1]],   b_hat = [b_Z - A_ZB A_BB^-1 b_B,  u_B],

whose bulk rows are identities holding u_B fixed, so its LU factors (and every solve with
them) only cover the zone. A step then costs two solves with the constant bulk factors (the
load, and recovering u_B after Newton), and building the condensation costs |I| solves with
them (as multiple right-hand sides), once per operator A.
"""

import numpy as np
import numpy.typing as npt
import scipy.sparse
from mpi4py import MPI
from petsc4py import PETSc

import dolfinx

from solver.dynamics.linear_algebra import direct_solver

__all__ = ["BulkCondensation"]


def _dof_marker(V: dolfinx.fem.FunctionSpace, cells: npt.NDArray[np.int32]) -> npt.NDArray[np.bool_]:
    """Owned dofs (unrolled, block size included) of the given owned cells, on any rank."""
    imap, bs = V.dofmap.index_map, V.dofmap.index_map_bs
    marker = dolfinx.la.vector(imap, bs)
    marker.array[:] = 0.0
    blocks = np.unique(V.dofmap.list[cells].ravel())
    marker.array[(blocks[:, None] * bs + np.arange(bs)).ravel()] = 1.0
    marker.scatter_reverse(dolfinx.la.InsertMode.add)
    return marker.array[: imap.size_local * bs] > 0


class BulkCondensation:
    """The condensed system (A_hat, b_hat) of ``A`` for contact acting on ``zone_cells``.

    Args:
        A: assembled operator (Dirichlet rows/columns as identities) on V.
        V: its function space.
        zone_cells: local cells (owned or ghost) whose dofs the contact residual involves
            (``ContactModel.support_cells``).
        lu_solver: factorisation package of the bulk.
        chunk: interface columns per multiple-right-hand-side solve when building S (64: 18 s
            against 25 s with 512 and 37 s with all 2592 at once, 48 around, 2 ranks).
    """

    def __init__(self, A: PETSc.Mat, V: dolfinx.fem.FunctionSpace, zone_cells: npt.NDArray[np.int32],
                 lu_solver: str = "mumps", chunk: int = 64):
        comm = A.getComm()
        self._comm = comm.tompi4py()
        topology = V.mesh.topology
        cell_map = topology.index_map(topology.dim)
        flag = dolfinx.la.vector(cell_map, 1)
        flag.array[:] = 0.0
        flag.array[zone_cells] = 1.0
        flag.scatter_reverse(dolfinx.la.InsertMode.add)  # owners learn of zone cells seen as ghosts
        owned = np.arange(cell_map.size_local, dtype=np.int32)
        in_zone = flag.array[: cell_map.size_local] > 0
        zone = _dof_marker(V, owned[in_zone])
        interface = zone & _dof_marker(V, owned[~in_zone])
        start = A.getOwnershipRange()[0]
        self._Z, self._B, self._I = (np.flatnonzero(m).astype(PETSc.IntType) for m in (zone, ~zone, interface))
        #: the zone's dofs (global indices, this rank's part): A_hat is block diagonal in (zone, bulk)
        self.zone = PETSc.IS().createGeneral(start + self._Z, comm=comm)
        is_B = PETSc.IS().createGeneral(start + self._B, comm=comm)
        is_I = PETSc.IS().createGeneral(start + self._I, comm=comm)
        self.sizes = {name: self._comm.allreduce(len(d), op=MPI.SUM) for name, d in
                      (("zone", self._Z), ("bulk", self._B), ("interface", self._I))}
        self.A_BB = A.createSubMatrix(is_B, is_B)
        self.A_BI = A.createSubMatrix(is_B, is_I)
        self.A_IB = A.createSubMatrix(is_I, is_B)
        for index_set in (is_B, is_I):
            index_set.destroy()
        self._ksp = direct_solver(comm, self.A_BB, lu_solver, prefix="condensation_")
        self._ksp.setUp()
        self._xB, self._yB = self.A_BB.createVecs()
        self._xI = self.A_IB.createVecLeft()
        self.A_hat = self._condensed_operator(A, zone, self._schur_correction(chunk))

    def _schur_correction(self, chunk: int) -> npt.NDArray[np.float64]:
        """This rank's interface rows of A_IB A_BB^-1 A_BI (dense, all interface columns)."""
        n_I = self.A_BI.getSize()[1]
        R = self.A_BI.convert("dense", PETSc.Mat())
        factor = self._ksp.getPC().getFactorMatrix()
        rows = []
        for c0 in range(0, n_I, chunk):
            c1 = min(c0 + chunk, n_I)
            view = R.getDenseSubMatrix(cbegin=c0, cend=c1)
            Rc = view.copy()
            R.restoreDenseSubMatrix(view)
            Xc = Rc.duplicate()
            factor.matSolve(Rc, Xc)
            Yc = self.A_IB.matMult(Xc)
            rows.append(Yc.getDenseArray().copy())
            for mat in (Rc, Xc, Yc):
                mat.destroy()
        R.destroy()
        return np.hstack(rows) if rows else np.zeros((len(self._I), 0))

    def _condensed_operator(self, A: PETSc.Mat, zone: npt.NDArray[np.bool_], correction) -> PETSc.Mat:
        """A_hat: A's zone rows and columns minus the Schur correction, identities on the bulk."""
        comm = self._comm
        start, end = A.getOwnershipRange()
        n, N = end - start, A.getSize()[0]
        zone_global = np.concatenate(comm.allgather(zone))
        indptr, cols, vals = A.getValuesCSR()
        rows = np.repeat(np.arange(n), np.diff(indptr))
        keep = zone[rows] & zone_global[cols]
        I_global = np.concatenate(comm.allgather(start + self._I))
        ci, cj = np.nonzero(correction)  # the blocks coupling different bulk parts are exact zeros
        all_rows = np.concatenate([rows[keep], self._B, self._I[ci]])
        all_cols = np.concatenate([cols[keep], start + self._B, I_global[cj]])
        all_vals = np.concatenate([vals[keep], np.ones(len(self._B)), -correction[ci, cj]])
        csr = scipy.sparse.csr_matrix((all_vals, (all_rows, all_cols)), shape=(n, N))
        csr.sum_duplicates()
        csr.sort_indices()
        A_hat = PETSc.Mat().createAIJ(((n, N), (n, N)), csr=(csr.indptr.astype(PETSc.IntType),
                                                             csr.indices.astype(PETSc.IntType), csr.data),
                                      comm=A.getComm())
        A_hat.assemble()
        return A_hat

    def reduce_load(self, b: PETSc.Vec, out: PETSc.Vec) -> None:
        """out_Z = b_Z - A_ZB A_BB^-1 b_B (one bulk solve); out_B is left for ``hold_bulk``."""
        self._xB.array[:] = b.array_r[self._B]
        self._ksp.solve(self._xB, self._yB)
        self.A_IB.mult(self._yB, self._xI)
        b.copy(out)
        out.array[self._I] -= self._xI.array_r

    def hold_bulk(self, u: dolfinx.fem.Function, out: PETSc.Vec) -> None:
        """out_B = u_B: the identity rows of A_hat keep the bulk where u has it."""
        out.array[self._B] = u.x.petsc_vec.array_r[self._B]

    def recover(self, b: PETSc.Vec, u: dolfinx.fem.Function) -> None:
        """u_B = A_BB^-1 (b_B - A_BI u_I) (one bulk solve), ghosts updated."""
        x = u.x.petsc_vec
        self._xI.array[:] = x.array_r[self._I]
        self.A_BI.mult(self._xI, self._yB)
        self._xB.array[:] = b.array_r[self._B] - self._yB.array_r
        self._ksp.solve(self._xB, self._yB)
        x.array[self._B] = self._yB.array_r
        u.x.scatter_forward()

    def destroy(self) -> None:
        for obj in (self.zone, self._ksp, self.A_BB, self.A_BI, self.A_IB, self.A_hat, self._xB, self._yB, self._xI):
            obj.destroy()
