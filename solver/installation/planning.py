"""The vibration stages as time-stepping plans, faithful to resonance.

A stage of frequency f is stepped with ``steps_per_period`` steps per period (dt fitted so
that the stage holds whole periods). The time scheme's algorithmic damping and period error
at that step (``solver.dynamics.fidelity``) are part of each plan, beside the physical
damping ratio at f:

* a scheme whose algorithmic damping exceeds ``ALGORITHMIC_SHARE`` of the physical damping
  ratio is refused (:func:`check_time_scheme` before anything is computed, and
  :func:`plan_vibration` per stage): it would damp a resonance numerically, not physically;
* a stage at a natural frequency f_n is driven at the time-discrete model's natural
  frequency of that mode (:func:`compensate`): the discrete model resonates there, below f_n
  by the scheme's period error, which would otherwise put the stage
  (period error) / (2 zeta) half-power bandwidths off resonance. The plan keeps f_n beside it.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace

import numpy as np

from solver.dynamics.fidelity import accuracy, discrete_frequency
from solver.dynamics.loads import Schedule
from solver.dynamics.schemes import GeneralisedAlpha, Scheme, scheme_from_name
from solver.installation.frequencies import Excitation
from solver.installation.settings import DampingSettings, TimeSettings

ALGORITHMIC_SHARE = (
    0.1  #: largest algorithmic damping of a vibration stage / physical damping ratio [-]
)
#: algorithmic damping ratios [-] up to this are round-off of the closed form (a conservative
#: scheme, Newmark or rho_inf = 1, gives about 1e-15), not damping
ROUND_OFF = 1e-12


def damps_resonance(algorithmic: float, physical: float) -> bool:
    """Whether an algorithmic damping ratio exceeds ``ALGORITHMIC_SHARE`` of the physical one."""
    return algorithmic > ALGORITHMIC_SHARE * physical + ROUND_OFF


@dataclass
class StagePlan:
    """A stage of the time loop: name, interval [s], nominal step [s], forcing frequency [Hz]
    and amplitude [N]; for vibration stages also the natural frequency the forcing frequency
    stands for (0: none), the steps per period, and the scheme's algorithmic damping ratio and
    period error there beside the physical damping ratio [-]."""

    name: str
    start_s: float
    end_s: float
    dt_s: float
    frequency_Hz: float
    amplitude_N: float
    reason: str = ""
    natural_frequency_Hz: float = 0.0
    steps_per_period: float = 0.0
    algorithmic_damping: float = 0.0
    period_error: float = 0.0
    physical_damping: float = 0.0


def _smallest_passing(values: Sequence, passes: Callable) -> float | None:
    return next((v for v in values if passes(v)), None)


def check_time_scheme(time: TimeSettings, damping: DampingSettings) -> None:
    """ValueError unless the vibration stages' scheme ([time]) keeps resonance: dynamic, and its
    algorithmic damping at ``steps_per_period`` within ``ALGORITHMIC_SHARE`` of the smallest
    physical damping ratio of the stages ([damping] zeta: the minimum of the Rayleigh curve, or
    the modal ratio)."""
    scheme = scheme_from_name(time.scheme, time.rho_inf)
    if not scheme.dynamic:
        raise ValueError(
            "[time] scheme = 'quasi-static' has no inertia: the vibration stages need "
            "'newmark' or 'generalised-alpha'"
        )
    xi = accuracy(scheme, time.steps_per_period).damping_ratio
    if not damps_resonance(xi, damping.zeta):
        return

    def damping_at(rho: float, n: int) -> float:
        return accuracy(GeneralisedAlpha.from_spectral_radius(rho), n).damping_ratio

    rho = _smallest_passing(
        np.round(np.arange(0.0, 1.0001, 0.05), 2),
        lambda r: not damps_resonance(damping_at(r, time.steps_per_period), damping.zeta),
    )
    steps = _smallest_passing(
        range(time.steps_per_period, 257),
        lambda n: not damps_resonance(damping_at(time.rho_inf, n), damping.zeta),
    )
    remedies = [f"rho_inf >= {rho:g} at this step"] if rho is not None else []
    if steps is not None:
        remedies.append(f"steps_per_period >= {steps} at this rho_inf")
    raise ValueError(
        f"[time] {time.scheme} (rho_inf = {time.rho_inf:g}) at {time.steps_per_period} steps per period "
        f"damps a resonance numerically by {100 * xi:.3g} % of critical, more than "
        f"{100 * ALGORITHMIC_SHARE:g} % of the smallest physical damping ratio of the vibration stages "
        f"([damping] zeta = {100 * damping.zeta:g} %): the time scheme, not the structure, would limit "
        f"the resonant response. Use {' or '.join(remedies)} (docs/dynamics.md)"
    )


def stage_step(duration_s: float, frequency_hz: float, steps_per_period: int) -> float:
    """Time step [s] of a stage: ``steps_per_period`` steps per period of ``frequency_hz`` (its
    largest frequency), shortened so that the stage holds a whole number of periods."""
    periods = max(1, math.ceil(duration_s * frequency_hz - 1e-9)) if frequency_hz > 0 else 1
    return duration_s / (periods * steps_per_period)


def compensate(
    excitations: Sequence[Excitation],
    durations_s: Sequence[float],
    scheme: Scheme,
    steps_per_period: int,
) -> list[Excitation]:
    """The excitations with ``forcing_Hz`` set: for a stage at a natural frequency f_n (a mode
    number), the time-discrete natural frequency of that mode at the stage's step (the stage's
    step depends on its forcing frequency: fixed point, a few iterations); f elsewhere."""
    out = []
    for e, duration in zip(excitations, durations_s):
        forcing = e.frequency_Hz
        if e.mode > 0 and isinstance(scheme, GeneralisedAlpha):
            for _ in range(8):
                dt = stage_step(duration, forcing, steps_per_period)
                new = discrete_frequency(scheme, e.frequency_Hz, dt)
                converged = abs(new - forcing) <= 1e-12 * forcing
                forcing = new
                if converged:
                    break
        out.append(replace(e, forcing_Hz=float(forcing)))
    return out


def plan_vibration(
    schedule: Schedule,
    scheme: Scheme,
    steps_per_period: int,
    damping_ratio: Callable[[float], float],
    excitations: Sequence[Excitation],
) -> list[StagePlan]:
    """One plan per stage of ``schedule`` (stage k at ``excitations[k]``, if given), with the
    scheme's accuracy at the stage's largest frequency; ValueError if the algorithmic damping
    there exceeds ``ALGORITHMIC_SHARE`` of ``damping_ratio(f)`` (the physical ratio at f [Hz])."""
    plans = []
    for i, (stage, start) in enumerate(zip(schedule.stages, schedule.stage_starts)):
        f_max = max(stage.frequency(0.0), stage.frequency(stage.duration_s))
        dt = stage_step(stage.duration_s, f_max, steps_per_period)
        e = excitations[i] if i < len(excitations) else None
        plan = StagePlan(
            f"vibration {i + 1}",
            float(start),
            float(start + stage.duration_s),
            dt,
            stage.frequency(0.0),
            stage.amplitude(0.0),
            e.reason if e else "",
        )
        if f_max > 0:
            fidelity = accuracy(scheme, 1.0 / (f_max * dt))
            plan.steps_per_period = fidelity.steps_per_period
            plan.algorithmic_damping = fidelity.damping_ratio
            plan.period_error = fidelity.period_error
            plan.physical_damping = float(damping_ratio(f_max))
            plan.natural_frequency_Hz = e.frequency_Hz if e is not None and e.mode > 0 else 0.0
            if damps_resonance(plan.algorithmic_damping, plan.physical_damping):
                raise ValueError(
                    f"{plan.name} at {f_max:.2f} Hz: the time scheme damps it numerically by "
                    f"{100 * plan.algorithmic_damping:.3g} % of critical, more than "
                    f"{100 * ALGORITHMIC_SHARE:g} % of the physical damping ratio there "
                    f"({100 * plan.physical_damping:.3g} %); raise [time] rho_inf or steps_per_period"
                    " (or, with modal damping, damping.n_modes)"
                )
        plans.append(plan)
    return plans


def format_fidelity(plan: StagePlan) -> str:
    """One line: forcing and natural frequency, step, algorithmic damping and period error
    (a conservative scheme's round-off damping, possibly -0.0, printed as 0: max returns its
    first argument on a tie)."""
    natural = (
        f" = time-discrete natural frequency of the {plan.natural_frequency_Hz:.2f} Hz mode"
        if plan.natural_frequency_Hz
        else " (not at a natural frequency)"
    )
    return (
        f"{plan.name}: {plan.frequency_Hz:.2f} Hz{natural}; dt {1e6 * plan.dt_s:.1f} us "
        f"({plan.steps_per_period:.1f} steps per period), algorithmic damping "
        f"{100 * max(0.0, plan.algorithmic_damping):.4f} % (physical {100 * plan.physical_damping:.3g} %), "
        f"period error {100 * plan.period_error:+.3f} %"
    )
