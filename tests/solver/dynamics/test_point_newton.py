"""Newton on the contact points (solver/dynamics/: point_newton, tractions, relaxation, compliance).

- The inner problem y - y_free + G lambda(y) = 0 for uncoupled points (G = g I per point) against
  its closed form (open, stick, slip); a recorded problem where Newton stalls with every point
  slipping, solved after the stick restart; the same problem stopped at the first iterate whose
  residual as forces on the points is below a force tolerance.
- The inner problem's linear solves (``TractionJacobian``: FGMRES with kept single-precision
  factors) against a dense double-precision solve, with the factors reused for a changed
  derivative, updated for a few points opening and closing and renewed for another active set;
  on one rank and with the products shared among the ranks. The factors of a Jacobian with
  slipping points and points tied only normally, reduced by the kernel of the law's derivative,
  against the same dense solve, and the kernel's basis against its definition. The inner
  problem solved with shared products takes the iterates of the one solved on one rank.
- The compliance G of ``ContactCompliance`` (blocks once per operator, the master part per
  pairing) against E A'^-1 F^T W formed densely on the tiny joint's condensed zone.
- The Aitken relaxation of the fixed point in the friction coefficients against linear fixed
  points: exact after three iterations for one rate, far fewer iterations than the plain fixed
  point for rates that differ between points; a fixed coefficient passes through.
- The installation steps of the quick frictional joint (self-weight ramp, then eccentric
  vibration steps) with ``[contact] solver = "points"`` against the generalized Newton on the
  zone, with the friction coefficient lagged by a step and at the step's own slip speed: the
  same discrete problem, so the same settlement and displacement to the Newton tolerance; and
  the outer tolerance of the default case against a tight one.

Serially and on 2 ranks.
"""

from pathlib import Path

import numpy as np
import pytest
import scipy.linalg
from mpi4py import MPI
from petsc4py import PETSc

from common.case import read_case
from solver.contact.model import Status
from solver.dynamics.compliance import ContactCompliance
from solver.dynamics.loads import Schedule
from solver.dynamics.relaxation import CoefficientRelaxation
from solver.dynamics.tractions import solve_tractions, traction_residual
from solver.contact.law import derivative
from solver.dynamics.traction_jacobian import TractionJacobian, kernel_basis
from solver.dynamics.time_loop import run
from solver.installation.case import InstallationCase
from solver.installation.model import attach_vibration, set_up_joint_model

pytestmark = pytest.mark.mpi


def _closed_form(y_free, g, normal, mu):
    """Solution of y - y_free + g lambda(y) = 0 at one point (G = g I)."""
    f_n = y_free @ normal
    f_t = y_free - f_n * normal
    if f_n > 0:
        return y_free.copy()  # open: no multiplier
    y_n = f_n / (1 + g)  # lambda_n = y_n
    pressure = -y_n
    if np.linalg.norm(f_t) / (1 + g) <= mu * pressure:
        return y_n * normal + f_t / (1 + g)  # stick: lambda_t = y_t
    q = f_t / np.linalg.norm(f_t)  # slip: y_t + g mu p q = f_t
    return y_n * normal + (np.linalg.norm(f_t) - g * mu * pressure) * q


def test_uncoupled_points_against_closed_form():
    rng = np.random.default_rng(7)
    n = 60
    normal = rng.normal(size=(n, 3))
    normal /= np.linalg.norm(normal, axis=1)[:, None]
    g = rng.uniform(1.0, 300.0, n)  # the joint's compliances are of this size
    mu = rng.uniform(0.05, 0.5, n)
    y_free = 1e7 * rng.normal(size=(n, 3))  # [Pa]
    G = np.kron(np.diag(g), np.eye(3))
    solution = solve_tractions(G, y_free.ravel(), np.zeros(3 * n), normal, mu)
    assert solution.converged
    expected = np.array([_closed_form(y_free[p], g[p], normal[p], mu[p]) for p in range(n)])
    assert np.allclose(solution.y.reshape(-1, 3), expected, rtol=1e-10, atol=1e-3)
    states = [_closed_form(y_free[p], g[p], normal[p], mu[p]) @ normal[p] < 0 for p in range(n)]
    assert 0 < sum(states) < n  # open and closed points both tested


def test_start_with_its_residual_given_repeats_the_solve():
    """``solve_tractions`` from a start whose residual the caller evaluated (as Newton on the
    contact points does when it chooses the start) takes the same iterates."""
    data = np.load(Path(__file__).parent / "data" / "stalling_slip.npz")
    G, y_free, y0, normal, mu = (data[k] for k in ("G", "y_free", "y0", "normal", "mu"))
    jacobian = TractionJacobian()
    jacobian.set_compliance(G)
    evaluated = traction_residual(jacobian, y0, y_free, normal, mu)
    given = solve_tractions(G, y_free, y0, normal, mu, jacobian=jacobian, evaluated=evaluated)
    plain = solve_tractions(G, y_free, y0, normal, mu)
    assert given.converged and given.iterations == plain.iterations
    assert np.array_equal(given.y, plain.y)


def test_shared_products_take_the_same_iterates():
    """The recorded inner problem solved with G's products shared among the ranks (on every rank
    the same iterations, to rounding the same solution as on one rank)."""
    data = np.load(Path(__file__).parent / "data" / "stalling_slip.npz")
    G, y_free, y0, normal, mu = (data[k] for k in ("G", "y_free", "y0", "normal", "mu"))
    alone = solve_tractions(G, y_free, y0, normal, mu)
    shared = solve_tractions(G, y_free, y0, normal, mu, jacobian=TractionJacobian(MPI.COMM_WORLD))
    assert shared.converged and shared.iterations == alone.iterations
    assert np.allclose(shared.y, alone.y, rtol=0, atol=1e-10 * np.abs(y_free).max())
    everywhere = MPI.COMM_WORLD.allgather(shared.y)
    assert all(np.array_equal(y, everywhere[0]) for y in everywhere)


def test_force_tolerance_stops_at_the_first_iterate_below_it():
    """With point areas given, the inner problem stops at the first iterate whose residual as
    forces on the points, ||area Phi|| [N], is at most the force tolerance (an outer Newton
    iteration's need), before the relative tolerance."""
    data = np.load(Path(__file__).parent / "data" / "stalling_slip.npz")
    G, y_free, y0, normal, mu = (data[k] for k in ("G", "y_free", "y0", "normal", "mu"))
    area = np.full(len(mu), 1e-3)  # [m^2]

    def force(y, multipliers):
        return np.linalg.norm(area[:, None] * (y - y_free + G @ multipliers).reshape(-1, 3))

    jacobian = TractionJacobian()
    jacobian.set_compliance(G)
    tol = 1e-3 * force(y0, traction_residual(jacobian, y0, y_free, normal, mu).lam)
    full = solve_tractions(G, y_free, y0, normal, mu)
    loose = solve_tractions(G, y_free, y0, normal, mu, area=area, force_tol=tol)
    assert loose.converged and 0 < loose.iterations < full.iterations
    assert force(loose.y, loose.multipliers) <= tol
    before = solve_tractions(
        G, y_free, y0, normal, mu, max_iterations=loose.iterations - 1, area=area, force_tol=tol
    )
    assert not before.converged and force(before.y, before.multipliers) > tol


def test_stalled_slip_restarts_stuck():
    """Four points of an inner problem recorded on the converged joint's self-weight stage: from
    their iterate's tractions, every point slipping, Newton finds no step that lowers ||Phi||;
    restarted from ``stick_restart`` it converges, to a solution of Phi = 0 (checked here)."""
    data = np.load(Path(__file__).parent / "data" / "stalling_slip.npz")
    G, y_free, y0, normal, mu = (data[k] for k in ("G", "y_free", "y0", "normal", "mu"))
    stalled = solve_tractions(G, y_free, y0, normal, mu, restarts=0)
    assert not stalled.converged
    solution = solve_tractions(G, y_free, y0, normal, mu)
    assert solution.converged
    phi = solution.y - y_free + G @ solution.multipliers
    assert np.abs(phi).max() <= 1e-10 * np.abs(y_free).max()
    P = solution.y.reshape(-1, 3)
    P_n = np.einsum("pi,pi->p", P, normal)
    assert np.all(P_n < 0)  # all four in contact


@pytest.mark.parametrize("comm", [MPI.COMM_SELF, MPI.COMM_WORLD], ids=["alone", "shared"])
def test_reused_factors_against_dense_solve(comm):
    """Each solve against a dense double-precision solve (to the single precision of the solves):
    the first factorises; a turned derivative, more points appended to G and a few points opening
    and closing reuse the factors (the last two by low-rank updates); another active set renews
    them."""
    rng = np.random.default_rng(3)  # the same problems on every rank
    n = 50
    G = rng.uniform(0.0, 1.0, (3 * n, 3 * n))
    G = 50.0 * G @ G.T / n  # compliance-like: symmetric positive, entries of tens
    jacobian = TractionJacobian(comm, rtol=1e-6)
    jacobian.set_compliance(G)

    def derivative(points):
        normal = rng.normal(size=(len(points), 3))
        normal /= np.linalg.norm(normal, axis=1)[:, None]
        return normal[:, :, None] * normal[:, None, :] + 0.3 * np.eye(3)

    def check(active, D):
        cols = (3 * active[:, None] + np.arange(3)).ravel()
        J = np.eye(len(cols)) + G[np.ix_(cols, cols)] @ scipy.linalg.block_diag(*D)
        r = rng.normal(size=len(cols))
        dy = jacobian.solve(active, D, r)
        assert np.allclose(J @ dy, r, rtol=0, atol=1e-5 * np.abs(r).max())

    active = np.sort(rng.choice(n, 30, replace=False))
    D_0 = derivative(active)
    turned = D_0 + 0.02 * rng.normal(size=D_0.shape)  # e.g. slip directions turned
    for D in (D_0, turned):  # the second with the first's factors
        check(active, D)
    assert jacobian.factorizations == 1 and jacobian.krylov_iterations > 2
    # more points appended (an extension of the compliance blocks): the factors stay
    extended = np.zeros((3 * n + 6, 3 * n + 6), order="F")
    extended[: 3 * n, : 3 * n] = G
    extended[3 * n :, :] = 1.0
    extended[:, 3 * n :] = 1.0
    jacobian.set_compliance(extended)
    check(active, turned)
    assert jacobian.factorizations == 1
    # one point opens, two close (3 of 30 points: within max_update): updated factors
    opened = active[7]
    closed = rng.choice(np.setdiff1d(np.arange(n), active), 2, replace=False)
    changed = np.sort(np.concatenate([np.setdiff1d(active, [opened]), closed]))
    D = np.empty((len(changed), 3, 3))
    kept = np.isin(changed, active)
    D[kept] = turned[np.searchsorted(active, changed[kept])]
    D[~kept] = derivative(closed)
    check(changed, D)
    assert jacobian.factorizations == 1 and jacobian.updates == 1
    # the last points opening one after another: an update for each set
    for k in (1, 2):
        check(active[:-k], turned[:-k])
    assert jacobian.factorizations == 1 and jacobian.updates == 3
    other = np.sort(rng.choice(n, 20, replace=False))
    check(other, derivative(other))
    assert jacobian.factorizations == 2


@pytest.mark.parametrize("comm", [MPI.COMM_SELF, MPI.COMM_WORLD], ids=["alone", "shared"])
def test_factors_reduced_by_the_kernel(comm):
    """The law's derivative at stuck, slipping and normally tied points: its kernel's basis is
    orthonormal and D vanishes on it (the slip direction; both tangents where tied normally);
    the factors have 3, 2 and 1 rows per such point and solve J = I + G_aa D to the precision
    of single-precision factors, alone and as FGMRES's preconditioner."""
    rng = np.random.default_rng(5)  # the same problems on every rank
    n, m = 60, 40
    G = rng.uniform(0.0, 1.0, (3 * n, 3 * n))
    G = 50.0 * G @ G.T / n
    active = np.sort(rng.choice(n, m, replace=False))
    normal = rng.normal(size=(m, 3))
    normal /= np.linalg.norm(normal, axis=1)[:, None]
    P_t = rng.normal(size=(m, 3))
    P_t -= np.einsum("pi,pi->p", P_t, normal)[:, None] * normal
    stick = np.arange(m) < 10
    slip = np.arange(m) >= 14  # points 10-13: tied normally only
    D = derivative(normal, P_t, np.full(m, 0.5), rng.uniform(0.5, 3.0, m), stick, slip)
    basis, kept = kernel_basis(D)
    assert np.allclose(basis.transpose(0, 2, 1) @ basis, np.eye(3), atol=1e-12)
    assert np.array_equal(kept.sum(axis=1), np.where(stick, 3, np.where(slip, 2, 1)))
    assert np.abs((D @ basis)[np.broadcast_to(~kept[:, None, :], D.shape)]).max() < 1e-12
    slip_direction = P_t[slip] / np.linalg.norm(P_t[slip], axis=1)[:, None]
    assert np.allclose(np.abs(np.einsum("pi,pi->p", basis[slip, :, 2], slip_direction)), 1.0)

    jacobian = TractionJacobian(comm, rtol=1e-6)
    jacobian.set_compliance(G)
    cols = (3 * active[:, None] + np.arange(3)).ravel()
    J = np.eye(len(cols)) + G[np.ix_(cols, cols)] @ scipy.linalg.block_diag(*D)
    r = rng.normal(size=len(cols))
    dy = jacobian.solve(active, D, r)
    assert jacobian.factorizations == 1 and jacobian.factor_rows == 3 * 10 + 1 * 4 + 2 * 26
    assert np.allclose(J @ dy, r, rtol=0, atol=1e-5 * np.abs(r).max())
    # the factors alone, one FGMRES iteration: J^-1 to the precision of single-precision
    # factors of M (condition number about 4e3 here), no double-precision solve
    lu_only = TractionJacobian(comm, max_krylov=1, rtol=1e-3)
    lu_only.set_compliance(G)
    dy = lu_only.solve(active, D, r)
    assert lu_only.factorizations == 1 and lu_only.dense_solves == 0
    assert np.allclose(J @ dy, r, rtol=0, atol=1e-3 * np.abs(r).max())


def _gather_rows(local: np.ndarray) -> np.ndarray:
    return np.concatenate(MPI.COMM_WORLD.allgather(local))


@pytest.mark.parametrize("lu_solver", ["mumps", "superlu_dist"])
def test_compliance_against_dense_product(tiny_case, lu_solver):
    """G = E A'^-1 F^T W of points on the tiny joint's contact surface, from the blocks of
    ContactCompliance (built in two extensions, then restricted to part of the points and band;
    on several ranks each rank solves a share of the columns with its own copy of the factors,
    also an extension by a single band dof: no point columns, one rank's share empty) and formed
    densely (E, F, A' gathered)."""
    if not PETSc.Sys.hasExternalPackage(lu_solver):
        pytest.skip(f"this PETSc has no {lu_solver}")
    comm = MPI.COMM_WORLD
    model = set_up_joint_model(comm, tiny_case())
    problem, contact = model.problem, model.contact
    condensation = problem.condensation_at(1e-4)  # the condensed operator at a step of 0.1 ms
    zone = condensation.zone
    A_prime = condensation.A_hat.copy()
    A_prime.axpy(
        1.0,
        contact.interface_stiffness(Status.OPEN),
        structure=PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN,
    )
    A_zone = A_prime.createSubMatrix(zone, zone)
    zone_dofs = np.concatenate(comm.allgather(zone.getIndices()))
    compliance = ContactCompliance(A_zone, zone_dofs, lu_solver)
    paired = np.flatnonzero(contact.pairing.paired)
    points = paired[:: max(1, len(paired) // 40)]  # a few dozen points per rank
    half = len(points) // 2
    for first, last in ((0, half), (half, len(points))):  # two extensions
        ops = contact.point_operators(points[:last])
        band = np.unique(_gather_rows(ops.master_dofs[first:last].ravel()))
        compliance.extend(ops, last - first, np.setdiff1d(band, compliance.band))
    spare = np.setdiff1d(zone_dofs, compliance.band)[:1]  # the same dof on every rank
    compliance.extend(contact.point_operators(points), 0, spare)
    _compare_with_dense(compliance, contact.point_operators(points), A_zone, zone_dofs)
    keep = np.arange(len(points)) % 3 != 1
    kept = contact.point_operators(points[keep])
    needed = np.isin(compliance.band, _gather_rows(kept.master_dofs.ravel()))
    compliance.restrict(kept, keep, needed)
    _compare_with_dense(compliance, kept, A_zone, zone_dofs)
    compliance.destroy()


def _compare_with_dense(compliance, ops, A_zone, zone_dofs) -> None:
    """The compliance's G for this rank's points ``ops`` against the dense product."""

    def gather(a):
        return compliance.points_to_block(_gather_rows(a))

    M_b = compliance.master_operator(gather(ops.master_dofs), gather(ops.master))
    G = compliance.matrix(M_b, gather(ops.weight))
    n_zone = len(zone_dofs)
    A_dense = _gather_rows(A_zone.convert("dense").getDenseArray())
    column = {int(d): i for i, d in enumerate(zone_dofs)}

    def dense_rows(dofs, values):
        rows = np.zeros((3 * len(dofs), n_zone))
        for p in range(len(dofs)):
            for c, dof in enumerate(dofs[p]):
                rows[3 * p : 3 * p + 3, column[int(dof)]] += values[p, :, c]
        return compliance.to_block(_gather_rows(rows))

    E = dense_rows(ops.slave_dofs, ops.E_slave) + dense_rows(ops.master_dofs, ops.master)
    F = dense_rows(ops.slave_dofs, ops.F_slave) + dense_rows(ops.master_dofs, ops.master)
    W = np.repeat(gather(ops.weight), 3)
    reference = E @ np.linalg.solve(A_dense, F.T * W)
    assert G.shape == reference.shape == (3 * compliance.points, 3 * compliance.points)
    assert np.abs(G - reference).max() <= 1e-8 * np.abs(reference).max()


def _relaxed_iterations(rate: np.ndarray, fixed: np.ndarray, relax: bool, tol=1e-12) -> int:
    """Iterations of mu_k = mu(u_k) for the linear map mu(u_k) = fixed + rate (mu_{k-1} - fixed)
    (the coefficients at the iterate of an inner problem with mu_{k-1}) until |mu - fixed| <= tol,
    through ``CoefficientRelaxation`` or plainly."""
    relaxation = CoefficientRelaxation(0.0, 1.0)
    mu = np.full_like(fixed, 0.5)
    for k in range(1, 1000):
        at_iterate = fixed + rate * (mu - fixed)
        mu = relaxation(at_iterate) if relax else at_iterate
        if np.abs(mu - fixed).max() <= tol:
            return k
    return 1000


def test_coefficient_relaxation_accelerates_the_fixed_point():
    """Velocity weakening feeds slip back into slip: the fixed point's rate is near 1 in an
    event. One rate (0.9): the plain iteration needs log(1e-12 / 0.1) / log(0.9) = 240
    iterations (241 counted), the relaxation 3 (omega = 1 / (1 - c) = 10 from the second). Rates 0.5-0.95 between
    points: at most a fifth of the plain count (measured 51 against 367)."""
    rng = np.random.default_rng(1)
    fixed = rng.uniform(0.4, 0.45, 50)
    one_rate = np.full(50, 0.9)
    assert _relaxed_iterations(one_rate, fixed, relax=False) > 200
    assert _relaxed_iterations(one_rate, fixed, relax=True) == 3
    rates = rng.uniform(0.5, 0.95, 50)
    plain = _relaxed_iterations(rates, fixed, relax=False)
    assert _relaxed_iterations(rates, fixed, relax=True) <= plain / 5
    relaxation = CoefficientRelaxation(0.4, 0.5)  # mu fixed within the step: passed through
    for _ in range(3):
        assert np.array_equal(relaxation(fixed), fixed)
    relaxation.reset()
    relaxation(np.full(3, 0.45))
    assert np.all(relaxation(np.full(3, 0.41)) >= 0.4)  # within the law's range
    assert len(relaxation(np.full(5, 0.45))) == 5  # other points: restarted


def _installation_steps(case, vibration_steps: int) -> tuple[float, np.ndarray, list[int]]:
    """The quick joint's self-weight ramp and ``vibration_steps`` steps of the 120 Hz eccentric
    stage: settlement [mm], the displacement (gathered) [m] and the iterations of each step."""
    comm = MPI.COMM_WORLD
    model = set_up_joint_model(comm, case)
    problem, sw = model.problem, case.self_weight
    iterations = []

    def record(p):
        iterations.append(p.last_result.iterations)
        return {}

    run(problem, sw.ramp_time_s, sw.dt_s, observers=[record], progress=False)
    dt = 1.0 / (120.0 * 16)
    stage = case.vibration.stage(vibration_steps * dt, 120.0, "eccentric")
    attach_vibration(model, Schedule([stage], start_s=problem.t))
    problem.set_scheme(case.vibration_scheme())
    run(problem, problem.t + vibration_steps * dt, dt, observers=[record], progress=False)
    assert problem.failed_steps == 0
    u = problem.u.x.petsc_vec
    order = np.concatenate(comm.allgather(np.arange(*u.getOwnershipRange())))
    values = _gather_rows(u.array_r.copy())
    return model.settlement(problem)["settlement_mm"], values[np.argsort(order)], iterations


def test_points_solver_matches_zone_newton(quick_case):
    """mu lagged by a step, or at the step's own slip speed (the zone Newton with mu's
    derivative, the points solver by a fixed point in its outer iteration); d_c = 5 s/m makes
    mu vary over the TP's slip speeds, so that the two laws give different solutions (measured:
    3.12816 against 3.13129 mm, 1.0e-3 apart; tested to 5e-4). Both solvers stop at ||R|| <= 1e-7 ||b||, which
    at these steps allows residuals of up to about 1 N; lagged they agree to 7e-8 (tested to
    1e-6), with the fixed point in mu to 6.1e-6 (tested to 1e-5)."""
    settlement = {}
    for lagged in ("true", "false"):
        overrides = (
            "contact.lu_solver=mumps",
            "time.steps_per_period=16",
            "friction.d_c=5",
            f"contact.lagged_friction={lagged}",
        )
        zone = _installation_steps(quick_case(*overrides), 8)
        points = _installation_steps(quick_case(*overrides, 'contact.solver="points"'), 8)
        print(
            f"\nlagged friction {lagged}: settlement zone Newton {zone[0]:.9f} mm "
            f"({zone[2]} iterations), points {points[0]:.9f} mm ({points[2]} iterations)"
        )
        assert zone[0] > 0.1
        rtol = 1e-6 if lagged == "true" else 1e-5
        assert points[0] == pytest.approx(zone[0], rel=rtol)
        assert np.linalg.norm(points[1] - zone[1]) <= rtol * np.linalg.norm(zone[1])
        settlement[lagged] = points[0]
    assert abs(settlement["true"] - settlement["false"]) > 5e-4 * settlement["true"]


def test_the_default_tolerance_keeps_the_settlement(quick_case):
    """The outer tolerance of the default case (cases/scaled.toml, ``[contact] newton_rtol``)
    against a tight one (1e-9), with mu at the step's own slip speed (d_c = 5 s/m) on the quick
    frictional joint's ramp and 8 eccentric steps: the settlement and the displacement within
    1e-3 relative, a thirtieth of the time step's error at 16 steps per period (3.5 %,
    docs/dynamics.md, "Convergence in the time step"), in fewer Newton iterations."""
    default = InstallationCase.from_dict(read_case("scaled")).contact.newton_rtol
    runs = {}
    for rtol in (default, 1e-9):
        case = quick_case(
            "contact.lu_solver=mumps",
            "time.steps_per_period=16",
            "friction.d_c=5",
            "contact.lagged_friction=false",
            'contact.solver="points"',
            f"contact.newton_rtol={rtol}",
        )
        runs[rtol] = _installation_steps(case, 8)
    (s, u, its), (s_tight, u_tight, its_tight) = runs[default], runs[1e-9]
    print(
        f"\nnewton_rtol {default:g}: settlement {s:.9f} mm in {sum(its)} Newton iterations; "
        f"1e-9: {s_tight:.9f} mm in {sum(its_tight)} (relative difference "
        f"{abs(s - s_tight) / s_tight:.1e}, displacement "
        f"{np.linalg.norm(u - u_tight) / np.linalg.norm(u_tight):.1e})"
    )
    assert default > 1e-9 and s_tight > 0.1
    assert s == pytest.approx(s_tight, rel=1e-3)
    assert np.linalg.norm(u - u_tight) <= 1e-3 * np.linalg.norm(u_tight)
    assert sum(its) < sum(its_tight)
