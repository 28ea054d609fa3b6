"""The residual of a contact step, F = A u - b + r_c(u) with the Dirichlet rows zeroed, and the
Dirichlet rows themselves: shared by the Newton solvers of ``solver.dynamics.newton`` and
``solver.dynamics.point_newton``. Forces in N.
"""

from typing import cast

import numpy as np
from petsc4py import PETSc

import dolfinx

from solver.contact.model import ContactModel

__all__ = ["contact_residual", "dirichlet_rows"]


def dirichlet_rows(bcs: list[dolfinx.fem.DirichletBC]) -> tuple[np.ndarray, np.ndarray]:
    """The Dirichlet dofs of ``bcs``: this rank's owned ones as global (unrolled) rows, and its
    local ones (owned and ghost) as indices into the local array."""
    rows = []
    for bc in bcs:
        dofs, _ = bc.dof_indices()
        imap, bs = bc.function_space.dofmap.index_map, bc.function_space.dofmap.index_map_bs
        owned = dofs[dofs < imap.size_local * bs]
        rows.append(imap.local_to_global(owned // bs) * bs + owned % bs)
    global_rows = (
        np.unique(np.concatenate(rows)).astype(PETSc.IntType)
        if rows
        else np.zeros(0, PETSc.IntType)
    )
    local = (
        np.unique(np.concatenate([bc.dof_indices()[0] for bc in bcs]))
        if bcs
        else np.zeros(0, np.int32)
    )
    return global_rows, local


def contact_residual(
    linear: PETSc.Vec,
    contact: ContactModel,
    u: dolfinx.fem.Function,
    F: PETSc.Vec,
    bc_local: np.ndarray,
    update: bool = True,
) -> float:
    """F = linear + r_c(u) with linear = A u - b (the contact updated at u unless ``update`` is
    False), zero on the Dirichlet dofs ``bc_local``; returns ||F||."""
    if update:
        contact.update(u)
    rc = contact.residual()
    with rc.localForm() as loc:
        loc.array[bc_local[bc_local < loc.array.size]] = 0.0
    linear.copy(F)
    F.axpy(1.0, rc)
    return cast(float, F.norm())
