"""Static condensation of the linear bulk away from the contact surfaces.

In A u + r_c(u) = b (A: the Newmark effective stiffness, or K when quasi-static) the contact
residual r_c and its Jacobian only involve the dofs of the cells with a slave or master facet
(the zone Z); the other dofs (the bulk B) enter linearly. Eliminating them gives

    S u_Z + r_c(u_Z) = b_Z - A_ZB A_BB^-1 b_B,   S = A_ZZ - A_ZB A_BB^-1 A_BZ,
    u_B = A_BB^-1 (b_B - A_BZ u_Z).

A_ZB only couples the interface I (the Z dofs that bulk cells share: for the slip-joint the
rings where the contact zone meets the rest of each cone). The bulk falls apart into parts
that share no dof (for the slip-joint: the MP below and above the zone and the TP above it),
so A_BB is block diagonal: each part k is factorised on its own, and S is A_ZZ plus one dense
block on I_k x I_k per part, built from |I_k| solves with part k's factors only. The Newton
solver is handed the full-size system

    A_hat = [[S, 0], [0, 1]],   b_hat = [b_Z - A_ZB A_BB^-1 b_B,  u_B],

whose bulk rows are identities holding u_B fixed, so its LU factors (and every solve with
them) only cover the zone. A step then costs two solves with the constant bulk factors (the
load, and recovering u_B after Newton); a new operator A (another time step) costs the |I_k|
solves per part again, with the factorisations' orderings kept.
"""

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
import scipy.sparse
import scipy.sparse.csgraph
from mpi4py import MPI
from petsc4py import PETSc

import dolfinx
import dolfinx.la.petsc

from common.timing import timed
from solver.dynamics.linear_algebra import direct_solver, solve_columns

__all__ = ["BulkCondensation", "bulk_parts"]


def _dof_marker(
    V: dolfinx.fem.FunctionSpace, cells: npt.NDArray[np.int32]
) -> npt.NDArray[np.bool_]:
    """Owned dofs (unrolled, block size included) of the given owned cells, on any rank."""
    imap, bs = V.dofmap.index_map, V.dofmap.index_map_bs
    marker = dolfinx.la.vector(imap, bs)
    marker.array[:] = 0.0
    blocks = np.unique(V.dofmap.list[cells].ravel())
    marker.array[(blocks[:, None] * bs + np.arange(bs)).ravel()] = 1.0
    marker.scatter_reverse(dolfinx.la.InsertMode.add)
    return marker.array[: imap.size_local * bs] > 0


def bulk_parts(V: dolfinx.fem.FunctionSpace, cells: npt.NDArray[np.int32]) -> npt.NDArray[np.int64]:
    """Connected parts of the given owned cells, joined through shared nodes (on all ranks):
    for every owned node (block of V) the index 0, 1, ... of the part whose cells hold it, the
    same on every rank; -1 for nodes of none of the cells.

    Within a rank the cell-node graph's components are found directly; across ranks, the
    smallest global node index of each part spreads through the shared nodes (a ghost update
    taking the maximum of minus the labels) until no label changes.
    """
    imap = V.dofmap.index_map
    comm = imap.comm
    n_nodes = imap.size_local + imap.num_ghosts
    nodes = V.dofmap.list[cells]
    incidence = scipy.sparse.coo_matrix(
        (np.ones(nodes.size), (np.repeat(np.arange(len(cells)), nodes.shape[1]), nodes.ravel())),
        shape=(len(cells), n_nodes),
    ).tocsr()
    graph = scipy.sparse.bmat([[None, incidence], [incidence.T, None]])
    _, component = scipy.sparse.csgraph.connected_components(graph, directed=False)
    component = component[len(cells) :]  # the nodes' components
    used = np.zeros(n_nodes, dtype=bool)
    used[nodes.ravel()] = True
    never = np.iinfo(np.int64).max
    global_index = imap.local_to_global(np.arange(n_nodes, dtype=np.int32))
    labels = np.full(n_nodes, never, dtype=np.int64)
    vec = dolfinx.la.petsc.create_vector([(imap, 1)])
    while True:
        # the smallest label of each local component, on all of its nodes
        smallest = np.full(component.max() + 1 if n_nodes else 0, never, dtype=np.int64)
        np.minimum.at(smallest, component[used], np.minimum(labels[used], global_index[used]))
        new = np.where(used, smallest[component], never)
        with (
            vec.localForm() as loc
        ):  # the minimum over ranks as a maximum of -label (exact in float64)
            loc.array[:] = np.where(used, -new.astype(np.float64), -np.inf)
        vec.ghostUpdate(addv=PETSc.InsertMode.MAX_VALUES, mode=PETSc.ScatterMode.REVERSE)
        vec.ghostUpdate(addv=PETSc.InsertMode.INSERT_VALUES, mode=PETSc.ScatterMode.FORWARD)
        with vec.localForm() as loc:
            spread = np.where(used, -loc.array, 0).astype(np.int64)
        spread[~used] = never
        changed = comm.allreduce(bool(np.any(spread != labels)), op=MPI.LOR)
        labels = spread
        if not changed:
            break
    vec.destroy()
    owned = labels[: imap.size_local]
    names = np.unique(np.concatenate(comm.allgather(np.unique(owned[owned != never]))))
    return np.where(owned == never, -1, np.searchsorted(names, owned))


@dataclass
class _Part:
    """One bulk part: its dofs (local positions among the owned dofs), its interface dofs (local
    positions; global indices of all ranks'), the blocks of A, the direct solver of A_kk and
    work vectors (x, y on the part, w on its interface)."""

    bulk: npt.NDArray
    interface: npt.NDArray
    interface_global: npt.NDArray
    is_bulk: PETSc.IS
    is_interface: PETSc.IS
    A_kk: PETSc.Mat
    A_ki: PETSc.Mat
    A_ik: PETSc.Mat
    ksp: PETSc.KSP
    x: PETSc.Vec
    y: PETSc.Vec
    w: PETSc.Vec

    def extract(self, A: PETSc.Mat) -> None:
        """The part's blocks of A (new values, same sparsity)."""
        for block, rows, cols in (
            (self.A_kk, self.is_bulk, self.is_bulk),
            (self.A_ki, self.is_bulk, self.is_interface),
            (self.A_ik, self.is_interface, self.is_bulk),
        ):
            A.createSubMatrix(rows, cols, submat=block)

    def destroy(self) -> None:
        for obj in (
            self.is_bulk,
            self.is_interface,
            self.A_kk,
            self.A_ki,
            self.A_ik,
            self.ksp,
            self.x,
            self.y,
            self.w,
        ):
            obj.destroy()


class BulkCondensation:
    """The condensed system (A_hat, b_hat) of ``A`` for contact acting on ``zone_cells``.

    Args:
        A: assembled operator (Dirichlet rows/columns as identities) on V.
        V: its function space.
        zone_cells: local cells (owned or ghost) whose dofs the contact residual involves
            (``ContactModel.support_cells``).
        lu_solver: factorisation package of the bulk parts.
        chunk: interface columns per multiple-right-hand-side solve when building S.
    """

    @timed("condensation")
    def __init__(
        self,
        A: PETSc.Mat,
        V: dolfinx.fem.FunctionSpace,
        zone_cells: npt.NDArray[np.int32],
        lu_solver: str = "mumps",
        chunk: int = 64,
    ):
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
        bs = V.dofmap.index_map_bs
        part_of_dof = np.repeat(bulk_parts(V, owned[~in_zone]), bs)
        start = A.getOwnershipRange()[0]
        self._Z, self._B, self._I = (
            np.flatnonzero(m).astype(PETSc.IntType) for m in (zone, ~zone, interface)
        )
        #: the zone's dofs (global indices, this rank's part): A_hat is block diagonal in (zone, bulk)
        self.zone = PETSc.IS().createGeneral(start + self._Z, comm=comm)
        n_parts = self._comm.allreduce(int(part_of_dof.max(initial=-1)) + 1, op=MPI.MAX)
        self.sizes = {
            name: self._comm.allreduce(len(d), op=MPI.SUM)
            for name, d in (("zone", self._Z), ("bulk", self._B), ("interface", self._I))
        } | {"parts": n_parts}
        self._parts = []
        for k in range(n_parts):
            bulk = np.flatnonzero(~zone & (part_of_dof == k)).astype(PETSc.IntType)
            ring = np.flatnonzero(interface & (part_of_dof == k)).astype(PETSc.IntType)
            is_bulk = PETSc.IS().createGeneral(start + bulk, comm=comm)
            is_interface = PETSc.IS().createGeneral(start + ring, comm=comm)
            A_kk = A.createSubMatrix(is_bulk, is_bulk)
            A_ki = A.createSubMatrix(is_bulk, is_interface)
            x, y = A_kk.createVecs()
            self._parts.append(
                _Part(
                    bulk,
                    ring,
                    np.concatenate(self._comm.allgather(start + ring)),
                    is_bulk,
                    is_interface,
                    A_kk,
                    A_ki,
                    A.createSubMatrix(is_interface, is_bulk),
                    direct_solver(comm, A_kk, lu_solver, prefix="condensation_"),
                    x,
                    y,
                    A_ki.createVecRight(),
                )
            )
        self._zone_marker, self._chunk = zone, chunk
        self._sparse = lu_solver == "mumps"  # sparse right-hand sides (solve_columns)
        self.A_hat: PETSc.Mat | None = None
        self._condense(A)

    @timed("condensation")
    def update(self, A: PETSc.Mat) -> None:
        """Condense new values of A (the same sparsity, e.g. another time step): the bulk parts are
        refactorised numerically and A_hat refilled in place (the solver objects are kept)."""
        for part in self._parts:
            part.extract(A)
        self._condense(A)

    def _condense(self, A: PETSc.Mat) -> None:
        for part in self._parts:
            part.ksp.setOperators(part.A_kk)
            part.ksp.setUp()
        self._condensed_operator(A, [self._schur_correction(part) for part in self._parts])

    def _schur_correction(self, part: _Part) -> npt.NDArray[np.float64]:
        """This rank's rows of A_ik A_kk^-1 A_ki of a part (dense, all its interface columns)."""
        n_i = part.A_ki.getSize()[1]
        R = part.A_ki.convert("dense", PETSc.Mat())
        columns = R.getDenseArray()  # this rank's rows of all interface columns
        rows = []

        def entries(c0: int, c1: int):
            rows, cols = np.nonzero(columns[:, c0:c1])
            return rows, cols, columns[rows, c0 + cols]

        def consume(X: PETSc.Mat, c0: int, c1: int) -> None:
            Y = part.A_ik.matMult(X)
            rows.append(Y.getDenseArray()[:, : c1 - c0].copy())
            Y.destroy()

        factor = part.ksp.getPC().getFactorMatrix()
        solve_columns(factor, part.A_kk, n_i, entries, consume, min(self._chunk, n_i), self._sparse)
        R.destroy()
        return np.hstack(rows) if rows else np.zeros((len(part.interface), 0))

    def _condensed_operator(self, A: PETSc.Mat, corrections: list[npt.NDArray]) -> None:
        """A_hat: A's zone rows and columns minus the parts' Schur corrections, identities on the
        bulk (created at the first call, refilled in its sparsity at later ones)."""
        comm, zone = self._comm, self._zone_marker
        start, end = A.getOwnershipRange()
        n, N = end - start, A.getSize()[0]
        zone_global = np.concatenate(comm.allgather(zone))
        indptr, cols, vals = A.getValuesCSR()
        rows = np.repeat(np.arange(n), np.diff(indptr))
        keep = zone[rows] & zone_global[cols]
        blocks = [
            (
                np.repeat(p.interface, len(p.interface_global)),
                np.tile(p.interface_global, len(p.interface)),
                -c.ravel(),
            )
            for p, c in zip(self._parts, corrections)
        ]
        all_rows = np.concatenate([rows[keep], self._B, *(b[0] for b in blocks)])
        all_cols = np.concatenate([cols[keep], start + self._B, *(b[1] for b in blocks)])
        all_vals = np.concatenate([vals[keep], np.ones(len(self._B)), *(b[2] for b in blocks)])
        csr = scipy.sparse.csr_matrix((all_vals, (all_rows, all_cols)), shape=(n, N))
        csr.sum_duplicates()
        csr.sort_indices()
        arrays = (csr.indptr.astype(PETSc.IntType), csr.indices.astype(PETSc.IntType), csr.data)
        if self.A_hat is None:
            self.A_hat = PETSc.Mat().createAIJ(((n, N), (n, N)), csr=arrays, comm=A.getComm())
        else:
            self.A_hat.setValuesCSR(*arrays)
        self.A_hat.assemble()

    @timed("condensation")
    def reduce_load(self, b: PETSc.Vec, out: PETSc.Vec) -> None:
        """out_Z = b_Z - A_ZB A_BB^-1 b_B (one bulk solve per part); out_B is left for ``hold_bulk``."""
        b.copy(out)
        for part in self._parts:
            part.x.array[:] = b.array_r[part.bulk]
            part.ksp.solve(part.x, part.y)
            part.A_ik.mult(part.y, part.w)
            out.array[part.interface] -= part.w.array_r

    def hold_bulk(self, u: dolfinx.fem.Function, out: PETSc.Vec) -> None:
        """out_B = u_B: the identity rows of A_hat keep the bulk where u has it."""
        out.array[self._B] = u.x.petsc_vec.array_r[self._B]

    @timed("condensation")
    def recover(self, b: PETSc.Vec, u: dolfinx.fem.Function) -> None:
        """u_B = A_BB^-1 (b_B - A_BI u_I) (one bulk solve), ghosts updated."""
        x = u.x.petsc_vec
        for part in self._parts:
            part.w.array[:] = x.array_r[part.interface]
            part.A_ki.mult(part.w, part.y)
            part.x.array[:] = b.array_r[part.bulk] - part.y.array_r
            part.ksp.solve(part.x, part.y)
            x.array[part.bulk] = part.y.array_r
        u.x.scatter_forward()

    def destroy(self) -> None:
        for obj in (self.zone, self.A_hat, *self._parts):
            obj.destroy()
