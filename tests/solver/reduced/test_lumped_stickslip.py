"""The stick/slip integrator of the reduced model against closed forms and energy balance.

Full-scale springs (cases/full_scale.toml). No DOLFINx: runs serially only.
"""

import math

import numpy as np
import pytest
from scipy.linalg import expm
from scipy.optimize import brentq

from geometry.parameters import load_geometry
from solver.contact import FrictionLaw
from solver.reduced.lumped import GRAVITY, AxialLoad, LumpedModel, Mode, simulate
from solver.reduced.shell import joint_stiffness


@pytest.fixture(scope="module")
def full_scale():
    joint, material, _ = load_geometry("cases/full_scale.toml")
    return joint, joint_stiffness(joint, material, tol=1e-6), joint.tp.mass(material)


def make_model(full_scale, friction: FrictionLaw, damping_ratio: float = 0.01) -> LumpedModel:
    joint, springs, mass = full_scale
    return LumpedModel(
        mass, springs, joint.mp.half_angle, 0.5 * joint.tp.thickness, friction, damping_ratio
    )


def test_constant_load_settles_at_the_closed_form_static_slip_position(full_scale):
    """mu_s = mu_d, damping that makes the slip motion overdamped: the TP creeps into the
    static slip equilibrium v* = N (1/K_N + cos a (cos a - mu sin a) / K_r) / sin a,
    N = F / (sin a + mu cos a)."""
    model = make_model(full_scale, FrictionLaw(0.3, 0.3, math.inf), damping_ratio=0.05)
    F = model.mass * GRAVITY
    traj = simulate(model, AxialLoad(static=F), 4.0, rtol=1e-10, stop_when_stuck=False)
    expected = model.static_slip_settlement(F, 0.3)
    assert traj.settlement[-1] == pytest.approx(expected, rel=1e-6)


@pytest.mark.parametrize("d_c", [math.inf, 100.0])
def test_energy_dissipated_per_slip_event_equals_friction_work(full_scale, d_c):
    """A strong harmonic load (1.5 x self-weight at 10 Hz) with mu_s = 0.5, mu_d = 0.3
    gives repeated stick/slip (Coulomb step, and docs/physics.md §4's mu(v) with d_c = 100 s/m);
    over every slip phase,
    external work - damping - change of mechanical energy = int T xi' dt (1e-6 relative);
    over stick phases the friction does no work."""
    model = make_model(full_scale, FrictionLaw(0.5, 0.3, d_c))
    load = AxialLoad(
        static=model.mass * GRAVITY, amplitude=1.5 * model.mass * GRAVITY, frequency=10.0
    )
    traj = simulate(model, load, 0.6, rtol=1e-11, stop_when_stuck=False)
    energy = traj.mechanical_energy(model)
    w_ext, w_damp, w_fric = traj.work
    intervals = traj.slip_intervals()
    assert len(intervals) >= 3  # the load produces several stick/slip cycles
    for i, j in intervals:
        dissipated = (w_ext[j] - w_ext[i]) - (w_damp[j] - w_damp[i]) - (energy[j] - energy[i])
        friction = w_fric[j] - w_fric[i]
        assert friction > 0
        assert dissipated == pytest.approx(friction, rel=1e-6)
    stick = traj.mode == Mode.STICK.value
    assert np.abs(np.diff(w_fric)[stick[1:]]).max() < 1e-9 * w_fric[-1]


def _slip_matrix(model: LumpedModel, mu: float):
    """First-order system x' = A x + B F of the closed contact slipping down at mu."""
    m, c = model.masses, model.damping
    k_slip = np.diag(model.stiffness) + model.springs.K_N * np.outer(
        model.a + mu * model.b, model.a
    )
    A = np.block([[np.zeros((4, 4)), np.eye(4)], [-k_slip / m[:, None], -np.diag(c / m)]])
    B = np.concatenate([np.zeros(4), [1.0 / m[0]], np.zeros(3)])
    return A, B


@pytest.mark.parametrize("rtol", [1e-6, 1e-9])
def test_slip_to_stick_transition_located_to_integrator_tolerance(full_scale, rtol):
    """Constant load at first contact: the first slip phase is linear, so its end (slip
    rate xi' = 0) follows from the matrix exponential; the event time agrees to the
    integrator's tolerance."""
    model = make_model(full_scale, FrictionLaw(0.5, 0.3, math.inf))
    F = model.mass * GRAVITY
    traj = simulate(model, AxialLoad(static=F), 0.6, rtol=rtol)
    t_event, before, after = traj.events[0]
    assert (before, after) == (Mode.SLIP_DOWN, Mode.STICK)

    A, B = _slip_matrix(model, 0.3)
    particular = -np.linalg.solve(A, B * F)  # constant-load equilibrium of the slip system

    def state(t):
        return particular + expm(A * t) @ (-particular)

    def slip_rate(t):
        return model.b @ state(t)[4:8]

    # bracket the first zero of the slip rate by marching with a fixed step, then refine
    dt, x, t = 1e-4, state(0.0), 0.0
    step = expm(A * dt)
    while model.b @ x[4:8] >= 0 or t == 0.0:
        x, t = particular + step @ (x - particular), t + dt
        assert t < 0.5, "no end of slip found"
    t_exact = brentq(slip_rate, t - dt, t, xtol=1e-14)
    assert t_event == pytest.approx(t_exact, rel=20 * rtol)
    i = int(np.searchsorted(traj.t, t_event))
    assert traj.settlement[i] == pytest.approx(state(t_exact)[0], rel=20 * rtol)


def test_stick_to_slip_transition_sits_on_the_friction_limit(full_scale):
    """At every stick -> slip event the friction force demanded by stick equals mu_s N."""
    model = make_model(full_scale, FrictionLaw(0.5, 0.3, math.inf))
    load = AxialLoad(
        static=model.mass * GRAVITY, amplitude=1.5 * model.mass * GRAVITY, frequency=10.0
    )
    traj = simulate(model, load, 0.6, rtol=1e-10, stop_when_stuck=False)
    onsets = [
        t for t, before, after in traj.events if before is Mode.STICK and after is not Mode.OPEN
    ]
    assert len(onsets) >= 2
    m, c, k = model.masses, model.damping, model.stiffness
    for t in onsets:
        i = int(np.searchsorted(traj.t, t))
        q, qd = traj.q[:, i], traj.qdot[:, i]
        N = model.springs.K_N * float(model.a @ q)
        f = -c * qd - k * q - N * model.a
        f[0] += load(t)
        T = float((model.b / m) @ f) / float(model.b @ (model.b / m))
        assert abs(T) == pytest.approx(model.friction.mu_s * N, rel=1e-8)


def test_drop_and_self_weight_stop_short_of_full_contact(full_scale):
    """docs/physics.md §7: self-weight and a 10 cm drop (1.4 m/s) settle well short of L_slip, and
    the drop settles further than the gentle placement."""
    joint, _, _ = full_scale
    model = make_model(full_scale, FrictionLaw(0.5, 0.3, math.inf))
    load = AxialLoad(static=model.mass * GRAVITY)
    placed = simulate(model, load, 5.0)
    dropped = simulate(model, load, 5.0, initial_velocity=math.sqrt(2 * GRAVITY * 0.1))
    assert placed.stuck_forever and dropped.stuck_forever
    assert 0 < placed.final_settlement < dropped.final_settlement < joint.required_slip


def test_bad_input_raises(full_scale):
    model = make_model(full_scale, FrictionLaw(0.5, 0.3, math.inf))
    with pytest.raises(ValueError, match="t_end"):
        simulate(model, AxialLoad(static=1.0), -1.0)
    with pytest.raises(ValueError, match="Runge-Kutta"):
        simulate(model, AxialLoad(static=1.0), 1.0, method="BDF")
    with pytest.raises(ValueError, match="frequency"):
        AxialLoad(static=1.0, frequency=-2.0)
    with pytest.raises(ValueError, match="mass"):
        LumpedModel(0.0, model.springs, model.alpha, model.lever)


def test_early_stop_only_when_the_joint_really_sticks_for_good(full_scale):
    """A run stopped by the stick certificate ends where the full run's last transition
    lies behind it, with the same final settlement."""
    model = make_model(full_scale, FrictionLaw(0.5, 0.3, math.inf))
    load = AxialLoad(
        static=model.mass * GRAVITY,
        amplitude=1.5 * model.mass * GRAVITY,
        frequency=10.0,
        harmonic_start=0.3,
    )
    stopped = simulate(model, load, 2.5, rtol=1e-9)
    full = simulate(model, load, 2.5, rtol=1e-9, stop_when_stuck=False)
    assert stopped.stuck_forever and stopped.t[-1] < 1.8
    assert len(full.events) > 5
    assert full.events[-1][0] <= stopped.t[-1]
    assert full.events[-1][2] is Mode.STICK
    assert stopped.final_settlement == pytest.approx(full.final_settlement, rel=1e-6)
