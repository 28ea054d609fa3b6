"""Press fit (Lamé): two thick rings with radial interference against the closed form.

Quarter rings a < r < b + delta (inner) and b < r < c (outer), one quadratic element
through an axial slice with u_z = 0 on both faces (plane strain) and symmetry rollers on
x = 0 and y = 0. Closed form: p = delta / (u_o(b) - u_i(b + delta)), with u_o, u_i the
radial displacements of the outer / inner ring under unit interface pressure.
"""

from mpi4py import MPI

import numpy as np
import pytest

import dolfinx
from contact_cases import MASTER, SLAVE, elastic_system, fixed, gathered, two_rings
from common.material import Material
from solver.contact import FrictionLaw, NitscheContact, Status
from solver.dynamics.newton import solve_contact_problem

pytestmark = pytest.mark.mpi

A_, B_, C_ = 0.5, 0.75, 1.0  # radii [m]
DELTA = 1e-3  # radial interference [m]
THICKNESS = 0.05  # axial slice [m]


def radial_displacement(
    material: Material, r_in: float, r_out: float, p_in: float, p_out: float, r: float
) -> float:
    """Plane-strain Lamé radial displacement [m] of a ring under inner/outer pressure [Pa]."""
    E, nu = material.E, material.nu
    A = (p_in * r_in**2 - p_out * r_out**2) / (r_out**2 - r_in**2)
    B = (p_in - p_out) * r_in**2 * r_out**2 / (r_out**2 - r_in**2)
    s_rr, s_tt = A - B / r**2, A + B / r**2
    return r * ((1 - nu**2) * s_tt - nu * (1 + nu) * s_rr) / E


@pytest.mark.parametrize("theta, gamma0", [(1, 30.0), (-1, 30.0), (-1, 1.0)])
def test_press_fit_pressure(theta, gamma0):
    mesh, _, tags = two_rings(
        MPI.COMM_WORLD, (A_, B_, C_), DELTA, THICKNESS, inner=(2, 12), outer=(2, 9)
    )
    V = dolfinx.fem.functionspace(mesh, ("Lagrange", 2, (3,)))
    material = Material(E=210e9, nu=0.3)
    bcs = [
        fixed(V, 0, lambda x: np.isclose(x[0], 0.0)),
        fixed(V, 1, lambda x: np.isclose(x[1], 0.0)),
        fixed(V, 2, lambda x: np.isclose(x[2], 0.0) | np.isclose(x[2], THICKNESS)),
    ]
    A, b = elastic_system(V, material, bcs)
    contact = NitscheContact(
        V, tags, SLAVE, MASTER, material, FrictionLaw(0.5, 0.5, 0.0), gamma0=gamma0, theta=theta
    )
    u = dolfinx.fem.Function(V)
    result = solve_contact_problem(A, b, contact, u, bcs, refactor_after=0)
    assert result.converged, result.message

    unit_outer = radial_displacement(material, B_, C_, 1.0, 0.0, B_)
    unit_inner = radial_displacement(material, A_, B_ + DELTA, 0.0, 1.0, B_ + DELTA)
    p_exact = DELTA / (unit_outer - unit_inner)

    comm = mesh.comm
    w, p, status = (
        gathered(comm, a)
        for a in (contact.slave.weights, contact.state.pressure, contact.state.status)
    )
    assert np.all(status == Status.STICK)  # radial problem: no slip
    if comm.rank == 0:
        print(
            f"theta {theta}, gamma0 {gamma0}: mean pressure / exact - 1 = {(w @ p) / w.sum() / p_exact - 1:.2e}"
        )
    assert (w @ p) / w.sum() == pytest.approx(p_exact, rel=2e-2)

    # the bulk field away from the interface: radial displacement of the free surfaces
    x = V.tabulate_dof_coordinates()[: V.dofmap.index_map.size_local]
    r = np.hypot(x[:, 0], x[:, 1])
    disp = u.x.array.reshape(-1, 3)[: len(x)]
    u_r = (disp[:, 0] * x[:, 0] + disp[:, 1] * x[:, 1]) / r
    for radius, expected in [
        (A_, radial_displacement(material, A_, B_ + DELTA, 0.0, p_exact, A_)),
        (C_, radial_displacement(material, B_, C_, p_exact, 0.0, C_)),
    ]:
        on_surface = gathered(comm, u_r[np.isclose(r, radius, atol=1e-9)])
        assert on_surface.mean() == pytest.approx(expected, rel=2e-2)
