"""Frictional contact: the contact model (status, state, interface), the friction law, the
contact surfaces and their closest-point pairing, the Nitsche terms between two bodies of
one mesh and against a rigid plane (docs/contact.md).

==============  ==================================================================
``model``       Status, ContactState, trial tractions, point operators, ContactModel
``friction``    velocity-dependent Coulomb law mu(v)
``law``         pointwise contact law: multipliers from trial tractions, their derivative
``surfaces``    master facets (gathered) and slave quadrature points of a mesh
``pairing``     closest points of the slave points on the deformed master surface
``nitsche``     NitscheContact: state update, residual, generalized-Newton tangent
``assembly``    PETSc vectors and COO-cached matrices from per-point contributions
``rigid``       RigidPlaneContact: Nitsche contact with a rigid plane, in UFL
==============  ==================================================================
"""

from solver.contact.friction import FrictionLaw
from solver.contact.model import ContactModel, ContactState, PointStates, Status
from solver.contact.nitsche import NitscheContact
from solver.contact.pairing import Pairing, pair
from solver.contact.rigid import RigidPlaneContact
from solver.contact.surfaces import MasterSurface, SlaveQuadrature

__all__ = [
    "ContactModel",
    "ContactState",
    "FrictionLaw",
    "MasterSurface",
    "NitscheContact",
    "Pairing",
    "PointStates",
    "RigidPlaneContact",
    "SlaveQuadrature",
    "Status",
    "pair",
]
