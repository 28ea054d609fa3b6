"""What a contact object is: the per-point status and state, and the interface that the time
stepping (``solver.dynamics``) and the Newton solver call on it.

Two implementations: ``solver.contact.nitsche.NitscheContact`` (two deformable bodies of one
mesh, closest-point pairing) and ``solver.contact.rigid.RigidPlaneContact`` (a body against
a rigid plane, UFL). Forces in N, displacements in m, tractions in Pa.
"""

from collections.abc import Mapping
from dataclasses import dataclass
from enum import IntEnum
from typing import Protocol

import dolfinx
import numpy as np
import numpy.typing as npt
from petsc4py import PETSc

__all__ = [
    "ContactModel",
    "ContactState",
    "PointOperators",
    "PointStates",
    "Status",
    "TrialTractions",
]


class Status(IntEnum):
    """Contact status of a slave quadrature point."""

    OPEN = 0
    STICK = 1
    SLIP = 2


@dataclass
class ContactState:
    """Per slave quadrature point (this rank's points) state after the last update [SI units]."""

    status: npt.NDArray  #: Status values (OPEN also for points without a master partner)
    gap: npt.NDArray  #: normal gap g [m] (nan where unpaired)
    pressure: npt.NDArray  #: contact pressure p = -lambda_n >= 0 [Pa]
    tangential_traction: npt.NDArray  #: friction traction lambda_t on the slave (np, 3) [Pa]
    slip_velocity: npt.NDArray  #: ds / dt (np, 3) [m/s] (zero in quasi-static steps without dt)
    coordinates: npt.NDArray  #: deformed slave points x (np, 3) [m]
    weights: npt.NDArray  #: surface quadrature weights (reference configuration) [m^2]
    normal: npt.NDArray  #: n = -n_m, the contact normal pointing out of the slave (np, 3)


@dataclass
class TrialTractions:
    """Per slave point (this rank's): the trial traction P = P_n n + P_t (np, 3) [Pa], the contact
    normal n (np, 3), the friction coefficient mu (np,), whether the point is paired and its gap."""

    traction: npt.NDArray
    normal: npt.NDArray
    mu: npt.NDArray
    paired: npt.NDArray
    gap: npt.NDArray  #: normal gap [m] (nan where unpaired)


@dataclass
class PointOperators:
    """Linear operators of points q on global (unrolled) dofs: E = E_slave + master and
    F = F_slave + master, E_slave and F_slave (q, 3, nd_s) on ``slave_dofs`` (q, nd_s), the master
    part (q, 3, nd_m) on ``master_dofs`` (q, nd_m) [Pa/m]; ``weight`` w / gamma (q,) [m^3/Pa]."""

    slave_dofs: npt.NDArray
    E_slave: npt.NDArray
    F_slave: npt.NDArray
    master_dofs: npt.NDArray
    master: npt.NDArray
    weight: npt.NDArray


class PointStates(Protocol):
    """The per-point state every contact model reports (this rank's contact points)."""

    status: npt.NDArray  #: Status values
    gap: npt.NDArray  #: normal gap [m]
    pressure: npt.NDArray  #: contact pressure >= 0 [Pa]
    tangential_traction: npt.NDArray  #: friction traction on the body (n, gdim) [Pa]
    slip_velocity: npt.NDArray  #: slip velocity (n, gdim) [m/s]


class ContactModel(Protocol):
    """Everything ``Elastodynamics`` and ``ContactNewtonSolver`` call on a contact object.

    A step: ``set_reference(u_n, dt)``, then at each iterate ``update(u)`` and
    ``residual()`` / ``jacobian()`` (PETSc objects in the layout of V, owned by the model and
    overwritten by the next call: a caller copies what it keeps).
    A model without a capability implements it trivially (a rigid plane has no round-off
    floor estimate, no reversal limit and no memory beyond the step).
    """

    #: local cells whose dofs the contact residual and Jacobian involve (the zone that
    #: ``solver.dynamics.condensation`` keeps)
    support_cells: npt.NDArray[np.int32]

    @property
    def state(self) -> PointStates:
        """Status, gap, pressure, friction traction, slip velocity at the last update."""
        ...

    def set_reference(self, u_old: dolfinx.fem.Function, dt: float | None) -> None:
        """Start a step from u_old; slip velocities are increments over dt [s] (None: rate-free)."""
        ...

    def update(self, u: dolfinx.fem.Function) -> None:
        """Evaluate the contact state at the iterate u."""
        ...

    def updated_at(self, u: dolfinx.fem.Function) -> bool:
        """Whether the last ``update`` was at u's present values, on every rank (False: update)."""
        ...

    def residual(self) -> PETSc.Vec:
        """Contact residual r_c at the last update [N]."""
        ...

    def jacobian(self) -> PETSc.Mat:
        """Generalized derivative d r_c / d u at the last update [N/m]."""
        ...

    def residual_floor(self) -> float:
        """Round-off level of ||r_c|| at the last update [N] (0: no estimate), on every rank."""
        ...

    def slip_directions(self) -> tuple[npt.NDArray, npt.NDArray]:
        """The slipping points at the last update and their trial tractions [Pa] (this rank)."""
        ...

    def reversal_limit(self, slipping: npt.NDArray, P_t0: npt.NDArray) -> float:
        """Largest fraction (<= 1, this rank) of the step from the ``slip_directions`` iterate to
        the last update before a slipping point's friction reverses (1: no limit)."""
        ...

    def memory(self) -> dict[str, npt.NDArray]:
        """This rank's state carried from one step to the next (for checkpoints)."""
        ...

    def restore_memory(self, memory: Mapping[str, npt.NDArray]) -> None:
        """Set the state carried between steps (after ``update`` at the restored u)."""
        ...
