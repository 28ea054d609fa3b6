"""The frequency-selectivity runs of the atlas (docs/physics.md §5.2, the two-stage form of the
reference sequence): from the joint settled by the case's self-weight stage, a lead-in at the
run's non-modal control frequency at the modal stages' amplitude (``vibration.amplitude_N``):
the joint takes the force there; then, from the state after it, the control continued and the
best-ranked mode (driven at its time-discrete natural frequency), each for the same time. The
selectivity ratio is the modal branch's settlement rate over its second half over the
control's (``solver.post.report.frequency_selectivity``'s sustained rate).

Kept as ``run.json`` in its folder (a later call with the same request reads it).
"""

import time
from pathlib import Path
from typing import Any

from mpi4py import MPI

from benchmarks.atlas.kept import frees_joints, keep_run, kept_run
from benchmarks.atlas.settled import SettledJoint, settle
from benchmarks.atlas.stepping import joint_state, run_schedule
from solver.dynamics.loads import Schedule, Stage
from solver.installation import checkpoint
from solver.installation.model import JointModel
from solver.installation.planning import compensate, stage_step
from solver.post import report

__all__ = [
    "selectivity_branches",
    "selectivity_ratio",
    "selectivity_runs",
    "sustained_rate",
    "whole_periods",
]


def sustained_rate(rows: list) -> float:
    """Settlement rate over the second half of a branch [mm/s], of its (time [s], settlement
    [mm], normal force [N]) rows."""
    t = [r[0] for r in rows]
    s = [r[1] for r in rows]
    return report.late_gain(t, s, 0.5) / (0.5 * (t[-1] - t[0]))


def selectivity_ratio(modal_rows: list, control_rows: list) -> float:
    """The modal branch's sustained rate over the control's (``report.rate_ratio``)."""
    return report.rate_ratio(sustained_rate(modal_rows), sustained_rate(control_rows))


def whole_periods(duration_s: float, frequency_hz: float) -> float:
    """The whole number of periods of ``frequency_hz`` [Hz] nearest to ``duration_s`` (at least
    one) [s]: a branch that ends at phase zero ends where the force is zero."""
    return max(1, round(duration_s * frequency_hz)) / frequency_hz


def _harmonic(
    model: JointModel, frequency_hz: float, duration_s: float, amplitude_N: float
) -> list:
    """``joint_state`` rows of ``duration_s`` [s] at ``frequency_hz`` [Hz] and ``amplitude_N``
    [N] from now, at the installation run's step for such a stage (``planning.stage_step``)."""
    dt = stage_step(duration_s, frequency_hz, model.case.time.steps_per_period)
    stage = Stage(duration_s, frequency_hz, amplitude_N)
    return run_schedule(model, Schedule([stage], start_s=model.problem.t), dt)


@frees_joints
def selectivity_runs(
    comm: MPI.Comm,
    case_name: str,
    overrides: list[str],
    folder: Path,
    lead_in_s: float,
    duration_s: float,
) -> dict[str, Any]:
    """Settle the case's joint, the lead-in of ``lead_in_s`` [s] at the control frequency, then
    the control and the best mode for ``duration_s`` [s] each (to whole periods of the control
    and of the mode's natural frequency). Returns (and keeps in ``folder``/run.json) the request,
    the settled state, per branch (lead-in, control, modal) its rows and frequencies [Hz], the
    natural frequencies [Hz] and the wall time [s] (collective)."""
    request = {
        "case": case_name,
        "overrides": overrides,
        "lead_in_s": lead_in_s,
        "duration_s": duration_s,
    }
    if (kept := kept_run(folder, request)) is not None:
        return kept
    wall = time.perf_counter()
    result = {
        "request": request,
        **selectivity_branches(settle(comm, overrides, case_name), folder, lead_in_s, duration_s),
    }
    result["wall_s"] = time.perf_counter() - wall
    keep_run(comm, folder, result)
    return result


def selectivity_branches(
    joint: SettledJoint, folder: Path, lead_in_s: float, duration_s: float
) -> dict[str, Any]:
    """From the settled ``joint``: the lead-in of ``lead_in_s`` [s] at the control frequency,
    then the control and the best mode for ``duration_s`` [s] each (to whole periods of the
    control and of the mode's natural frequency); the lead-in's state is kept in ``folder``.
    Returns the settled state, per branch (lead-in, control, modal) its rows and frequencies
    [Hz], the natural frequencies [Hz] and the amplitude [N] (collective)."""
    model = joint.model
    case, problem = model.case, model.problem
    t0, s0, n0 = joint_state(model)
    scheme, steps = case.vibration_scheme(), case.time.steps_per_period
    problem.set_scheme(scheme)
    best = min((e for e in joint.chosen if e.role == "modal"), key=lambda e: e.rank)
    control = next(e for e in joint.chosen if e.role == "control")
    f_c, amplitude = control.frequency_Hz, case.vibration.amplitude_N
    modal_s = whole_periods(duration_s, best.frequency_Hz)  # driven at f_m, a little off phase 0
    f_m = compensate([best], [modal_s], scheme, steps)[0].drive_Hz
    branches: dict[str, Any] = {
        "lead-in": {
            "rows": _harmonic(model, f_c, whole_periods(lead_in_s, f_c), amplitude),
            "frequency_Hz": f_c,
        }
    }
    led = folder / "lead_in"
    checkpoint.save(led, problem, {})
    branches["control"] = {
        "rows": _harmonic(model, f_c, whole_periods(duration_s, f_c), amplitude),
        "frequency_Hz": f_c,
    }
    checkpoint.restore(led, problem)
    branches["modal"] = {
        "rows": _harmonic(model, f_m, modal_s, amplitude),
        "frequency_Hz": best.frequency_Hz,
        "forcing_Hz": f_m,
        "m": best.m,
        "n": best.n,
    }
    return {
        "name": folder.name,
        "settled": {"time_s": t0, "settlement_mm": s0, "normal_N": n0},
        "natural_Hz": [float(f) for f in joint.frequencies_hz],
        "amplitude_N": amplitude,
        "branches": branches,
    }
