"""The sweep runs of the atlas (docs/physics.md §3 and §5.7): from the joint settled by the case's
self-weight stage,

* a step-wise frequency increase, ``STEPS_HZ`` (10 to 130 Hz in 10 Hz steps) at the
  eccentric-motor amplitude 0.3632 f^2 N, each step held ``dwell_s``, all at the step of
  ``steps_per_period`` steps per period of the highest frequency;
* linear frequency ramps across the best-ranked mode, from ``centre / (1 + span)`` to
  ``centre (1 + span)``, centre its time-discrete natural frequency at the ramps' step, at the
  modal stages' amplitude (``vibration.amplitude_N``): first a lead-in held at the ramps' start
  frequency for whole periods (the joint takes the force there, off resonance), then from that
  state a slow ramp of ``slow_s`` and a fast one ``speed_up`` times shorter, all at the step of
  ``steps_per_period`` steps per period of the highest frequency (a run whose duration is not a
  whole number of steps ends with a shorter step, at the cost of a new operator).

The unexcited joint, from the same settled state for as long as the step-wise sweep
(``unexcited_run``), is what the sweep's settlement is measured against: after its self-weight
stage the joint may still settle under the held force.

Kept as ``run.json`` in its folder (a later call with the same request reads it).
"""

import time
from pathlib import Path
from typing import Any

import numpy as np
from mpi4py import MPI

from benchmarks.atlas.kept import frees_joints, keep_run, kept_run
from benchmarks.atlas.settled import settle
from benchmarks.atlas.stepping import advance, joint_state, run_schedule
from common.case import read_case
from solver.dynamics.fidelity import discrete_frequency
from solver.dynamics.loads import Schedule, Stage, frequency_ramp, frequency_steps
from solver.dynamics.schemes import GeneralisedAlpha
from solver.installation import checkpoint
from solver.installation.case import InstallationCase
from solver.installation.model import set_up_joint_model

__all__ = [
    "STEPS_HZ",
    "nearest_mode",
    "ramp_band_gains",
    "settling_peaks",
    "step_gains",
    "sweep_runs",
    "unexcited_run",
]

STEPS_HZ = (10.0, 130.0, 10.0)  #: the step-wise sweep: first, last frequency, step [Hz]
LEAD_IN_PERIODS = 5  #: periods of the ramps' lead-in at their start frequency


def step_gains(rows: list, starts_s: list[float], dwell_s: float) -> list[float]:
    """Settlement gained in each step of a step-wise sweep [mm], of its (time [s], settlement
    [mm], normal force [N]) rows and the steps' start times [s] (interpolated at the bounds)."""
    t, s, _ = np.array(rows).T
    bounds = np.interp(np.r_[starts_s, starts_s[-1] + dwell_s], t, s)
    return np.diff(bounds).tolist()


def ramp_band_gains(rows: list, f_start: float, f_stop: float, bands: int) -> list[float]:
    """Settlement gained [mm] in each of ``bands`` equal parts of a linear frequency ramp from
    ``f_start`` to ``f_stop`` [Hz], of its (time [s], settlement [mm], normal force [N]) rows
    (the ramp's time span is that of the rows)."""
    t, s, _ = np.array(rows).T
    f = f_start + (f_stop - f_start) * (t - t[0]) / (t[-1] - t[0])
    return np.diff(np.interp(np.linspace(f_start, f_stop, bands + 1), f, s)).tolist()


def settling_peaks(gains: list[float]) -> list[int]:
    """The steps of a step-wise sweep that settle more than both their neighbours (so neither
    the first nor the last step), of the settlement gained per step."""
    g = gains
    return [k for k in range(1, len(g) - 1) if g[k] > 0 and g[k] > max(g[k - 1], g[k + 1])]


def nearest_mode(frequency_hz: float, natural_hz: list[float]) -> tuple[float, float]:
    """The natural frequency [Hz] nearest in ratio to ``frequency_hz`` (of the positive ones)
    and the relative distance frequency / natural - 1 [-]."""
    f_n = min((f for f in natural_hz if f > 0), key=lambda f: abs(np.log(frequency_hz / f)))
    return f_n, frequency_hz / f_n - 1.0


@frees_joints
def sweep_runs(
    comm: MPI.Comm,
    case_name: str,
    overrides: list[str],
    folder: Path,
    dwell_s: float,
    slow_s: float,
    speed_up: float,
    span: float,
) -> dict[str, Any]:
    """Settle the case's joint, then the step-wise sweep (steps of ``dwell_s`` [s]) and, from
    the settled state again, the lead-in and the slow (``slow_s`` [s]) and fast (``slow_s /
    speed_up``) ramps across the best-ranked mode, +- ``span`` (a fraction) about it. Returns
    (and keeps in ``folder``/run.json) the request, the settled state, the natural frequencies
    [Hz], the best mode (nominal and driven [Hz]), per run its (time [s], settlement [mm],
    normal force [N]) rows with its step [s] and frequencies, and the wall time [s]
    (collective)."""
    request = {
        "case": case_name,
        "overrides": overrides,
        "dwell_s": dwell_s,
        "slow_s": slow_s,
        "speed_up": speed_up,
        "span": span,
    }
    if (kept := kept_run(folder, request)) is not None:
        return kept
    wall = time.perf_counter()
    joint = settle(comm, overrides, case_name)
    model = joint.model
    case, problem = model.case, model.problem
    t0, s0, n0 = joint_state(model)
    settled = folder / "settled"
    checkpoint.save(settled, problem, {})
    scheme, steps = case.vibration_scheme(), case.time.steps_per_period
    problem.set_scheme(scheme)

    f_start, f_stop, f_step = STEPS_HZ
    stages = frequency_steps(f_start, f_stop, f_step, dwell_s, "eccentric")
    dt_steps = 1.0 / (steps * f_stop)
    schedule = Schedule(stages, start_s=t0)
    runs: dict[str, Any] = {
        "steps": {
            "rows": run_schedule(model, schedule, dt_steps),
            "dt_s": dt_steps,
            "frequencies_Hz": [s.frequency_hz for s in stages],
            "starts_s": schedule.stage_starts.tolist(),
        }
    }

    best = min((e for e in joint.chosen if e.role == "modal"), key=lambda e: e.rank)
    dt = 1.0 / (steps * (1.0 + span) ** 2 * best.frequency_Hz)  # >= steps per period at the top
    centre = best.frequency_Hz  # the time-discrete frequency of the mode, where there is one
    if isinstance(scheme, GeneralisedAlpha):
        centre = float(discrete_frequency(scheme, best.frequency_Hz, dt))
    low, high = centre / (1.0 + span), centre * (1.0 + span)
    amplitude = case.vibration.amplitude_N
    checkpoint.restore(settled, problem)
    lead = Schedule([Stage(LEAD_IN_PERIODS / low, low, amplitude)], start_s=t0)
    runs["lead-in"] = {"rows": run_schedule(model, lead, dt), "dt_s": dt, "frequency_Hz": low}
    led = folder / "lead_in"
    checkpoint.save(led, problem, {})
    for name, duration in (("slow", slow_s), ("fast", slow_s / speed_up)):
        checkpoint.restore(led, problem)
        ramp = Schedule(frequency_ramp(low, high, duration, amplitude), start_s=problem.t)
        runs[name] = {
            "rows": run_schedule(model, ramp, dt),
            "dt_s": dt,
            "duration_s": duration,
            "sweep_rate_Hz_s": (high - low) / duration,
        }
    result = {
        "request": request,
        "name": folder.name,
        "settled": {"time_s": t0, "settlement_mm": s0, "normal_N": n0},
        "natural_Hz": [float(f) for f in joint.frequencies_hz],
        "best": {"frequency_Hz": best.frequency_Hz, "centre_Hz": centre, "m": best.m, "n": best.n},
        "ramp_Hz": [low, high],
        "amplitude_N": amplitude,
        "runs": runs,
        "wall_s": time.perf_counter() - wall,
    }
    keep_run(comm, folder, result)
    return result


@frees_joints
def unexcited_run(
    comm: MPI.Comm, case_name: str, overrides: list[str], folder: Path, sweeps: dict[str, Any]
) -> dict[str, Any]:
    """The joint without excitation from the settled state of the sweep runs ``sweeps`` (kept in
    their folder) for as long as their step-wise sweep, under the held self-weight force, with
    the self-weight stage's step and the vibration scheme. Returns (and keeps in
    ``folder``/run.json) the request, its (time [s], settlement [mm], normal force [N]) rows and
    the wall time [s] (collective)."""
    steps = sweeps["runs"]["steps"]
    duration = steps["rows"][-1][0] - steps["rows"][0][0]
    request = {
        "case": case_name,
        "overrides": overrides,
        "settled": sweeps["settled"],
        "duration_s": duration,
    }
    if (kept := kept_run(folder, request)) is not None:
        return kept
    wall = time.perf_counter()
    case = InstallationCase.from_dict(read_case(case_name, overrides))
    model = set_up_joint_model(comm, case)
    problem = model.problem
    checkpoint.restore(folder.parent / sweeps["name"] / "settled", problem)
    problem.set_scheme(case.vibration_scheme())
    rows = [joint_state(model)]
    advance(model, problem.t + duration, case.self_weight.dt_s, rows)
    result = {
        "request": request,
        "name": folder.name,
        "rows": rows,
        "wall_s": time.perf_counter() - wall,
    }
    keep_run(comm, folder, result)
    return result
