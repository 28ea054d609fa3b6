"""Reduced (lumped-element) stick/slip model of the slip-joint installation (docs/physics.md §7).

Degrees of freedom q = (v, u, theta, w), all in SI units (m, m, rad, m):

* v      axial displacement of the rigid TP, positive *down* (settlement), mass M;
* u      radial displacement of the TP's lower edge ring (outward), spring K_r, mass m_r;
* theta  meridional rotation ("rocking") of that edge ring, spring K_rot, inertia J_rot;
         positive when it moves the TP's inner fibre down the MP meridian;
* w      displacement of the MP's contact circle down its meridian, spring K_T, mass m_T.

The springs and masses come from shell statics (:func:`solver.reduced.shell.joint_stiffness`).
Contact acts at the TP's inner surface at its lower edge, on the MP cone of
half-angle alpha:

* normal penetration  g  = v sin(alpha) - u cos(alpha),  normal force N = K_N max(g, 0)
* tangential slip     xi = v cos(alpha) + u sin(alpha) + e theta - w,  e = h_TP / 2

Equations of motion (downward axial force F(t) on the TP):

    Mass q'' + C q' + K q = F(t) e_v - N a - T b,   a = dg/dq, b = dxi/dq,

with T the friction force (on the TP, opposing downward slip when positive):
stick: xi' = 0 and T is the constraint force that keeps xi'' = 0, admissible while
|T| <= mu_s N; slip: T = sign(xi') mu(|xi'|) N with the friction law's mu(v)
(d_c = inf: Coulomb with a step from mu_s to mu_d). Transitions are located as
events of scipy's adaptive Runge-Kutta integrators. Damping: C diagonal, each dof
at ``damping_ratio`` of critical for its own spring (for v: the axial stick stiffness).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from enum import Enum

import numpy as np
import numpy.typing as npt
from scipy.integrate import solve_ivp
from scipy.linalg import eigh

from solver.contact import FrictionLaw
from solver.reduced.shell import JointStiffness

#: standard gravity [m/s^2]
GRAVITY = 9.81


class Mode(Enum):
    """Contact state of the edge ring on the MP."""

    STICK = 0
    SLIP_DOWN = 1
    SLIP_UP = -1
    OPEN = 2


@dataclass(frozen=True)
class AxialLoad:
    """Downward axial force on the TP [N]: a static part ramped linearly over
    ``ramp_time`` [s] (0: applied at once), plus ``amplitude`` sin(2 pi f t) starting
    at ``harmonic_start`` [s]."""

    static: float = 0.0
    ramp_time: float = 0.0
    amplitude: float = 0.0
    frequency: float = 0.0
    harmonic_start: float = 0.0

    def __post_init__(self) -> None:
        if (
            self.ramp_time < 0
            or self.frequency < 0
            or self.amplitude < 0
            or self.harmonic_start < 0
        ):
            raise ValueError(
                "ramp_time, frequency, amplitude and harmonic_start must be >= 0, got "
                f"{self.ramp_time} s, {self.frequency} Hz, {self.amplitude} N, "
                f"{self.harmonic_start} s"
            )

    def __call__(self, t: float) -> float:
        ramp = 1.0 if self.ramp_time == 0 else min(t / self.ramp_time, 1.0)
        tau = max(t - self.harmonic_start, 0.0)
        return self.static * ramp + self.amplitude * math.sin(2 * math.pi * self.frequency * tau)


@dataclass(frozen=True)
class LumpedModel:
    """The 4-dof stick/slip model: masses, springs, contact geometry and friction."""

    mass: float  #: TP mass M [kg]
    springs: JointStiffness
    alpha: float  #: MP cone half-angle [rad]
    lever: float  #: distance of the TP's inner surface from its mid-surface, h/2 [m]
    friction: FrictionLaw = field(default_factory=lambda: FrictionLaw(0.5, 0.3, math.inf))
    damping_ratio: float = 0.01

    def __post_init__(self) -> None:
        if not self.mass > 0:
            raise ValueError(f"TP mass must be positive, got {self.mass} kg")
        if not 0 < self.alpha < math.pi / 4:
            raise ValueError(f"alpha must lie in (0, pi/4) rad, got {self.alpha}")
        if not self.lever >= 0:
            raise ValueError(f"lever must be >= 0 m, got {self.lever}")
        if not self.damping_ratio >= 0:
            raise ValueError(f"damping_ratio must be >= 0, got {self.damping_ratio}")

    # --- constant matrices --------------------------------------------------------
    @property
    def masses(self) -> npt.NDArray[np.float64]:
        s = self.springs
        return np.array([self.mass, s.m_r, s.J_rot, s.m_T])

    @property
    def stiffness(self) -> npt.NDArray[np.float64]:
        """Diagonal of K (no spring on v) [N/m, N/m, N m/rad, N/m]."""
        s = self.springs
        return np.array([0.0, s.K_r, s.K_rot, s.K_T])

    @property
    def a(self) -> npt.NDArray[np.float64]:
        """dg/dq."""
        return np.array([math.sin(self.alpha), -math.cos(self.alpha), 0.0, 0.0])

    @property
    def b(self) -> npt.NDArray[np.float64]:
        """dxi/dq."""
        return np.array([math.cos(self.alpha), math.sin(self.alpha), self.lever, -1.0])

    @property
    def stick_basis(self) -> npt.NDArray[np.float64]:
        """Z with q = Z r + const in stick: r = (v, u, theta), w = b[:3] . r - xi (xi fixed)."""
        return np.vstack([np.eye(3), self.b[:3]])

    def stick_stiffness(self) -> npt.NDArray[np.float64]:
        """Stiffness matrix Z^T K Z of the sticking, closed contact."""
        Z = self.stick_basis
        return Z.T @ (np.diag(self.stiffness) + self.springs.K_N * np.outer(self.a, self.a)) @ Z

    def stick_frequencies(self) -> npt.NDArray[np.float64]:
        """Natural frequencies [Hz] of the closed, sticking joint (undamped, ascending)."""
        Z = self.stick_basis
        w2 = eigh(self.stick_stiffness(), Z.T @ np.diag(self.masses) @ Z, eigvals_only=True)
        return np.sqrt(w2) / (2 * math.pi)

    def axial_stick_stiffness(self) -> float:
        """Axial stiffness of the TP in stick, other dofs condensed out [N/m]."""
        Kr = self.stick_stiffness()
        return float(Kr[0, 0] - Kr[0, 1:] @ np.linalg.solve(Kr[1:, 1:], Kr[1:, 0]))

    @property
    def damping(self) -> npt.NDArray[np.float64]:
        """Diagonal of C [N s/m, ...]."""
        k = self.stiffness.copy()
        k[0] = self.axial_stick_stiffness()
        return 2 * self.damping_ratio * np.sqrt(k * self.masses)

    def static_slip_settlement(self, force: float, mu: float | None = None) -> float:
        """Closed-form settlement [m] under a slowly applied axial force [N], slipping at mu.

        Quasi-static slip with T = mu N: N = F / (sin a + mu cos a),
        u = N (cos a - mu sin a) / K_r, v = (N / K_N + u cos a) / sin a.
        """
        mu = self.friction.mu_d if mu is None else mu
        sa, ca = math.sin(self.alpha), math.cos(self.alpha)
        N = force / (sa + mu * ca)
        u = N * (ca - mu * sa) / self.springs.K_r
        return (N / self.springs.K_N + u * ca) / sa

    def slip_coefficient(self, slip_speed: float) -> float:
        """mu during slip at |xi'| [m/s]; d_c = inf gives mu_d (Coulomb step)."""
        law = self.friction
        if math.isinf(law.d_c):
            return law.mu_d
        return float(law.coefficient(slip_speed))


@dataclass
class Trajectory:
    """Time history of a run: t [s], q, qdot, mode per sample, events, energies [J]."""

    t: npt.NDArray[np.float64]
    q: npt.NDArray[np.float64]  #: (4, n) v, u, theta, w
    qdot: npt.NDArray[np.float64]
    mode: npt.NDArray[np.int_]  #: Mode value per sample
    work: npt.NDArray[np.float64]  #: (3, n) external work, damping, friction dissipation
    events: list[tuple[float, Mode, Mode]]  #: (time, from, to)
    stuck_forever: bool = False  #: ended early: proven to stick under the load forever
    #: settlement [m] of the final state: in stick, the static equilibrium v at the final
    #: stick anchor under the static load alone (vibration died out); else v at the end
    final_settlement: float = math.nan

    @property
    def settlement(self) -> npt.NDArray[np.float64]:
        """v [m], down positive."""
        return self.q[0]

    def mechanical_energy(self, model: LumpedModel) -> npt.NDArray[np.float64]:
        """Kinetic + elastic (springs and normal contact) energy [J] at every sample."""
        m, k = model.masses, model.stiffness
        g = np.maximum(model.a @ self.q, 0.0)
        return 0.5 * (m @ self.qdot**2 + k @ self.q**2 + model.springs.K_N * g**2)

    def slip_intervals(self) -> list[tuple[int, int]]:
        """Sample index ranges [start, end] of the slip phases (ends at events)."""
        slipping = np.isin(self.mode, (Mode.SLIP_DOWN.value, Mode.SLIP_UP.value))
        out, start = [], None
        for i in range(1, self.t.size):
            if slipping[i] and start is None:
                start = i - 1
            if start is not None and (not slipping[i] or i == self.t.size - 1):
                out.append((start, i if slipping[i] else i - 1))
                start = None
        return out


class _Dynamics:
    """Right-hand side and event functions of one mode."""

    def __init__(self, model: LumpedModel, load: AxialLoad):
        self.model = model
        self.load = load
        self.m = model.masses
        self.k = model.stiffness
        self.c = model.damping
        self.a = model.a
        self.b = model.b
        self.minv_b = self.b / self.m
        self.b_minv_b = float(self.b @ self.minv_b)
        self.K_N = model.springs.K_N
        self.mu_s = model.friction.mu_s

    def split(self, y):
        return y[0:4], y[4:8]

    def normal_force(self, q) -> float:
        return self.K_N * max(float(self.a @ q), 0.0)

    def free_force(self, t, q, qd, N) -> npt.NDArray:
        """All generalized forces except friction [N]."""
        f = -self.c * qd - self.k * q - N * self.a
        f[0] += self.load(t)
        return f

    def stick_friction(self, t, q, qd, N) -> float:
        """Constraint force T that keeps xi'' = 0 [N]."""
        return float(self.minv_b @ self.free_force(t, q, qd, N)) / self.b_minv_b

    def friction(self, mode: Mode, t, q, qd, N) -> float:
        if mode is Mode.OPEN:
            return 0.0
        if mode is Mode.STICK:
            return self.stick_friction(t, q, qd, N)
        slip_speed = abs(float(self.b @ qd))
        return mode.value * self.model.slip_coefficient(slip_speed) * N

    def rhs(self, mode: Mode):
        def f(t, y):
            q, qd = self.split(y)
            N = 0.0 if mode is Mode.OPEN else self.normal_force(q)
            T = self.friction(mode, t, q, qd, N)
            force = self.free_force(t, q, qd, N) - T * self.b
            return np.concatenate(
                [
                    qd,
                    force / self.m,
                    [self.load(t) * qd[0], float(qd @ (self.c * qd)), T * float(self.b @ qd)],
                ]
            )

        return f

    def events(self, mode: Mode) -> list:
        def terminal(fun, direction):
            fun.terminal, fun.direction = True, direction
            return fun

        def gap(t, y):
            return float(self.a @ y[0:4])

        if mode is Mode.OPEN:
            return [terminal(gap, 1)]
        evs = [terminal(gap, -1)]
        if mode is Mode.STICK:

            def slip_down(t, y):
                q, qd = self.split(y)
                N = self.normal_force(q)
                return self.mu_s * N - self.stick_friction(t, q, qd, N)

            def slip_up(t, y):
                q, qd = self.split(y)
                N = self.normal_force(q)
                return self.mu_s * N + self.stick_friction(t, q, qd, N)

            evs += [terminal(slip_down, -1), terminal(slip_up, -1)]
        else:
            evs.append(terminal(lambda t, y: mode.value * float(self.b @ y[4:8]), -1))
        return evs

    def select_mode(self, t, y) -> Mode:
        """Contact state consistent with (t, y) (after an event or at the start)."""
        q, qd = self.split(y)
        g, gdot = float(self.a @ q), float(self.a @ qd)
        tol_g = 1e-12 * max(1.0, float(np.abs(q).max()))
        if g < -tol_g or (g <= tol_g and gdot < 0):
            return Mode.OPEN
        slip_rate = float(self.b @ qd)
        if abs(slip_rate) > 1e-12 * max(1.0, float(np.abs(qd).max())):
            return Mode.SLIP_DOWN if slip_rate > 0 else Mode.SLIP_UP
        N = self.normal_force(q)
        T = self.stick_friction(t, q, qd, N)
        if abs(T) <= self.mu_s * N:
            return Mode.STICK
        return Mode.SLIP_DOWN if T > 0 else Mode.SLIP_UP

    def stick_system(self, xi0: float):
        """Reduced stick system r = (v, u, theta), q = Z r + (0, 0, 0, -xi0).

        Returns (Z, z0, M_r, C_r, K_r, f0) with f0 the load vector that does not
        depend on F(t); the axial force enters as F(t) e_v (first entry).
        """
        Z = self.model.stick_basis
        z0 = np.array([0.0, 0.0, 0.0, -xi0])
        Mr = Z.T @ np.diag(self.m) @ Z
        Cr = Z.T @ np.diag(self.c) @ Z
        Kr = self.model.stick_stiffness()
        f0 = -Z.T @ (self.k * z0)
        return Z, z0, Mr, Cr, Kr, f0

    def _affine_in_state(self, fun, Z, z0):
        """Coefficients (c_r, c_rd, c_F, const) of a function linear in (q, qdot, F(t))."""
        base = np.zeros(8)
        base[0:4] = z0
        const_q = fun(base, 0.0)
        cr = np.array(
            [fun(np.concatenate([z0 + Z[:, i], np.zeros(4)]), 0.0) - const_q for i in range(3)]
        )
        crd = np.array([fun(np.concatenate([z0, Z[:, i]]), 0.0) - const_q for i in range(3)])
        cF = fun(base, 1.0) - const_q
        return cr, crd, cF, const_q

    def stuck_forever(self, t: float, y) -> tuple[bool, float]:
        """Whether the closed, sticking contact provably never slips or opens again.

        Valid once the static load is fully ramped and the harmonic has started: the
        stick system is linear, its response = steady state + a free vibration whose
        energy never grows (C >= 0); the friction margins and the gap are affine in the
        state, so |free part| <= ||coefficients||_(energy dual) sqrt(2 E_free).
        Returns (proof holds, static settlement v [m] at this stick anchor under the
        static load alone).
        """
        load = self.load
        q, qd = self.split(y)
        xi0 = float(self.b @ q)
        Z, z0, Mr, Cr, Kr, f0 = self.stick_system(xi0)
        ev = Z.T @ np.array([1.0, 0.0, 0.0, 0.0])
        r_static = np.linalg.solve(Kr, f0 + load.static * ev)
        if t < load.ramp_time or t < load.harmonic_start:
            return False, float(r_static[0])
        omega = 2 * math.pi * load.frequency
        R = np.linalg.solve(-(omega**2) * Mr + 1j * omega * Cr + Kr, load.amplitude * ev)
        phase = omega * (t - load.harmonic_start)
        # steady state at t: r = r_static + Im(R e^{i phase}), rdot = Im(i omega R e^{i phase})
        e = np.exp(1j * phase)
        r_ss, rd_ss = r_static + (R * e).imag, (1j * omega * R * e).imag
        r_now = np.linalg.lstsq(Z, q - z0, rcond=None)[0]
        rd_now = np.linalg.lstsq(Z, qd, rcond=None)[0]
        x, xd = r_now - r_ss, rd_now - rd_ss
        energy = 0.5 * (x @ Kr @ x + xd @ Mr @ xd)

        def margin(sign):
            def h(state, F):
                qq, qqd = state[0:4], state[4:8]
                N = self.K_N * float(self.a @ qq)  # affine (contact assumed closed)
                f = -self.c * qqd - self.k * qq - N * self.a
                f[0] += F
                return self.mu_s * N + sign * float(self.minv_b @ f) / self.b_minv_b

            return h

        def gap(state, F):
            return float(self.a @ state[0:4])

        for fun in (margin(-1.0), margin(1.0), gap):
            cr, crd, cF, c0 = self._affine_in_state(fun, Z, z0)
            mean = c0 + cr @ r_static + cF * load.static
            amp = abs(cr @ R + crd @ (1j * omega * R) + cF * load.amplitude)
            bound = math.sqrt(
                2 * energy * (cr @ np.linalg.solve(Kr, cr) + crd @ np.linalg.solve(Mr, crd))
            )
            if not mean - amp > bound:
                return False, float(r_static[0])
        return True, float(r_static[0])

    def project_stick(self, y) -> npt.NDArray:
        """Remove the (event-tolerance) slip rate from the velocities, momentum-consistently."""
        y = y.copy()
        qd = y[4:8]
        y[4:8] = qd - self.minv_b * float(self.b @ qd) / self.b_minv_b
        return y


def simulate(
    model: LumpedModel,
    load: AxialLoad,
    t_end: float,
    initial_velocity: float = 0.0,
    rtol: float = 1e-8,
    method: str = "DOP853",
    max_events: int = 100000,
    stop_when_stuck: bool = True,
    check_interval: float = 0.25,
) -> Trajectory:
    """Integrate from first contact (q = 0) with TP velocity ``initial_velocity`` [m/s, down].

    ``method`` is one of scipy's adaptive Runge-Kutta integrators ("RK23", "RK45",
    "DOP853"). With ``stop_when_stuck`` the run ends as soon as (checked every
    ``check_interval`` s of stick) the contact provably sticks forever under the load.
    """
    if not t_end > 0:
        raise ValueError(f"t_end must be positive, got {t_end} s")
    if method not in ("RK23", "RK45", "DOP853"):
        raise ValueError(f"method must be an explicit adaptive Runge-Kutta method, got {method!r}")
    dyn = _Dynamics(model, load)
    atol = np.concatenate([np.full(4, 1e-12), np.full(4, 1e-12), np.full(3, 1e-9)])
    y = np.zeros(11)
    y[4] = initial_velocity
    t = 0.0
    mode = dyn.select_mode(t, y)
    ts, ys, modes, events = [np.array([t])], [y[:, None]], [np.array([mode.value])], []
    stuck = False
    while t < t_end:
        if len(events) > max_events:
            raise RuntimeError(f"more than {max_events} stick/slip transitions before t = {t} s")
        t_stop = t_end
        if mode is Mode.STICK and stop_when_stuck:
            stuck, _ = dyn.stuck_forever(t, y)
            if stuck:
                break
            t_stop = min(t_end, t + check_interval)
        sol = solve_ivp(
            dyn.rhs(mode),
            (t, t_stop),
            y,
            method=method,
            rtol=rtol,
            atol=atol,
            events=dyn.events(mode),
        )
        if sol.status == -1:
            raise RuntimeError(f"integration failed at t = {t} s: {sol.message}")
        ts.append(sol.t[1:])
        ys.append(sol.y[:, 1:])
        modes.append(np.full(sol.t.size - 1, mode.value))
        t, y = float(sol.t[-1]), sol.y[:, -1].copy()
        if sol.status == 1:  # an event
            new, y = _after_event(dyn, sol, mode, t, y)
            events.append((t, mode, new))
            mode = new
    Y = np.concatenate(ys, axis=1)
    final = dyn.stuck_forever(t, y)[1] if mode is Mode.STICK else float(y[0])
    return Trajectory(
        t=np.concatenate(ts),
        q=Y[0:4],
        qdot=Y[4:8],
        mode=np.concatenate(modes),
        work=Y[8:11],
        events=events,
        stuck_forever=stuck,
        final_settlement=final,
    )


def _after_event(dyn: _Dynamics, sol, mode: Mode, t: float, y) -> tuple[Mode, npt.NDArray]:
    """Mode (and state) after the event that ended a segment: which event fired decides.

    Event 0 is always the gap. In stick, events 1/2 are the friction limits (slip
    down/up). In slip, event 1 is the slip rate reaching zero: then the joint sticks if
    the friction it needs is admissible, else it slips the other way.
    """
    fired = next(i for i, te in enumerate(sol.t_events) if te.size)
    if mode is Mode.OPEN:
        return dyn.select_mode(t, y), y
    if fired == 0:
        return Mode.OPEN, y
    if mode is Mode.STICK:
        return (Mode.SLIP_DOWN if fired == 1 else Mode.SLIP_UP), y
    y = dyn.project_stick(y)
    q, qd = dyn.split(y)
    N = dyn.normal_force(q)
    T = dyn.stick_friction(t, q, qd, N)
    if abs(T) <= dyn.mu_s * N:
        return Mode.STICK, y
    return (Mode.SLIP_DOWN if T > 0 else Mode.SLIP_UP), y
