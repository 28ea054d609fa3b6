"""Modal solver on a solid cantilever: Euler-Bernoulli, band search, partition independence."""

import numpy as np
import pytest
from mpi4py import MPI

from common.material import Material
from solver.modal.eigen import EigenOptions, modal_analysis

from dolfinx import fem, mesh

pytestmark = pytest.mark.mpi

L, B, H = 1.0, 0.05, 0.05  # cantilever length, width, height [m]
STEEL = Material(E=210e9, nu=0.3, rho=7850.0)
BETA1_L = 1.8751040687119611  # first root of 1 + cos(x) cosh(x) = 0


def cantilever(comm: MPI.Comm, n_length: int = 20):
    """Q2 vector space on a hexahedral beam clamped at x = 0."""
    msh = mesh.create_box(comm, [[0, 0, 0], [L, B, H]], [n_length, 2, 2], mesh.CellType.hexahedron)
    V = fem.functionspace(msh, ("Lagrange", 2, (3,)))
    facets = mesh.locate_entities_boundary(msh, 2, lambda x: np.isclose(x[0], 0.0))
    bc = fem.dirichletbc(np.zeros(3), fem.locate_dofs_topological(V, 2, facets), V)
    return V, bc


def test_first_bending_frequency_matches_euler_bernoulli():
    V, bc = cantilever(MPI.COMM_WORLD)
    result = modal_analysis(V, STEEL, [bc], options=EigenOptions(n_modes=4))
    f_eb = BETA1_L**2 / (2 * np.pi) * np.sqrt(STEEL.E * B * H**3 / 12 / (STEEL.rho * B * H * L**4))
    # square section: the two bending directions are degenerate
    assert result.frequencies_hz[0] == pytest.approx(f_eb, rel=0.01)
    assert result.frequencies_hz[1] == pytest.approx(result.frequencies_hz[0], rel=1e-8)
    print(
        f"cantilever: f1 = {result.frequencies_hz[0]:.4f} Hz, Euler-Bernoulli {f_eb:.4f} Hz, "
        f"rel. diff {result.frequencies_hz[0] / f_eb - 1:.2e}"
    )


def test_modes_are_mass_normalised_and_clamped_dofs_inert():
    V, bc = cantilever(MPI.COMM_WORLD, n_length=8)
    result = modal_analysis(V, STEEL, [bc], options=EigenOptions(n_modes=3))
    for f, u in zip(result.frequencies_hz, result.modes):
        x = u.x.petsc_vec
        Mx, Kx = x.duplicate(), x.duplicate()
        result.M.mult(x, Mx)
        result.K.mult(x, Kx)
        assert x.dot(Mx) == pytest.approx(1.0, rel=1e-10)
        assert x.dot(Kx) == pytest.approx((2 * np.pi * f) ** 2, rel=1e-8)
        dofs, n_owned = bc.dof_indices()
        assert np.abs(u.x.array[dofs]).max(initial=0.0) == 0.0


def test_band_returns_exactly_the_modes_in_it():
    V, bc = cantilever(MPI.COMM_WORLD, n_length=8)
    lowest = modal_analysis(V, STEEL, [bc], options=EigenOptions(n_modes=8)).frequencies_hz
    f_lo, f_hi = 0.5 * (lowest[1] + lowest[2]), 0.5 * (lowest[6] + lowest[7])
    band = modal_analysis(V, STEEL, [bc], options=EigenOptions(band_hz=(f_lo, f_hi))).frequencies_hz
    np.testing.assert_allclose(band, lowest[2:7], rtol=1e-8)


def test_partitioned_and_serial_frequencies_agree():
    """COMM_WORLD (2 ranks under mpiexec) against a COMM_SELF solve of the same problem."""
    options = EigenOptions(n_modes=10)
    f_world = modal_analysis(
        *_bc_list(cantilever(MPI.COMM_WORLD, 10)), options=options
    ).frequencies_hz
    f_self = modal_analysis(
        *_bc_list(cantilever(MPI.COMM_SELF, 10)), options=options
    ).frequencies_hz
    np.testing.assert_allclose(f_world, f_self, rtol=1e-8)


def _bc_list(space_and_bc):
    V, bc = space_and_bc
    return V, STEEL, [bc]


@pytest.mark.parametrize(
    "kwargs", [dict(n_modes=0), dict(band_hz=(50.0, 10.0)), dict(target_hz=-1.0), dict(tol=0.0)]
)
def test_bad_options_raise(kwargs):
    with pytest.raises(ValueError):
        EigenOptions(**kwargs)
