"""Dynamic Nitsche contact against a rigid plane: impacting bar and friction oscillator.

1. Impacting elastic bar (Chouly, Hild & Renard 2015; Doyen, Ern & Piperno 2011):
   bar (0, 1), E = rho = 1, clamped at x = 1, rigid wall at x = 0 (u(0) >= 0),
   initial displacement u0 = 0.5 - 0.5 x, at rest. Exact solution (d'Alembert),
   periodic with period 3: u(0, t) = 0.5 - t/2 on (0, 1), 0 on (1, 2) (contact,
   pressure 1/2), (t - 2)/2 on (2, 3); energy 1/8.
2. Friction oscillator: a stiff block (mass m) on a rigid plane under normal load N,
   tied to ground by a spring k, driven by F0 cos(omega t + phi), Coulomb friction
   F_f = mu N. Reference: Den Hartog's (1931) closed-form periodic motion without
   stops, obtained from the half-period boundary-value problem
   m x'' + k x = F0 cos(omega t + phi) - F_f, x(0) = -X0, x(pi/omega) = X0, x' = 0 at both.
   With stops (stick-slip) the reference is a run with ten times finer steps.
"""

import functools

import numpy as np
import pytest
import ufl
from mpi4py import MPI
from petsc4py import PETSc
from scipy.integrate import solve_ivp

from dolfinx import fem, mesh
from dolfinx.fem.petsc import assemble_vector

from common.material import Material
from solver.contact import FrictionLaw, RigidPlaneContact, Status
from solver.dynamics.elastodynamics import Elastodynamics, assemble_structure
from solver.dynamics.loads import TopFaceLoad
from solver.dynamics.schemes import GeneralisedAlpha, QuasiStatic
from solver.dynamics.time_loop import EventSteps, run
from solver.probes import PointProbe

pytestmark = pytest.mark.mpi

# plain Newton with a fresh LU per iteration: ContactNewtonSolver's adaptive refactorisation
# decides by each rank's own timings, which can disagree between ranks and deadlock
NEWTON = {"refactor_after": 0}


def bar_exact(t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(u(0, t) [m], contact pressure [Pa]) of the impacting bar."""
    t = np.mod(t, 3.0)
    u = np.where(t < 1, 0.5 - 0.5 * t, np.where(t < 2, 0.0, 0.5 * (t - 2)))
    return u, np.where((t > 1) & (t < 2), 0.5, 0.0)


def bar_history(n: int, t_end: float = 3.0) -> dict[str, np.ndarray]:
    """Time [s], u(0, t) [m], contact pressure [Pa] and energy [J] of the impacting bar with n cells."""
    domain = mesh.create_interval(MPI.COMM_WORLD, n, [0.0, 1.0])
    V = fem.functionspace(domain, ("Lagrange", 1, (1,)))
    material = Material(E=1.0, nu=0.0, rho=1.0)
    bcs = [fem.dirichletbc(0.0, fem.locate_dofs_geometrical(V, lambda x: np.isclose(x[0], 1.0)), V)]
    M, K = assemble_structure(V, material, bcs)
    wall = mesh.locate_entities_boundary(domain, 0, lambda x: np.isclose(x[0], 0.0))
    tags = mesh.meshtags(domain, 0, wall, np.full(len(wall), 1, dtype=np.int32))
    contact = RigidPlaneContact(
        V, tags, 1, material, None, [0, 0, 0], [1, 0, 0], gamma0=1.0, theta=0.0
    )
    problem = Elastodynamics(V, M, K, bcs, contact=contact, newton_options=NEWTON)
    problem.u.interpolate(lambda x: (0.5 - 0.5 * x[0])[None, :])
    problem.initialise(0.0)
    end = PointProbe(problem.u, [[0.0, 0.0, 0.0]])

    def observe(p):
        pressure = domain.comm.allreduce(
            contact.state.pressure.sum()
        )  # one quadrature point: x = 0
        return {"u0_m": end()[0, 0], "pressure_Pa": pressure, "energy_J": sum(p.energy())}

    rows = run(problem, t_end, 1.0 / n, observers=[observe], progress=False)  # dt = h (CFL 1)
    return {
        k: np.array([r[k] for r in rows]) for k in ("time_s", "u0_m", "pressure_Pa", "energy_J")
    }


def impacting_bar(n: int, t_end: float = 3.0):
    """Errors (L2 in time, relative to the L2 norm of the exact history) and energy range."""
    t, u, p, e = bar_history(n, t_end).values()
    u_ex, p_ex = bar_exact(t)
    error_u = np.sqrt(np.sum((u - u_ex) ** 2) / np.sum(u_ex**2))
    error_p = np.sqrt(np.sum((p - p_ex) ** 2) / np.sum(p_ex**2))
    return error_u, error_p, (e.min() - 0.125) / 0.125, (e.max() - 0.125) / 0.125


def test_impacting_bar_converges_and_keeps_its_energy():
    table = [(n, *impacting_bar(n)) for n in (20, 40, 80)]
    if MPI.COMM_WORLD.rank == 0:
        print("\n   n   err u(0,t)  err pressure  energy min/max - 1/8 (relative)")
        for n, eu, ep, emin, emax in table:
            print(f"{n:4d}  {eu:10.3e}  {ep:12.3e}  {emin:+.3e} / {emax:+.3e}")
    eu = np.array([row[1] for row in table])
    ep = np.array([row[2] for row in table])
    assert np.all(np.diff(eu) < 0) and np.all(np.diff(ep) < 0)
    rate_u, rate_p = np.log2(eu[0] / eu[-1]) / 2, np.log2(ep[0] / ep[-1]) / 2
    assert rate_u > 0.5 and rate_p > 0.3, (rate_u, rate_p)
    assert all(abs(row[3]) < 0.15 and abs(row[4]) < 0.15 for row in table)  # bounded
    assert abs(table[-1][3]) < 0.03 and abs(table[-1][4]) < 0.03


def den_hartog(m, k, F0, Ff, omega):
    """Amplitude X0 [m], phase phi [rad] and x(t) on (0, pi/omega) of the non-stop periodic motion."""
    wn = np.sqrt(k / m)
    theta = np.pi * wn / omega
    D = F0 / (k * (1 - (omega / wn) ** 2))
    # x = C1 cos(wn t) + C2 sin(wn t) + D cos(omega t + phi) - Ff/k; x' = 0 at 0 and pi/omega
    alpha, beta = np.linalg.solve(
        [[0, wn], [-wn * np.sin(theta), wn * np.cos(theta)]], [omega * D, -omega * D]
    )
    s = 2 * Ff / k / (alpha * (1 + np.cos(theta)) + beta * np.sin(theta))  # x(pi/omega) = -x(0)
    C1, C2 = alpha * s, beta * s
    for c in (np.sqrt(1 - s * s), -np.sqrt(1 - s * s)):
        X0, phi = Ff / k - C1 - D * c, np.arctan2(s, c)

        def x(t, phi=phi):
            return C1 * np.cos(wn * t) + C2 * np.sin(wn * t) + D * np.cos(omega * t + phi) - Ff / k

        t = np.linspace(0, np.pi / omega, 2001)[1:-1]
        if X0 > 0 and np.all(np.diff(x(t)) > 0):  # moves up throughout: no stop
            return X0, phi, x
    raise ValueError("no non-stop periodic motion for these parameters")


M_BLOCK, K_SPRING, F0, MU = 1.0, (2 * np.pi) ** 2, 1.0, 0.3  # kg, N/m (1 Hz), N, -
F_FRICTION, OMEGA = 0.2, 0.6 * 2 * np.pi  # N, rad/s
STOPS = 0.6  # friction force [N] with which the block, started at rest, stops once
STICKS = 0.95  # friction force [N] with which the block sticks for much of each half-period
SLIDING_RATE = 1e-4  # block speed [m/s] above which it slides (its peak speed: about 20 mm/s)


def test_den_hartog_reference_solves_the_ode():
    """The closed form against scipy's ODE solver over one upward half-period."""
    X0, phi, x = den_hartog(M_BLOCK, K_SPRING, F0, F_FRICTION, OMEGA)

    def rhs(t, y):
        return [y[1], (F0 * np.cos(OMEGA * t + phi) - F_FRICTION - K_SPRING * y[0]) / M_BLOCK]

    t = np.linspace(0, np.pi / OMEGA, 50)
    sol = solve_ivp(rhs, (0, t[-1]), [-X0, 0.0], t_eval=t, rtol=1e-11, atol=1e-13)
    assert np.max(np.abs(sol.y[0] - x(t))) < 1e-8 * X0
    assert sol.y[0][-1] == pytest.approx(X0, rel=1e-8) and abs(sol.y[1][-1]) < 1e-8


def friction_oscillator(
    periods: float = 2.0,
    friction_force: float = F_FRICTION,
    backtracks: int = 0,
    steps_per_period: int = 100,
    event_steps_per_period: int = 0,
    operators_kept: int = 1,
) -> dict[str, np.ndarray]:
    """Time [s], block displacement x [m] and the number of slipping points per step of the
    friction oscillator with friction force ``friction_force`` [N], ``steps_per_period`` steps
    per period (and ``event_steps_per_period`` while the block slides faster than
    SLIDING_RATE: ``EventSteps``; ``operators_kept``: ``Elastodynamics``), started on Den
    Hartog's orbit (x = -X0, at rest) where that exists, else at rest at x = 0 with phi = 0
    (``backtracks``: Newton line-search halvings, which the stops need)."""
    try:
        X0, phi, _ = den_hartog(M_BLOCK, K_SPRING, F0, friction_force, OMEGA)
    except ValueError:  # motion with stops
        X0, phi = 0.0, 0.0
    a = 0.1  # block side [m]; 2D, per unit thickness
    domain = mesh.create_rectangle(
        MPI.COMM_WORLD, [[0, 0], [a, a]], [2, 2], mesh.CellType.quadrilateral
    )
    V = fem.functionspace(domain, ("Lagrange", 1, (2,)))
    material = Material(
        E=1e8, nu=0.0, rho=M_BLOCK / a**2
    )  # internal modes ~ kHz: a rigid block at 0.6 Hz
    bottom = mesh.locate_entities_boundary(domain, 1, lambda x: np.isclose(x[1], 0.0))
    top = mesh.locate_entities_boundary(domain, 1, lambda x: np.isclose(x[1], a))
    facets = np.concatenate([bottom, top])
    order = np.argsort(facets)
    values = np.concatenate([np.full(len(bottom), 1), np.full(len(top), 2)]).astype(np.int32)
    tags = mesh.meshtags(domain, 1, facets[order], values[order])
    w = ufl.TestFunction(V)
    spring = (
        (K_SPRING / a**2) * ufl.TrialFunction(V)[0] * w[0] * ufl.dx
    )  # spring to ground, total k
    M, K = assemble_structure(V, material, [], extra_stiffness=spring)
    friction = FrictionLaw(mu_s=MU, mu_d=MU, d_c=0.0)
    contact = RigidPlaneContact(
        V, tags, 1, material, friction, [0, 0, 0], [0, 1, 0], gamma0=10.0, theta=0.0
    )
    top_load = TopFaceLoad(V, tags, 2)
    drive = assemble_vector(fem.form((1.0 / a**2) * w[0] * ufl.dx))  # unit total horizontal force
    drive.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    normal = np.array([0.0, -friction_force / MU, 0.0])

    def load(t, out):
        top_load.add(normal, out)
        out.axpy(F0 * np.cos(OMEGA * t + phi), drive)

    # static pre-load under N, then start on the periodic orbit: x = -X0, at rest
    static = Elastodynamics(
        V,
        M,
        K,
        [],
        scheme=QuasiStatic(),
        contact=contact,
        load=lambda t, out: top_load.add(normal, out),
        newton_options=NEWTON,
    )
    static.initialise(0.0)
    assert static.step(1.0).converged
    assert contact.normal_force() == pytest.approx(friction_force / MU, rel=1e-6)
    problem = Elastodynamics(
        V,
        M,
        K,
        [],
        scheme=GeneralisedAlpha.from_spectral_radius(0.5),
        contact=contact,
        load=load,
        newton_options=NEWTON | {"max_backtracks": backtracks},
        operators_kept=operators_kept,
    )
    problem.u.x.array[:] = static.u.x.array
    problem.u.x.array[0::2] -= X0
    problem.initialise(0.0)
    centre = PointProbe(problem.u, [[a / 2, a / 2, 0.0]])

    def observe(p):
        slipping = domain.comm.allreduce(int(np.sum(contact.state.status == Status.SLIP)))
        return {"x_m": centre()[0, 0], "slipping": slipping}

    period = 2 * np.pi / OMEGA
    events = None
    if event_steps_per_period:
        events = EventSteps(
            period / event_steps_per_period, SLIDING_RATE, lambda p: centre()[0, 0], calm_steps=5
        )
    rows = run(
        problem,
        periods * period,
        period / steps_per_period,
        observers=[observe],
        progress=False,
        events=events,
    )
    return {k: np.array([r[k] for r in rows]) for k in ("time_s", "x_m", "slipping")}


def test_friction_oscillator_matches_den_hartog():
    X0, _, x_half = den_hartog(M_BLOCK, K_SPRING, F0, F_FRICTION, OMEGA)
    period = 2 * np.pi / OMEGA
    t, x, slipping = friction_oscillator().values()
    second = t > period
    amplitude = 0.5 * (x[second].max() - x[second].min())
    exact = np.where(np.mod(t, period) < period / 2, 1.0, -1.0) * x_half(np.mod(t, period / 2))
    history_error = np.max(np.abs(x - exact)) / X0
    print(
        f"\nfriction oscillator: amplitude {amplitude:.6f} m, Den Hartog {X0:.6f} m "
        f"({amplitude / X0 - 1:+.2%}); max history error {history_error:.2%} of X0"
    )
    assert amplitude == pytest.approx(X0, rel=0.03)
    assert history_error < 0.03
    assert slipping.sum() > 0  # the block slides (and it is not glued by a wrong friction limit)


def test_event_steps_resolve_stick_slip():
    """Stick-slip (friction 0.95 F0, started at rest): 20 steps per period, retaken at 200 per
    period wherever the block slides (``EventSteps``), follow the uniform run at 200 steps per
    period, which the uniform run at 20 does not; the long steps fall only where the block
    sticks (in them the uniform run at 200 travels less than 0.1 % of its path). Keeping the
    operators of both step sizes changes nothing but the cost."""
    period = 2 * np.pi / OMEGA
    run_with = functools.partial(friction_oscillator, 3.0, STICKS, 4)
    fine = run_with(steps_per_period=200)
    coarse = run_with(steps_per_period=20)
    stepped = run_with(steps_per_period=20, event_steps_per_period=200, operators_kept=2)
    refactorised = run_with(steps_per_period=20, event_steps_per_period=200)
    grid = np.arange(1, 61) * period / 20
    reference = np.interp(grid, fine["time_s"], fine["x_m"])
    amplitude = np.max(np.abs(reference))

    def error(history):
        return np.max(np.abs(np.interp(grid, history["time_s"], history["x_m"]) - reference))

    dt = np.diff(np.r_[0.0, stepped["time_s"]])
    long = dt > 1.5 * period / 200
    within_long = np.zeros(len(fine["time_s"]), dtype=bool)  # the fine run's steps in long ones
    for end, step in zip(stepped["time_s"][long], dt[long]):
        within_long |= (fine["time_s"] > end - step + 1e-12) & (fine["time_s"] <= end + 1e-12)
    travel = np.abs(np.diff(np.r_[0.0, fine["x_m"]]))  # the fine run's path per step [m]
    print(
        f"\nstick-slip over 3 periods: {len(stepped['time_s'])} steps ({np.sum(long)} long) "
        f"against {len(fine['time_s'])}; largest error {error(stepped) / amplitude:.2%} of the "
        f"amplitude, uniform long steps {error(coarse) / amplitude:.0%}"
    )
    assert error(stepped) < 0.01 * amplitude < 0.1 * error(coarse)
    assert 0 < np.sum(long) and len(stepped["time_s"]) < 0.7 * len(fine["time_s"])
    assert travel[within_long].sum() < 1e-3 * travel.sum()  # long steps where the block rests
    assert np.array_equal(stepped["time_s"], refactorised["time_s"])
    assert np.max(np.abs(stepped["x_m"] - refactorised["x_m"])) < 1e-7 * amplitude


def test_newton_starts_from_u_n_where_stick_and_slip_change(monkeypatch):
    """Each step's Newton solve starts from the predictor unless some point's status there
    changes between stick and slip against the last step's; then from u_n
    (``Elastodynamics.initial_guesses``). In the friction oscillator with a stop (friction
    0.6 F0, started at rest) that happens only around the stop. The start must not change the
    solution: the history equals that of predictor-first starts to the Newton tolerance."""
    original = Elastodynamics.initial_guesses
    starts = []

    def spy(self, u_old, dt):
        guesses = original(self, u_old, dt)
        starts.append((self.t + dt, guesses[0] is u_old))
        return guesses

    monkeypatch.setattr(Elastodynamics, "initial_guesses", spy)
    chosen = friction_oscillator(periods=2.0, friction_force=STOPS, backtracks=4)
    t_u_n = np.array([t for t, first in starts if first])
    sticking = chosen["time_s"][chosen["slipping"] == 0]
    period = 2 * np.pi / OMEGA
    print(
        f"\nu_n first at t / period = {np.round(t_u_n / period, 3)}; sticking steps at "
        f"{np.round(sticking / period, 3)}"
    )
    assert sticking.size > 0 and t_u_n.size > 0
    # u_n starts only around the stop (the points' slip restarts over a few steps), none while
    # the block slides on
    assert all(np.min(np.abs(sticking - t)) <= 0.05 * period for t in t_u_n)
    assert t_u_n.size <= 0.1 * chosen["time_s"].size

    def predictor_first(self, u_old, dt):
        return u_old + dt * self.v.x.array + 0.5 * dt**2 * self.a.x.array, u_old

    monkeypatch.setattr(Elastodynamics, "initial_guesses", predictor_first)
    reference = friction_oscillator(periods=2.0, friction_force=STOPS, backtracks=4)
    assert np.array_equal(chosen["time_s"], reference["time_s"])
    assert np.max(np.abs(chosen["x_m"] - reference["x_m"])) < 1e-7 * np.max(
        np.abs(reference["x_m"])
    )
