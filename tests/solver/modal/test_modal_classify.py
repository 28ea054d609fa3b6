"""Mode classification (m, n) on synthetic displacement fields of a tube."""

import numpy as np
import pytest
from mpi4py import MPI

from solver.modal.classify import classify

from dolfinx import fem, mesh

pytestmark = pytest.mark.mpi

R, T, L = 0.3, 0.006, 1.4  # mid-surface radius, wall, length [m]


@pytest.fixture(scope="module")
def tube_space():
    """Q2 space on a hexahedral tube (box mapped to (theta, r, z); the seam is not glued,
    which does not matter for prescribed fields)."""
    msh = mesh.create_box(
        MPI.COMM_WORLD,
        [[0, R - T / 2, 0], [2 * np.pi, R + T / 2, L]],
        [32, 1, 20],
        mesh.CellType.hexahedron,
    )
    x = msh.geometry.x
    theta, r = x[:, 0].copy(), x[:, 1].copy()
    x[:, 0], x[:, 1] = r * np.cos(theta), r * np.sin(theta)
    return fem.functionspace(msh, ("Lagrange", 2, (3,)))


def axial_shape(n: int, z: np.ndarray) -> np.ndarray:
    """Clamped-free-like profile with exactly n interior nodes on (0, L)."""
    return np.sin((2 * n + 1) * np.pi * z / (2 * L))


def synthetic_mode(
    V, m: int, n: int, phase: float, component: str, noise: float = 0.0
) -> fem.Function:
    """u_c = cos(m theta + phase) g_n(z) in cylindrical component c, plus small noise."""
    u = fem.Function(V)

    def field(x):
        theta = np.arctan2(x[1], x[0])
        amp = np.cos(m * theta + phase) * axial_shape(n, x[2])
        e_r = np.array([np.cos(theta), np.sin(theta), 0 * theta])
        e_t = np.array([-np.sin(theta), np.cos(theta), 0 * theta])
        e_z = np.array([0 * theta, 0 * theta, 1 + 0 * theta])
        e = {"r": e_r, "theta": e_t, "z": e_z}[component]
        rng = np.random.default_rng(7)
        return amp * e + noise * rng.standard_normal(e.shape)

    u.interpolate(field)
    return u


@pytest.mark.parametrize(
    "m, n, component",
    [
        (2, 0, "r"),
        (2, 1, "r"),
        (3, 0, "r"),
        (4, 2, "r"),
        (6, 1, "r"),
        (1, 0, "r"),
        (1, 3, "r"),
        (0, 0, "z"),
        (0, 1, "theta"),
        (5, 0, "theta"),
    ],
)
def test_known_wave_numbers(tube_space, m, n, component):
    u = synthetic_mode(tube_space, m, n, phase=0.4, component=component, noise=0.01)
    result = classify(u)
    assert (result.m, result.n) == (m, n)
    assert result.component == component
    assert result.m_share > 0.9


def test_mixed_field_reports_dominant_harmonic(tube_space):
    u = synthetic_mode(tube_space, 3, 1, phase=0.0, component="r")
    weak = synthetic_mode(tube_space, 2, 0, phase=1.0, component="r")
    u.x.array[:] += 0.5 * weak.x.array
    result = classify(u)
    assert (result.m, result.n) == (3, 1)
    # both axial profiles have mean square 1/2, so the m = 3 share is 1 / (1 + 0.5^2)
    assert result.m_share == pytest.approx(0.8, rel=0.02)


def test_too_many_harmonics_for_the_mesh_raise(tube_space):
    u = synthetic_mode(tube_space, 2, 0, phase=0.0, component="r")
    with pytest.raises(ValueError):
        classify(u, m_max=80)
