"""What a contact object is: the per-point status and state, and the interface that the time
stepping (``solver.dynamics``) and the Newton solver call on it.

Two implementations: ``solver.contact.nitsche.NitscheContact`` (two deformable bodies of one
mesh, closest-point pairing) and ``solver.contact.rigid.RigidPlaneContact`` (a body against
a rigid plane, UFL). Forces in N, displacements in m, tractions in Pa.
"""

from dataclasses import dataclass
from enum import IntEnum

import numpy.typing as npt

__all__ = ["ContactState", "Status"]


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
