"""The LU factorisations of A + J_c that the contact Newton solver keeps, one per contact state.

Under vibration the joint alternates between a few contact states (stick, slip down, slip
up); each is served by its own factors instead of a refactorisation at every transition. A
correction takes the kept factors whose contact status is nearest the iterate's; a new
factorisation replaces the least recently used one. With a ``zone`` (the condensed system of
``solver.dynamics.condensation``) only the zone block of A + J_c is factorised.
"""

from dataclasses import dataclass

import numpy as np
from mpi4py import MPI
from petsc4py import PETSc

from common.timing import timed
from solver.dynamics.linear_algebra import direct_solver

__all__ = ["FactorStore", "Factors"]


@dataclass
class Factors:
    """A factorised P = A + J_P (its zone block with a zone): the matrix, its LU solver, J_P, the
    sparsity tag of J_P, the contact status J_P was assembled at (the states it suits), the
    workspace J - J_P and when it was last used."""

    P: PETSc.Mat
    lu: PETSc.KSP
    J_P: PETSc.Mat
    pattern: int | None
    status: np.ndarray
    D: PETSc.Mat | None = None
    used: int = 0

    def destroy(self) -> None:
        for obj in (self.P, self.lu, self.J_P, self.D):
            if obj is not None:
                obj.destroy()


class FactorStore:
    """Up to ``kept`` factorisations of A + J (collective: every rank holds its part of each).

    Args:
        A: the bulk operator the factors belong to (``set_operator`` replaces its values).
        zone: global dofs (this rank's part) of the factorised block; None: all of A.
        lu_solver: PETSc factorisation package ("mumps", "superlu_dist", "petsc").
        kept: number of factorisations kept at once (>= 1).
    """

    def __init__(self, A: PETSc.Mat, zone: PETSc.IS | None, lu_solver: str, kept: int):
        if kept < 1:
            raise ValueError(f"factorisations_kept must be >= 1, got {kept}")
        self.kept, self.zone, self.lu_solver = kept, zone, lu_solver
        self._comm = A.getComm().tompi4py()
        self._A = A if zone is None else A.createSubMatrix(zone, zone)
        self._factors: list[Factors] = []  # valid for the current A
        self._spare: list[Factors] = []  # factors of an earlier A: their objects are reused
        self._uses = 0
        self.factorizations = 0  #: numeric factorisations so far

    @property
    def empty(self) -> bool:
        """No factors valid for the current A."""
        return not self._factors

    def set_operator(self, A: PETSc.Mat) -> None:
        """A has new values in the same sparsity: the kept factors become spares (their objects,
        and their orderings where the sparsity allows, are reused)."""
        if self.zone is not None:
            A.createSubMatrix(self.zone, self.zone, submat=self._A)
        else:
            self._A = A
        self._spare += self._factors
        self._factors = []

    @timed("factorisation")
    def factorise(self, J: PETSc.Mat, status: np.ndarray) -> Factors:
        """Factorise A + J into a new slot, or the least recently used one, and return it. When J
        carries the ``coo_pattern`` tag of the slot's J (``NitscheContact`` tags its Jacobians),
        A + J has the same sparsity: the matrix is refilled in place and only the numeric
        factorisation is redone."""
        pattern = J.getAttr("coo_pattern")
        if len(self._factors) < self.kept:
            slot = self._spare.pop() if self._spare else None
        else:
            slot = min(self._factors, key=lambda f: f.used)
            self._factors.remove(slot)
        J_zone = J if self.zone is None else J.createSubMatrix(self.zone, self.zone)
        same = slot is not None and pattern is not None and pattern == slot.pattern
        if self._comm.allreduce(same, op=MPI.LAND):  # collective: both branches are
            slot.P.zeroEntries()
            slot.P.axpy(1.0, self._A, PETSc.Mat.Structure.SUBSET_NONZERO_PATTERN)
            slot.P.axpy(1.0, J_zone, PETSc.Mat.Structure.SUBSET_NONZERO_PATTERN)
            J.copy(slot.J_P, PETSc.Mat.Structure.SAME_NONZERO_PATTERN)
        else:
            P = self._A.copy()
            P.axpy(1.0, J_zone, PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN)
            if slot is None:
                slot = Factors(
                    P, direct_solver(self._comm, package=self.lu_solver), J.copy(), pattern, status
                )
            else:
                for old in (slot.P, slot.J_P):
                    old.destroy()
                slot.P, slot.J_P, slot.pattern = P, J.copy(), pattern
        if J_zone is not J:
            J_zone.destroy()
        if slot.D is not None:
            slot.D.destroy()
        slot.D, slot.status = None, status.copy()
        slot.lu.setOperators(slot.P)
        slot.lu.setUp()
        self._factors.append(slot)
        self.factorizations += 1
        return self.use(slot)

    def use(self, factors: Factors) -> Factors:
        """Mark ``factors`` as the most recently used and return them."""
        self._uses += 1
        factors.used = self._uses
        return factors

    def nearest(self, status: np.ndarray) -> Factors:
        """The kept factors whose contact status differs from ``status`` at the fewest points (all
        ranks), the most recently used on a tie; marked as used."""
        mismatch = self._comm.allreduce(
            np.array([np.count_nonzero(f.status != status) for f in self._factors]), op=MPI.SUM
        )
        return self.use(min(zip(mismatch, self._factors), key=lambda m: (m[0], -m[1].used))[1])

    def destroy(self) -> None:
        for factors in self._factors + self._spare:
            factors.destroy()
        if self.zone is not None:
            self._A.destroy()
