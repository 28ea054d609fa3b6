"""Contact patch test: two blocks pressed together through a non-matching flat interface.

Base [0,1]^2 x [-0.5,0] on rollers at its bottom, block [0,1]^2 x [0,0.5] pushed down by
delta at its top, symmetry rollers on x = 0 and y = 0: uniaxial stress, so the exact
contact pressure is uniform, p = E delta / (H_base + H_block), for any friction.
"""

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np
import pytest

import dolfinx
from contact_cases import MASTER, SLAVE, elastic_system, fixed, gathered, two_blocks
from common.material import Material
from solver.contact import FrictionLaw, NitscheContact, Status
from solver.dynamics.newton import solve_contact_problem

pytestmark = pytest.mark.mpi


@pytest.mark.parametrize("degree", [1, 2])
# small gamma0 only for theta = 0, -1: the symmetric variant is not stable for it (with
# theta = 1, gamma0 = 1 Newton does not converge on the P2 blocks)
@pytest.mark.parametrize("theta, gamma0", [(1, 10.0), (0, 10.0), (-1, 10.0), (0, 1.0), (-1, 1.0)])
@pytest.mark.parametrize("mu", [0.0, 0.5])
def test_uniform_pressure(degree, theta, mu, gamma0):
    mesh, _, tags = two_blocks(MPI.COMM_WORLD, lower=(3, 3, 2), upper=(4, 5, 2))
    V = dolfinx.fem.functionspace(mesh, ("Lagrange", degree, (3,)))
    material = Material(E=1e9, nu=0.3)
    delta = 1e-3
    bcs = [
        fixed(V, 2, lambda x: np.isclose(x[2], -0.5)),
        fixed(V, 0, lambda x: np.isclose(x[0], 0.0)),
        fixed(V, 1, lambda x: np.isclose(x[1], 0.0)),
        fixed(V, 2, lambda x: np.isclose(x[2], 0.5), -delta),
    ]
    A, b = elastic_system(V, material, bcs)
    contact = NitscheContact(
        V, tags, SLAVE, MASTER, material, FrictionLaw(mu, mu, 0.0), gamma0=gamma0, theta=theta
    )
    u = dolfinx.fem.Function(V)
    result = solve_contact_problem(A, b, contact, u, bcs)
    assert result.converged, result.message
    p_exact = material.E * delta / 1.0
    comm = mesh.comm
    status, pressure, gap = (
        gathered(comm, a) for a in (contact.state.status, contact.state.pressure, contact.state.gap)
    )
    assert np.all(status != Status.OPEN)
    assert np.allclose(pressure, p_exact, rtol=1e-2)
    assert np.abs(gap).max() < 1e-6 * delta  # Nitsche is consistent: no penalty-like penetration
    normal_force, friction_force = contact.forces()
    assert normal_force == pytest.approx(p_exact * 1.0, rel=1e-2)
    assert np.allclose(friction_force, 0.0, atol=1e-6 * normal_force)


def test_interface_stiffness_of_another_variant():
    """interface_stiffness(status, theta, gamma0) of a (theta = -1, gamma0 = 1) contact equals the
    tangent of a contact built with that theta and gamma0 (same pairing)."""
    mesh, _, tags = two_blocks(MPI.COMM_WORLD, lower=(3, 3, 2), upper=(4, 5, 2))
    V = dolfinx.fem.functionspace(mesh, ("Lagrange", 2, (3,)))
    material = Material(E=1e9, nu=0.3)
    stepping = NitscheContact(
        V, tags, SLAVE, MASTER, material, FrictionLaw(0.5, 0.5, 0.0), gamma0=1.0, theta=-1
    )
    modal = NitscheContact(
        V, tags, SLAVE, MASTER, material, FrictionLaw(0.5, 0.5, 0.0), gamma0=30.0, theta=1
    )
    S = stepping.interface_stiffness(Status.STICK, theta=1, gamma0=30.0)
    S_ref = modal.interface_stiffness(Status.STICK)
    S_own = stepping.interface_stiffness(Status.STICK)
    norm = S_ref.norm()
    S.axpy(-1.0, S_ref, structure=PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN)
    S_own.axpy(-1.0, S_ref, structure=PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN)
    assert S.norm() < 1e-12 * norm
    assert S_own.norm() > 1e-3 * norm  # the variant arguments do change the tangent
    with pytest.raises(ValueError, match="theta"):
        stepping.interface_stiffness(Status.STICK, theta=2)
