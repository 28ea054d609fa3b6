"""The load-direction runs of the atlas (docs/physics.md §5.4): from the installed state (the
last checkpoint of an installation run of the case), the lowest anti-symmetric mode of the
run's modal stage driven at the modal stages' amplitude, once axially and once axially plus the
case's lateral fraction (``vibration.lateral_fraction``, 5 %) laterally, each for one stage
(``vibration.stage_duration_s``) from the same state.

Anti-symmetric: circumferential wave number m = 1, the modes that bend the joint as a beam and
that a lateral force excites. The mode is driven at its time-discrete natural frequency
(``solver.installation.planning.compensate``) with the step of such a stage. Kept as
``run.json`` in its folder (a later call with the same request, the installed state's time
included, reads it).
"""

import time
from dataclasses import asdict
from pathlib import Path
from typing import Any

from mpi4py import MPI

from benchmarks.atlas.installed import modal_table, restore_installed
from benchmarks.atlas.kept import frees_joints, keep_run, kept_run
from benchmarks.atlas.stepping import advance, joint_state
from common.case import read_case
from solver.dynamics.loads import Schedule, Stage
from solver.installation import checkpoint
from solver.installation.case import InstallationCase
from solver.installation.frequencies import MIN_FREQUENCY_HZ, Excitation
from solver.installation.model import attach_vibration
from solver.installation.planning import compensate, stage_step

__all__ = ["BRANCHES", "anti_symmetric_mode", "direction_runs"]

#: the branches: (direction, lateral angle from the case's ``vibration.angle_deg`` [deg]):
#: axial; axial plus the lateral fraction; the same with the lateral part reversed (a probe: the
#: lateral part's modal force adds to the axial part's or opposes it, by the mode's orientation)
BRANCHES = {"axial": ("axial", 0.0), "both": ("both", 0.0), "both reversed": ("both", 180.0)}


def anti_symmetric_mode(run_folder: Path, amplitude_N: float) -> Excitation | None:
    """The lowest m = 1 mode of at least ``MIN_FREQUENCY_HZ`` among the modes of the modal
    stage of the installation run in ``run_folder`` (its ``modes.csv``) as a modal excitation at
    ``amplitude_N`` [N]; None where the run had no modal stage or found no such mode."""
    rows = [
        r
        for r in modal_table(run_folder)
        if int(r["m"]) == 1 and float(r["frequency_Hz"]) >= MIN_FREQUENCY_HZ
    ]
    if not rows:
        return None
    r = min(rows, key=lambda r: float(r["frequency_Hz"]))
    return Excitation(
        float(r["frequency_Hz"]),
        amplitude_N,
        "modal",
        int(r["mode"]),
        1,
        int(r["n"]),
        int(r["rank"]),
        "lowest m = 1 (anti-symmetric) mode of the run's modal stage",
    )


@frees_joints
def direction_runs(
    comm: MPI.Comm,
    case_name: str,
    overrides: list[str],
    folder: Path,
    installed: Path,
    amplitude_N: float,
) -> dict[str, Any]:
    """From the installed state of ``installed`` (an installation run's output folder), its
    lowest m = 1 mode (``anti_symmetric_mode``) at ``amplitude_N`` [N] for one stage, in each of
    the ``BRANCHES``. Returns (and keeps in ``folder``/run.json) the state's time [s], the mode
    (None: not run) and per branch its (time [s], settlement [mm], normal force [N]) rows, the
    lateral fraction and the wall time [s] (collective). A kept run of the same request is
    returned with only the branches it lacks run."""
    request = {
        "case": case_name,
        "overrides": overrides,
        "installed": str(installed),
        "time_s": checkpoint.read_manifest(installed / "checkpoint", comm)["time_s"],
        "amplitude_N": amplitude_N,
    }
    branches: dict[str, list] = {}
    wall_kept = 0.0
    if (kept := kept_run(folder, request)) is not None:
        if kept["mode"] is None or set(kept["branches"]) == set(BRANCHES):
            return kept
        branches, wall_kept = kept["branches"], kept["wall_s"]
    wall = time.perf_counter()
    mode = anti_symmetric_mode(installed, amplitude_N)
    case = InstallationCase.from_dict(read_case(case_name, overrides))
    vibration = case.vibration
    if mode is not None:
        model, _, _ = restore_installed(comm, case_name, overrides, installed)
        problem = model.problem
        saved = folder / "installed"
        checkpoint.save(saved, problem, {})
        scheme, steps = case.vibration_scheme(), case.time.steps_per_period
        duration = vibration.stage_duration_s
        mode = compensate([mode], [duration], scheme, steps)[0]
        dt = stage_step(duration, mode.drive_Hz, steps)  # the step compensate drives it at
        for name, (direction, turn_deg) in BRANCHES.items():
            if name in branches:
                continue
            checkpoint.restore(saved, problem)
            problem.reset_operator()
            start = problem.t
            stage = Stage(
                duration,
                mode.drive_Hz,
                amplitude_N,
                direction=direction,
                lateral_fraction=vibration.lateral_fraction,
                lateral_angle_deg=vibration.angle_deg + turn_deg,
            )
            attach_vibration(model, Schedule([stage], start_s=start))
            problem.set_scheme(scheme)
            rows = [joint_state(model)]
            advance(model, start + duration, dt, rows)
            branches[name] = rows
    result = {
        "request": request,
        "name": folder.name,
        "mode": None if mode is None else asdict(mode),
        "lateral_fraction": vibration.lateral_fraction,
        "branches": branches,
        "wall_s": wall_kept + time.perf_counter() - wall,
    }
    keep_run(comm, folder, result)
    return result
