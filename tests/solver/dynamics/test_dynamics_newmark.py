"""Newmark-family integration of a small clamped steel beam against its modal solution.

Reference: the lowest bending mode (SLEPc, shift-invert) as initial displacement;
the exact undamped response is phi cos(omega t), the damped one decays with the
prescribed ratio zeta.
"""

import numpy as np
import pytest
from mpi4py import MPI
from petsc4py import PETSc
from slepc4py import SLEPc

from dolfinx import fem, mesh
from dolfinx.fem.petsc import set_bc

from common.material import Material
from solver.dynamics.damping import ModalDamping, RayleighDamping
from solver.dynamics.elastodynamics import Elastodynamics, assemble_structure
from solver.dynamics.fidelity import accuracy, amplification_matrix, discrete_frequency
from solver.dynamics.schemes import GeneralisedAlpha, QuasiStatic
from solver.dynamics.time_loop import run

pytestmark = pytest.mark.mpi

STEEL = Material()


@pytest.fixture(scope="module")
def beam():
    """Cantilever 1.0 x 0.1 x 0.1 m, clamped at x = 0, trilinear hexahedra."""
    domain = mesh.create_box(
        MPI.COMM_WORLD, [[0, 0, 0], [1.0, 0.1, 0.1]], [8, 2, 2], cell_type=mesh.CellType.hexahedron
    )
    V = fem.functionspace(domain, ("Lagrange", 1, (3,)))
    clamped = fem.locate_dofs_geometrical(V, lambda x: np.isclose(x[0], 0.0))
    bcs = [fem.dirichletbc(np.zeros(3), clamped, V)]
    M, K = assemble_structure(V, STEEL, bcs)
    return V, M, K, bcs


def lowest_modes(K: PETSc.Mat, M: PETSc.Mat, bcs, n: int):
    """n lowest (omega [rad/s], M-normalised mode) pairs of K phi = omega^2 M phi.

    The clamped rows are identity in K and M; the eigenproblem uses M with zero
    clamped rows instead, which sends those spurious eigenvalues to infinity.
    """
    clamped = M.createVecLeft()
    clamped.set(0.0)
    ones = M.createVecLeft()
    ones.set(-1.0)
    set_bc(clamped, bcs, x0=ones)  # clamped rows = 0 - (-1) = 1
    M0 = M.copy()
    diagonal = M0.getDiagonal()
    diagonal.axpy(-1.0, clamped)
    M0.setDiagonal(diagonal)
    eps = SLEPc.EPS().create(K.getComm())
    eps.setOperators(K, M0)
    eps.setProblemType(SLEPc.EPS.ProblemType.GHEP)
    eps.setDimensions(n)
    eps.setWhichEigenpairs(SLEPc.EPS.Which.TARGET_MAGNITUDE)
    eps.setTarget(0.0)
    st = eps.getST()
    st.setType(SLEPc.ST.Type.SINVERT)
    st.getKSP().setType("preonly")
    st.getKSP().getPC().setType("lu")
    st.getKSP().getPC().setFactorSolverType("mumps")
    eps.setTolerances(1e-12, 200)
    eps.solve()
    assert eps.getConverged() >= n
    pairs = []
    for i in range(n):
        phi = K.createVecRight()
        eps.getEigenvector(i, phi)
        y = M.createVecLeft()
        M.mult(phi, y)
        phi.scale(1 / np.sqrt(phi.dot(y)))
        pairs.append((np.sqrt(eps.getEigenvalue(i).real), phi))
    return sorted(pairs, key=lambda p: p[0])


@pytest.fixture(scope="module")
def modes(beam):
    V, M, K, bcs = beam
    return lowest_modes(K, M, bcs, 3)


def start_in_mode(V, M, K, bcs, phi, scheme, damping=None, operators_kept=1) -> Elastodynamics:
    problem = Elastodynamics(
        V, M, K, bcs, scheme=scheme, damping=damping, operators_kept=operators_kept
    )
    phi.copy(problem.u.x.petsc_vec)
    problem.u.x.scatter_forward()
    problem.initialise(0.0)
    return problem


def modal_coordinate(M: PETSc.Mat, phi: PETSc.Vec):
    y = M.createVecLeft()
    M.mult(phi, y)
    return lambda problem: {"q": problem.u.x.petsc_vec.dot(y)}


def test_energy_conserved_over_1000_steps(beam, modes):
    """Average acceleration, no damping: E = 1/2 v.Mv + 1/2 u.Ku constant to 1e-8 (relative)."""
    V, M, K, bcs = beam
    omega, phi = modes[0]
    u0 = phi.copy()
    u0.axpy(0.7, modes[1][1])
    u0.axpy(0.3, modes[2][1])  # three modes, so the energy moves between them
    problem = start_in_mode(V, M, K, bcs, u0, GeneralisedAlpha())
    e0 = sum(problem.energy())
    dt = 2 * np.pi / omega / 37.0
    energies = []
    for _ in range(1000):
        assert problem.step(dt).converged
        energies.append(sum(problem.energy()))
    drift = np.max(np.abs(np.array(energies) - e0)) / e0
    print(f"max relative energy drift over 1000 steps: {drift:.2e}")
    assert drift < 1e-8
    kinetic, strain = problem.energy()
    assert kinetic > 0.01 * e0  # the motion did not stop


def test_kept_operators_change_nothing_but_the_cost(beam, modes):
    """Steps alternating between two sizes with both operators kept, then with one
    (``keep_operators(1)``), give the history of a problem that rebuilds its operator at every
    change of the step, to round-off; the operators held are those asked for."""
    V, M, K, bcs = beam
    omega, phi = modes[0]
    dt = 2 * np.pi / omega / 32
    steps = [dt, dt, dt / 2, dt / 2, dt, dt / 4, dt / 2, dt]
    histories = []
    for kept in (1, 2):
        problem = start_in_mode(
            V, M, K, bcs, phi, GeneralisedAlpha.from_spectral_radius(0.8), operators_kept=kept
        )
        coordinate = modal_coordinate(M, phi)
        history = []
        for i, h in enumerate(steps * 2):
            if i == len(steps):
                assert problem.operators_held == kept
                problem.keep_operators(1)
                assert problem.operators_held == 1
            assert problem.step(h).converged
            history.append(coordinate(problem)["q"])
        assert problem.operators_held == 1
        histories.append(np.array(history))
    assert np.max(np.abs(histories[1] - histories[0])) < 1e-10
    with pytest.raises(ValueError, match="operators_kept must be >= 1"):
        problem.keep_operators(0)


@pytest.mark.parametrize(
    "scheme",
    [GeneralisedAlpha(), GeneralisedAlpha.from_spectral_radius(0.8)],
    ids=["newmark", "generalised-alpha"],
)
def test_second_order_convergence(beam, modes, scheme):
    """Error of the modal-coordinate history vs cos(omega t) over two periods: rate 2."""
    V, M, K, bcs = beam
    omega, phi = modes[0]
    period = 2 * np.pi / omega
    errors = []
    for n in (16, 32, 64):
        problem = start_in_mode(V, M, K, bcs, phi, scheme)
        rows = run(
            problem, 2 * period, period / n, observers=[modal_coordinate(M, phi)], progress=False
        )
        t = np.array([r["time_s"] for r in rows])
        q = np.array([r["q"] for r in rows])
        errors.append(np.max(np.abs(q - np.cos(omega * t))))
    rates = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    print(f"{scheme}: errors {errors}, rates {rates}")
    assert np.all(np.abs(rates - 2.0) < 0.15)


def measured_damping_ratio(q: np.ndarray) -> float:
    """Damping ratio from the logarithmic decrement between the first and last peak of the
    samples q (a free decay sampled at a fixed step)."""
    i = np.flatnonzero((q[1:-1] > q[:-2]) & (q[1:-1] >= q[2:])) + 1
    # parabolic refinement of each sampled peak
    y0, y1, y2 = q[i - 1], q[i], q[i + 1]
    peaks = y1 - 0.25 * (y0 - y2) ** 2 / (y0 - 2 * y1 + y2)
    delta = np.log(peaks[0] / peaks[-1]) / (len(peaks) - 1)
    return delta / np.sqrt(4 * np.pi**2 + delta**2)


@pytest.mark.parametrize("kind", ["rayleigh-at-frequency", "rayleigh-two-frequencies", "modal"])
def test_free_decay_gives_prescribed_damping_ratio(beam, modes, kind):
    V, M, K, bcs = beam
    omega, phi = modes[0]
    f1, f3 = omega / (2 * np.pi), modes[2][0] / (2 * np.pi)
    zeta = 0.01
    damping = {
        "rayleigh-at-frequency": lambda: RayleighDamping.at_frequency(zeta, f1),
        "rayleigh-two-frequencies": lambda: RayleighDamping.from_two_frequencies(
            zeta, f1, 0.03, f3
        ),
        "modal": lambda: ModalDamping(
            M, [m[1] for m in modes], [m[0] / (2 * np.pi) for m in modes], zeta
        ),
    }[kind]()
    period = 2 * np.pi / omega
    problem = start_in_mode(V, M, K, bcs, phi, GeneralisedAlpha(), damping)
    rows = run(
        problem, 6.05 * period, period / 100, observers=[modal_coordinate(M, phi)], progress=False
    )
    measured = measured_damping_ratio(np.array([r["q"] for r in rows]))
    print(f"{kind}: measured zeta = {measured:.5f} (prescribed {zeta})")
    assert measured == pytest.approx(zeta, rel=0.02)


def test_rayleigh_coefficients_hit_both_frequencies():
    d = RayleighDamping.from_two_frequencies(0.01, 50.0, 0.02, 200.0)
    assert d.ratio(50.0) == pytest.approx(0.01, rel=1e-12)
    assert d.ratio(200.0) == pytest.approx(0.02, rel=1e-12)
    d1 = RayleighDamping.at_frequency(0.01, 120.0)
    assert d1.ratio(120.0) == pytest.approx(0.01, rel=1e-12)
    assert d1.ratio(60.0) > 0.01 and d1.ratio(240.0) > 0.01


def test_quasi_static_follows_the_load(beam):
    """Quasi-static stepping under a load ramp f(t) = t F reproduces K u = f(t) at every step."""
    V, M, K, bcs = beam
    F = K.createVecLeft()
    rng = np.random.default_rng(0)
    F.array_w[:] = rng.standard_normal(F.getLocalSize())
    set_bc(F, bcs, alpha=0.0)  # zero on the clamped rows
    problem = Elastodynamics(V, M, K, bcs, scheme=QuasiStatic(), load=lambda t, out: out.axpy(t, F))
    problem.initialise(0.0)
    run(problem, 1.0, 0.25, progress=False)
    residual = F.copy()
    residual.scale(-1.0)
    K.multAdd(problem.u.x.petsc_vec, residual, residual)  # K u(1) - F
    assert residual.norm() < 1e-10 * F.norm()


@pytest.mark.parametrize(
    "kwargs",
    [
        dict(beta=0.0),
        dict(beta=1.5),
        dict(gamma=2.0),
        dict(gamma=0.4),
        dict(alpha_f=1.0),
        dict(alpha_m=-1.5),
    ],
)
def test_bad_scheme_parameters_raise(kwargs):
    with pytest.raises(ValueError):
        GeneralisedAlpha(**kwargs)


def test_bad_damping_raises():
    with pytest.raises(ValueError):
        RayleighDamping.from_two_frequencies(0.01, 10.0, 0.01, 10.0)
    with pytest.raises(ValueError):
        RayleighDamping(a=-1.0)


@pytest.mark.parametrize("rho_inf", [0.0, 0.5])
def test_generalised_alpha_damps_unresolved_modes(beam, modes, rho_inf):
    """A mode with omega dt = 1000 decays by about rho_inf per step; Newmark keeps it (|ratio| = 1).

    Measured between steps 20 and 40 (past the start-up transient of the non-normal
    amplification matrix), on the energy (ratio^2 per step).
    """
    V, M, K, bcs = beam
    omega, phi = modes[2]
    dt = 1000.0 / omega
    ratios = {}
    for name, scheme in (
        ("newmark", GeneralisedAlpha()),
        ("alpha", GeneralisedAlpha.from_spectral_radius(rho_inf)),
    ):
        problem = start_in_mode(V, M, K, bcs, phi, scheme)
        energies = []
        for _ in range(40):
            problem.step(dt)
            energies.append(sum(problem.energy()))
        ratios[name] = (energies[39] / energies[19]) ** (1 / 40)
    print(f"rho_inf = {rho_inf}: amplitude ratio per step {ratios}")
    assert ratios["newmark"] == pytest.approx(1.0, abs=1e-9)
    assert ratios["alpha"] == pytest.approx(rho_inf, abs=0.05)


def test_scheme_names():
    from solver.dynamics.schemes import scheme_from_name

    assert scheme_from_name("newmark") == GeneralisedAlpha()
    assert scheme_from_name(
        "generalised-alpha", rho_inf=0.5
    ) == GeneralisedAlpha.from_spectral_radius(0.5)
    assert not scheme_from_name("quasi-static").dynamic
    with pytest.raises(ValueError, match="unknown time scheme"):
        scheme_from_name("euler")


def fitted_accuracy(q: np.ndarray, omega_dt: float) -> tuple[float, float]:
    """(damping ratio, period error) of the discrete oscillator behind the sequence q_n.

    Past the start-up (the spurious root of the amplification matrix has died out), q obeys
    q_{n+1} = A q_n - B q_{n-1} with A = 2 Re(lambda), B = |lambda|^2 of the principal pair;
    least squares give A and B, hence lambda."""
    q = q[20:]
    (A, B), *_ = np.linalg.lstsq(np.column_stack([q[1:-1], -q[:-2]]), q[2:], rcond=None)
    lam = complex(A / 2, np.sqrt(B - A**2 / 4))
    phase = np.angle(lam)
    return -np.log(abs(lam)) / phase, omega_dt / phase - 1.0


SCHEMES = {
    "newmark": GeneralisedAlpha(),
    **{
        f"generalised-alpha {rho}": GeneralisedAlpha.from_spectral_radius(rho)
        for rho in (0.0, 0.5, 0.8, 1.0)
    },
}


@pytest.mark.parametrize("steps_per_period", [12, 16, 32])
@pytest.mark.parametrize("name", SCHEMES)
def test_algorithmic_damping_and_period_error(beam, modes, name, steps_per_period):
    """Free vibration in the lowest mode, no physical damping: the damping ratio and the period
    error of the computed modal history equal those of the scheme's amplification matrix
    (solver.dynamics.fidelity.accuracy)."""
    V, M, K, bcs = beam
    omega, phi = modes[0]
    scheme = SCHEMES[name]
    dt = 2 * np.pi / omega / steps_per_period
    problem = start_in_mode(V, M, K, bcs, phi, scheme)
    rows = run(
        problem, 8 * steps_per_period * dt, dt, observers=[modal_coordinate(M, phi)], progress=False
    )
    q = np.array([1.0] + [r["q"] for r in rows])
    damping, period_error = fitted_accuracy(q, omega * dt)
    expected = accuracy(scheme, steps_per_period)
    print(
        f"{name}, {steps_per_period} steps per period: damping {100 * damping:.5f} % "
        f"(closed form {100 * expected.damping_ratio:.5f} %), period error {100 * period_error:.5f} % "
        f"(closed form {100 * expected.period_error:.5f} %)"
    )
    assert damping == pytest.approx(expected.damping_ratio, abs=1e-8)
    assert period_error == pytest.approx(expected.period_error, rel=1e-6)


@pytest.mark.parametrize("steps_per_period", [8, 16, 24, 64])
def test_trapezoidal_rule_in_closed_form(steps_per_period):
    """Average acceleration (and generalised-alpha with rho_inf = 1): no algorithmic damping and
    arg(lambda) = 2 atan(omega dt / 2), so T_h / T = (omega dt / 2) / atan(omega dt / 2); its
    discrete natural frequency for a step dt is (2 / dt) atan(omega dt / 2) / (2 pi)."""
    x = 2 * np.pi / steps_per_period
    for scheme in (GeneralisedAlpha(), GeneralisedAlpha.from_spectral_radius(1.0)):
        result = accuracy(scheme, steps_per_period)
        assert result.damping_ratio == pytest.approx(0.0, abs=1e-12)
        assert result.period_error == pytest.approx(0.5 * x / np.arctan(0.5 * x) - 1, rel=1e-10)
        f, dt = 120.0, 1e-3
        w = 2 * np.pi * f
        assert discrete_frequency(scheme, f, dt) == pytest.approx(
            2 / dt * np.arctan(0.5 * w * dt) / (2 * np.pi), rel=1e-12
        )


@pytest.mark.parametrize("rho_inf", [0.0, 0.3, 0.55, 0.8])
def test_spectral_radius_at_infinity(rho_inf):
    """The amplification matrix's spectral radius tends to rho_inf as omega dt grows (the design
    property of generalised-alpha, Chung and Hulbert 1993), and the principal root's damping
    grows with omega dt."""
    scheme = GeneralisedAlpha.from_spectral_radius(rho_inf)
    radius = max(abs(np.linalg.eigvals(amplification_matrix(scheme, 1e8))))
    assert radius == pytest.approx(rho_inf, abs=1e-4)
    damping = [accuracy(scheme, n).damping_ratio for n in (64, 32, 16, 8)]
    assert np.all(np.diff(damping) >= 0)


def test_quasi_static_has_no_resonance():
    with pytest.raises(ValueError, match="no inertia"):
        accuracy(QuasiStatic(), 24)
