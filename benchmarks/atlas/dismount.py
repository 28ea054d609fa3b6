"""The dismount runs of the atlas (docs/physics.md §5.5): from the joint settled by the case's
self-weight stage (or from the last checkpoint of an installation run of the case, the
installed state), the axial force goes from the self-weight push to an upward pull over a
ramp and is held (the pull alone), then the same pull plus the vibration amplitude at the
best-ranked natural frequency and, from the same pulled state, at the non-modal control
frequency, each for at most a given time. The amplitude is a given force or the eccentric
motors' force at the best mode, 0.3632 f^2 N (docs/physics.md §3), at both frequencies.

The frequencies are the installation run's choice (``benchmarks.atlas.settled.settle``, or the
installation run's own), a modal stage driven at the time-discrete natural frequency of its mode
(``solver.installation.planning.compensate``). A branch ends released (:func:`released`) when
the TP is above its first-contact position (settlement < 0) and has separated (the contact
normal force below ``SEPARATION_FRACTION`` of the settled one) or lifts faster than the case's
event threshold ``output.slip_rate_mm_s`` (a shaken TP still strikes the MP there). Kept as
``run.json`` in its folder (a later call with the same request reads it).
"""

import time
from pathlib import Path
from typing import Any

import numpy as np
from mpi4py import MPI

from benchmarks.atlas.installed import restore_installed
from benchmarks.atlas.kept import frees_joints, keep_run, kept_run
from benchmarks.atlas.settled import settle
from benchmarks.atlas.stepping import advance, joint_state
from solver.dynamics.loads import Schedule, Stage, eccentric_amplitude
from solver.installation import checkpoint
from solver.installation.dismount import SEPARATION_FRACTION, pull_out_force
from solver.installation.frequencies import Excitation
from solver.installation.model import JointModel, attach_vibration
from solver.installation.planning import compensate, stage_step
from solver.installation.settings import StaticForceSettings

__all__ = ["dismount_branches", "dismount_runs", "lift_rate", "released", "separated"]

CHUNKS = 10  #: a vibration branch stops at the first of these chunks of steps that ends released


def lift_rate(rows: list) -> float:
    """The TP's upward speed [mm/s] over the second half of a branch's rows (time [s],
    settlement [mm], contact normal force [N]); 0 where the second half has no length."""
    t, s, _ = np.array(rows).T
    half = np.searchsorted(t, 0.5 * (t[0] + t[-1]))
    if t[-1] <= t[half]:
        return 0.0
    return float((s[half] - s[-1]) / (t[-1] - t[half]))


def separated(rows: list, settled_normal_N: float) -> bool:
    """Whether a branch's rows end with the TP above its first-contact position and a contact
    normal force below ``SEPARATION_FRACTION`` of ``settled_normal_N`` [N]."""
    return rows[-1][1] < 0.0 and rows[-1][2] < SEPARATION_FRACTION * settled_normal_N


def released(rows: list, settled_normal_N: float, slip_rate_mm_s: float) -> bool:
    """Whether a branch's rows end with the TP released: above its first-contact position and
    separated, or lifting faster than ``slip_rate_mm_s`` [mm/s] over the second half."""
    return separated(rows, settled_normal_N) or (
        rows[-1][1] < 0.0 and lift_rate(rows) > slip_rate_mm_s
    )


@frees_joints
def dismount_runs(
    comm: MPI.Comm,
    case_name: str,
    overrides: list[str],
    folder: Path,
    pull_factors: tuple[float, ...],
    amplitude_N: float | None,
    duration_s: float,
    installed: Path | None = None,
) -> dict[str, Any]:
    """Settle the case's joint (or restore the state ``installed``: the output folder of an
    installation run of the case, its last checkpoint), then :func:`dismount_branches`; the
    result, with its request and wall time [s], is kept in ``folder``/run.json (collective)."""
    request = {
        "case": case_name,
        "overrides": overrides,
        "pull_factors": list(pull_factors),
        "amplitude_N": amplitude_N,
        "duration_s": duration_s,
    }
    if installed is not None:
        request["installed"] = str(installed)
    if (kept := kept_run(folder, request)) is not None:
        return kept
    wall = time.perf_counter()
    if installed is None:
        joint = settle(comm, overrides, case_name)
        model, chosen, natural_Hz = joint.model, joint.chosen, list(joint.frequencies_hz)
    else:
        model, chosen, natural_Hz = restore_installed(comm, case_name, overrides, installed)
    result = {
        "request": request,
        **dismount_branches(
            model, chosen, natural_Hz, folder, pull_factors, amplitude_N, duration_s
        ),
        "wall_s": time.perf_counter() - wall,
    }
    keep_run(comm, folder, result)
    return result


def dismount_branches(
    model: JointModel,
    chosen: list[Excitation],
    natural_Hz: list[float],
    folder: Path,
    pull_factors: tuple[float, ...],
    amplitude_N: float | None,
    duration_s: float,
    vibrated: tuple[str, ...] = ("modal", "control"),
) -> dict[str, Any]:
    """From the joint's present state (held at the self-weight force), with ``chosen`` the
    frequency choice of its modes (``natural_Hz`` [Hz]): the pulls ``pull_factors`` x the
    self-weight force alone (ramped over ``duration_s`` [s] and held as long), and the first
    pull plus ``amplitude_N`` [N] (None: the motors' force at the best mode) at the best mode
    and at the control frequency (``vibrated``: those of the two to run; at most
    ``duration_s`` each), only where the first pull alone holds. Returns per branch its
    (time [s], settlement [mm], normal force [N]) rows and whether it ended released
    (:func:`released`), the settled state and the rigid Coulomb pull-out forces [N]; the states
    it branches from are saved in ``folder`` (collective)."""
    case = model.case
    sw, problem = case.self_weight, model.problem
    t0, s0, n0 = joint_state(model)
    saved = folder / "settled"
    checkpoint.save(saved, problem, {})
    modal = min((e for e in chosen if e.role == "modal"), key=lambda e: e.rank)
    control = next(e for e in chosen if e.role == "control")
    scheme, steps = case.vibration_scheme(), case.time.steps_per_period
    drives = compensate([modal, control], [duration_s] * 2, scheme, steps)
    force_N = (
        amplitude_N if amplitude_N is not None else float(eccentric_amplitude(modal.frequency_Hz))
    )

    slip_rate = case.output.slip_rate_mm_s

    # times from the end of the self-weight stage: its force is held to t0, then ramped to the pull
    since = t0 - sw.duration_s
    held = [(since, sw.force_N)] if since > 0.5 * sw.dt_s else []

    def pull_alone(factor: float) -> list:
        problem.load.shaker = None
        times, forces = zip(*held, (max(since, 0.0) + duration_s, factor * abs(sw.force_N)))
        problem.load.static_axial = StaticForceSettings(times, forces).history(sw)
        checkpoint.restore(saved, problem)
        problem.reset_operator()
        rows = [joint_state(model)]
        advance(model, t0 + 2 * duration_s, sw.dt_s, rows)
        return rows

    branches: dict[str, dict[str, Any]] = {}
    pulled = folder / "pulled"
    for factor in pull_factors:
        rows = pull_alone(factor)
        branches[f"pull {factor:g} x"] = {"rows": rows, "released": released(rows, n0, slip_rate)}
        if factor == pull_factors[0]:
            checkpoint.save(pulled, problem, {})
    if not branches[f"pull {pull_factors[0]:g} x"]["released"]:
        for name, e in (("modal", drives[0]), ("control", drives[1])):
            if name not in vibrated:
                continue
            checkpoint.restore(pulled, problem)
            problem.reset_operator()
            start = problem.t
            attach_vibration(
                model, Schedule([Stage(duration_s, e.forcing_Hz, force_N)], start_s=start)
            )
            problem.set_scheme(scheme)
            # the step compensate() drove the mode for; chunks of whole steps (a partial step
            # would be another step size, with its own operator and contact set-up)
            dt = stage_step(duration_s, e.forcing_Hz, steps)
            n_steps = round(duration_s / dt)
            ends = sorted({round(k * n_steps / CHUNKS) for k in range(1, CHUNKS + 1)} - {0})
            branch = [joint_state(model)]
            for end in ends:
                advance(model, start + end * dt, dt, branch)
                if released(branch, n0, slip_rate):
                    break
            branches[name] = {
                "rows": branch,
                "released": released(branch, n0, slip_rate),
                "frequency_Hz": e.frequency_Hz,
                "forcing_Hz": e.forcing_Hz,
                "amplitude_N": force_N,
            }
            problem.set_scheme(case.self_weight_scheme())
    alpha, friction = case.joint.mp.half_angle, case.friction
    return {
        "name": folder.name,
        "settled": {"time_s": t0, "settlement_mm": s0, "normal_N": n0},
        "self_weight_N": abs(sw.force_N),
        "pull_out_N": {
            "mu_d": pull_out_force(n0, friction.mu_d, alpha),
            "mu_s": pull_out_force(n0, friction.mu_s, alpha),
        },
        "natural_Hz": [float(f) for f in np.asarray(natural_Hz)],
        "branches": branches,
    }
