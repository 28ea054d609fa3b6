"""Coupling of MP and TP in the modal analysis through the contact interface.

The interface stiffness is the linear tangent of the Nitsche contact
(:meth:`solver.contact.nitsche.NitscheContact.interface_stiffness`) for a fixed per-point
status: STICK ties normal and tangential relative motion, SLIP the normal motion
only, OPEN nothing. The symmetric Nitsche variant (theta = 1) keeps K symmetric,
as the generalized symmetric eigenproblem requires. A bonded band of height H [m]
at the TP's lower edge is the status "STICK within H of the lowest TP contact
point, OPEN elsewhere"; a settled contact state is the status of an equilibrium
computed by the contact solver. Both go through the same class.
"""

from common import backend  # noqa: F401  (before dolfinx/petsc4py)

import numpy as np
import numpy.typing as npt
from dolfinx import fem
from mpi4py import MPI
from petsc4py import PETSc

from common.material import Material
from geometry import tags
from solver.contact import FrictionLaw, NitscheContact, Status


class ContactInterface:
    """Interface stiffness [N/m] of a contact for a fixed status of its slave points."""

    def __init__(self, contact: NitscheContact, status: npt.NDArray | Status):
        if contact.theta != 1:
            raise ValueError(
                "modal analysis needs the symmetric Nitsche variant (theta = 1), "
                f"got {contact.theta}"
            )
        self.contact = contact
        self.status = np.broadcast_to(
            np.asarray(status, dtype=np.int8), (contact.slave.num_points,)
        ).copy()

    def stiffness(self, V: fem.FunctionSpace) -> PETSc.Mat:
        if V is not self.contact.V:
            raise ValueError("ContactInterface: the space differs from the contact's space")
        return self.contact.interface_stiffness(self.status)

    def tied_fraction(self) -> float:
        """Fraction of the slave points (all ranks) that are tied (STICK or SLIP) [-]."""
        comm = self.contact.V.mesh.comm
        tied = comm.allreduce(int(np.count_nonzero(self.status != Status.OPEN)))
        return tied / comm.allreduce(len(self.status))


def band_status(contact: NitscheContact, height: float, axis: int = 2) -> npt.NDArray:
    """STICK for the slave points of ``contact`` within ``height`` [m] of the slave surface's
    lowest point along ``axis`` (e.g. a bonded band at the TP lower edge), OPEN elsewhere
    (reference coordinates)."""
    if not height >= 0:
        raise ValueError(f"band height must be >= 0 m, got {height}")
    z = contact.slave.points[:, axis]
    z_min = contact.V.mesh.comm.allreduce(z.min() if len(z) else np.inf, op=MPI.MIN)
    return np.where(z <= z_min + height, Status.STICK, Status.OPEN).astype(np.int8)


def bonded_band(
    V: fem.FunctionSpace, facet_tags, material: Material, height: float, gamma0: float = 100.0
) -> ContactInterface:
    """TP inner cone (slave) stuck to the MP outer cone within ``height`` [m] of the TP's
    lower edge."""
    if not height > 0:
        raise ValueError(f"bonded band height must be positive, got {height} m")
    contact = NitscheContact(
        V,
        facet_tags,
        tags.TP_CONTACT,
        tags.MP_CONTACT,
        material,
        FrictionLaw(),
        gamma0=gamma0,
        theta=1,
    )
    return ContactInterface(contact, band_status(contact, height))
