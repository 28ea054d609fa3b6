"""The vibration stages' plans keep resonance: the scheme check, the compensated forcing
frequency and the per-stage figures (solver.installation.planning).

Independent references: the closed-form accuracy of the schemes (``solver.dynamics.fidelity``,
itself checked against time stepping in test_dynamics_newmark.py) and the case files.
"""

import pytest

from common.case import read_case
from solver.dynamics.fidelity import accuracy, discrete_frequency
from solver.dynamics.loads import Schedule, Stage
from solver.dynamics.schemes import GeneralisedAlpha
from solver.installation.case import InstallationCase
from solver.installation.frequencies import Excitation
from solver.installation.planning import (
    ALGORITHMIC_SHARE,
    check_time_scheme,
    compensate,
    format_fidelity,
    plan_vibration,
    stage_step,
)
from solver.installation.settings import DampingSettings, TimeSettings

ZETA = DampingSettings()  # 1 % at 120 Hz


def test_scheme_check_refuses_numerical_damping_of_resonance():
    # generalised-alpha rho_inf = 0 at 16 steps per period: 2.0 % of critical, twice the physical 1 %
    with pytest.raises(
        ValueError, match=r"2 % of critical.*rho_inf >= 0\.\d+.*steps_per_period >= \d+"
    ):
        check_time_scheme(TimeSettings(rho_inf=0.0, steps_per_period=16), ZETA)
    with pytest.raises(ValueError, match="no inertia"):
        check_time_scheme(TimeSettings(scheme="quasi-static"), ZETA)
    check_time_scheme(TimeSettings(rho_inf=0.7, steps_per_period=16), ZETA)
    check_time_scheme(TimeSettings(scheme="newmark", steps_per_period=4), ZETA)


def test_undamped_structure_admits_only_conservative_schemes():
    """zeta = 0: Newmark and rho_inf = 1 pass (their algorithmic damping is round-off), any
    rho_inf < 1 is refused at every step, with rho_inf = 1 as the only remedy named."""
    undamped = DampingSettings(zeta=0.0)
    check_time_scheme(TimeSettings(scheme="newmark", steps_per_period=4), undamped)
    check_time_scheme(TimeSettings(rho_inf=1.0, steps_per_period=4), undamped)
    with pytest.raises(ValueError, match=r"zeta = 0 %.*Use rho_inf >= 1 at this step \(") as err:
        check_time_scheme(TimeSettings(rho_inf=0.7, steps_per_period=16), undamped)
    assert "steps_per_period >=" not in str(err.value)


def test_suggested_settings_pass_and_are_the_smallest():
    with pytest.raises(ValueError) as err:
        check_time_scheme(TimeSettings(rho_inf=0.0, steps_per_period=16), ZETA)
    text = str(err.value)
    rho = float(text.split("rho_inf >= ")[1].split()[0])
    steps = int(text.split("steps_per_period >= ")[1].split()[0])
    limit = ALGORITHMIC_SHARE * ZETA.zeta
    assert accuracy(GeneralisedAlpha.from_spectral_radius(rho), 16).damping_ratio <= limit
    assert accuracy(GeneralisedAlpha.from_spectral_radius(rho - 0.05), 16).damping_ratio > limit
    assert accuracy(GeneralisedAlpha.from_spectral_radius(0.0), steps).damping_ratio <= limit
    assert accuracy(GeneralisedAlpha.from_spectral_radius(0.0), steps - 1).damping_ratio > limit


def test_case_with_a_damping_scheme_is_refused_before_any_computation():
    data = read_case("scaled", ["time.rho_inf=0.0"])
    with pytest.raises(ValueError, match=r"\[time\] generalised-alpha \(rho_inf = 0\)"):
        InstallationCase.from_dict(data)


def excitation(frequency_Hz: float, mode: int) -> Excitation:
    return Excitation(frequency_Hz, 3600.0, "modal" if mode else "control", mode, 2, 1, 1, "test")


def test_modal_stage_is_driven_at_the_discrete_natural_frequency():
    scheme = GeneralisedAlpha.from_spectral_radius(0.7)
    duration, steps = 0.1, 16
    modal, control = compensate(
        [excitation(327.3, 7), excitation(76.0, 0)], [duration, duration], scheme, steps
    )
    assert control.drive_Hz == 76.0
    f_c = modal.forcing_Hz
    dt = stage_step(duration, f_c, steps)
    # a fixed point: at the step of the forcing frequency, the mode's discrete frequency is f_c
    assert discrete_frequency(scheme, 327.3, dt) == pytest.approx(f_c, rel=1e-10)
    # below f_n by the period error there (the discrete oscillator's period is longer)
    assert f_c == pytest.approx(
        327.3 / (1 + accuracy(scheme, 1 / (327.3 * dt)).period_error), rel=1e-9
    )
    assert f_c < 327.3


def test_stage_plans_carry_the_accuracy_at_their_frequency():
    scheme = GeneralisedAlpha.from_spectral_radius(0.7)
    stages = [Stage(0.1, 68.0, 1000.0), Stage(0.05, 322.0, 3600.0)]
    plans = plan_vibration(
        Schedule(stages, start_s=2.1),
        scheme,
        16,
        lambda f: 0.01,
        [excitation(68.0, 0), excitation(327.3, 7)],
    )
    for plan, stage in zip(plans, stages):
        dt = stage_step(stage.duration_s, stage.frequency_hz, 16)
        assert plan.dt_s == pytest.approx(dt)
        expected = accuracy(scheme, 1 / (stage.frequency_hz * dt))
        assert plan.algorithmic_damping == pytest.approx(expected.damping_ratio)
        assert plan.period_error == pytest.approx(expected.period_error)
        assert plan.physical_damping == 0.01
    assert plans[1].start_s == pytest.approx(2.2) and plans[1].natural_frequency_Hz == 327.3
    line = format_fidelity(plans[1])
    assert "322.00 Hz = time-discrete natural frequency of the 327.30 Hz mode" in line
    assert "algorithmic damping" in line and "period error" in line and " us " in line
    assert "not at a natural frequency" in format_fidelity(plans[0])


def test_stage_plan_refuses_where_physical_damping_is_small():
    # Rayleigh damping is smallest at its minimum; a frequency-dependent ratio of 0.01 % is too
    # small for rho_inf = 0.7 at 16 steps per period (0.016 % of critical)
    scheme = GeneralisedAlpha.from_spectral_radius(0.7)
    with pytest.raises(ValueError, match=r"vibration 1 at 100\.00 Hz.*numerically"):
        plan_vibration(Schedule([Stage(0.1, 100.0, 3600.0)]), scheme, 16, lambda f: 1e-4, [])
