"""A resonant stage resonates: time stepping against the frequency-domain solution.

The joint with a bonded 50 mm band at the TP's lower edge (linear, no friction; the coarse
joint, 8 around, 0.25 m, degree 2: any mesh will do, both sides use the same discrete model)
is driven at its best-ranked natural frequency f_n by a harmonic force at a point of the TP
top edge, with Rayleigh damping of 1 % at f_n. The steady-state displacement amplitude at the
force point from time stepping must agree within 5 % with the frequency-domain solution
(K - w^2 M + i w C) U = F at w = 2 pi f_n (solver.dynamics.frequency_response).

The time-discrete model resonates at its own natural frequency, below f_n by the scheme's
period error (solver.dynamics.fidelity): the time stepping excites at that compensated
frequency, as the installation run does. Uncompensated, the same scheme misses the
resonance: the test checks that too (the amplitude then falls short by far more than 5 %).
"""

import numpy as np
import pytest
from dolfinx import fem
from mpi4py import MPI
from petsc4py import PETSc

from common.case import read_case
from geometry import tags
from geometry.mesh import create_joint_mesh
from geometry.parameters import MeshOptions, geometry_from_case
from solver.dynamics.damping import RayleighDamping
from solver.dynamics.elastodynamics import Elastodynamics, assemble_structure
from solver.dynamics.fidelity import compensated_frequency
from solver.dynamics.frequency_response import harmonic_response
from solver.dynamics.loads import shaker_point
from solver.dynamics.schemes import GeneralisedAlpha
from solver.dynamics.time_loop import run
from solver.modal.eigen import EigenOptions, clamp, modal_analysis
from solver.modal.interface import bonded_band
from solver.modal.ranking import JointParts, describe_modes
from solver.probes import PointProbe

pytestmark = pytest.mark.mpi

FORCE_N = 1000.0
ZETA = 0.01
PERIODS = 90  #: from rest; the transient of the resonant mode decays as exp(-2 pi zeta periods)
FIT_PERIODS = 10


@pytest.fixture(scope="module")
def joint():
    """The bonded-band joint: space, M, K (with the band), clamp, the best-ranked natural
    frequency [Hz], the force point and the load vector F [N] there."""
    comm = MPI.COMM_WORLD
    geometry, material, _ = geometry_from_case(read_case("coarse"))
    data = create_joint_mesh(comm, geometry, MeshOptions(n_circumferential=8, axial_size=0.25))
    V = fem.functionspace(data.mesh, ("Lagrange", 2, (3,)))
    bcs = [clamp(V, data.facet_tags, [tags.MP_CLAMPED])]
    band = bonded_band(V, data.facet_tags, material, 0.05)
    M, K = assemble_structure(V, material, bcs)
    K.axpy(1.0, band.stiffness(V), structure=PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN)
    modes = modal_analysis(V, material, bcs, [band], EigenOptions(n_modes=8))
    parts = JointParts.for_joint(V, data, geometry)
    records = describe_modes(modes, material, parts, zeta=ZETA, m_max=7)
    best = min(records, key=lambda r: (r.rank, r.mode))
    point = shaker_point(geometry.tp, geometry.tp_offset, geometry.tp.total_length, 0.0)
    point[2] -= 1e-6 * geometry.tp.total_length  # just inside the top face, as JointParts's
    F = K.createVecLeft()
    F.set(0.0)
    parts.point.add(FORCE_N * np.array([1.0, 0.0, 1.0]) / np.sqrt(2.0), F)  # lateral and axial
    return V, M, K, bcs, best.frequency_Hz, point, F


def steady_amplitude(t: np.ndarray, x: np.ndarray, f: float) -> float:
    """|complex amplitude vector| [m] of x(t) (n, 3) at frequency f [Hz]: least squares on
    (1, cos, sin) per component."""
    w = 2 * np.pi * f
    basis = np.column_stack([np.ones_like(t), np.cos(w * t), np.sin(w * t)])
    coefficients, *_ = np.linalg.lstsq(basis, x, rcond=None)
    return float(np.sqrt(np.sum(coefficients[1] ** 2 + coefficients[2] ** 2)))


def time_domain_amplitude(joint, scheme, excitation_hz: float, steps_per_period: int) -> float:
    """Steady-state amplitude [m] at the force point under F sin(2 pi f t) from rest."""
    V, M, K, bcs, f_n, point, F = joint
    dt = 1.0 / (excitation_hz * steps_per_period)
    w = 2 * np.pi * excitation_hz
    problem = Elastodynamics(
        V,
        M,
        K,
        bcs,
        load=lambda t, out: out.axpy(np.sin(w * t), F),
        scheme=scheme,
        damping=RayleighDamping.at_frequency(ZETA, f_n),
    )
    problem.initialise(0.0)
    probe = PointProbe(problem.u, point[None, :])
    rows = run(
        problem,
        PERIODS / excitation_hz,
        dt,
        observers=[lambda p: dict(zip("xyz", probe()[0]))],
        progress=False,
    )
    last = rows[-FIT_PERIODS * steps_per_period :]
    t = np.array([r["time_s"] for r in last])
    x = np.array([[r[c] for c in "xyz"] for r in last])
    return steady_amplitude(t, x, excitation_hz)


def frequency_domain_amplitude(joint) -> float:
    V, M, K, bcs, f_n, point, F = joint
    U_re, U_im = harmonic_response(M, K, RayleighDamping.at_frequency(ZETA, f_n), F, f_n)
    values = []
    for U in (U_re, U_im):
        u = fem.Function(V)
        u.x.petsc_vec.array_w[:] = U.array_r
        u.x.scatter_forward()
        values.append(PointProbe(u, point[None, :])()[0])
    return float(np.sqrt(np.sum(values[0] ** 2 + values[1] ** 2)))


SCHEMES = {
    "generalised-alpha 0.55, 16 steps": (GeneralisedAlpha.from_spectral_radius(0.55), 16),
    "newmark, 24 steps": (GeneralisedAlpha(), 24),
}


@pytest.mark.parametrize("name", SCHEMES)
def test_resonant_amplitude_matches_the_frequency_domain(joint, name):
    scheme, steps = SCHEMES[name]
    f_n = joint[4]
    reference = frequency_domain_amplitude(joint)
    f_c = compensated_frequency(scheme, f_n, steps)
    compensated = time_domain_amplitude(joint, scheme, f_c, steps)
    uncompensated = time_domain_amplitude(joint, scheme, f_n, steps)
    if MPI.COMM_WORLD.rank == 0:
        print(
            f"{name}: f_n = {f_n:.3f} Hz, frequency domain {1e6 * reference:.4f} um; time domain at the "
            f"compensated {f_c:.3f} Hz {1e6 * compensated:.4f} um ({compensated / reference - 1:+.2%}), "
            f"at f_n {1e6 * uncompensated:.4f} um ({uncompensated / reference - 1:+.2%})"
        )
    assert compensated == pytest.approx(reference, rel=0.05)
    assert uncompensated < 0.95 * reference
