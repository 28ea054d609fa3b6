"""A vibration stage of an installation run continued (the atlas's S2 probe, docs/physics.md
§5.2 "each event stabilises"): from the state the run kept after the stage (``[output]
stage_states``), the same excitation (the frequency, amplitude and step of the run's plan of
that stage) for another stage duration. Kept as ``run.json`` in its folder (a later call with
the same request reads it).
"""

import time
from dataclasses import asdict
from pathlib import Path
from typing import Any

from mpi4py import MPI

from benchmarks.atlas.installed import installed_state, restore_installed
from benchmarks.atlas.kept import keep_run, kept_run
from benchmarks.atlas.stepping import run_schedule
from solver.dynamics.loads import Schedule
from solver.installation.planning import StagePlan

__all__ = ["continued_stage"]


def continued_stage(
    comm: MPI.Comm,
    case_name: str,
    overrides: list[str],
    folder: Path,
    installed: Path,
    stage: int,
) -> dict[str, Any]:
    """Stage ``stage`` (>= 1) of the installation run in ``installed`` continued from the state
    the run kept after it. Returns (and keeps in ``folder``/run.json) the stage's plan, the
    (time [s], settlement [mm], contact normal force [N]) rows, the first one at the stage's
    end, and the wall time [s] (collective)."""
    request = {
        "case": case_name,
        "overrides": overrides,
        "installed": str(installed),
        "stage": stage,
    }
    if (kept := kept_run(folder, request)) is not None:
        return kept
    wall = time.perf_counter()
    model, _, _ = restore_installed(comm, case_name, overrides, installed, stage)
    case = model.case
    plan = StagePlan(**installed_state(comm, case, installed, stage)["plans"][stage])
    duration = plan.end_s - plan.start_s
    excitation = case.vibration.stage(duration, plan.frequency_Hz, plan.amplitude_N)
    model.problem.set_scheme(case.vibration_scheme())
    rows = run_schedule(model, Schedule([excitation], start_s=model.problem.t), plan.dt_s)
    result = {
        "request": request,
        "name": folder.name,
        "plan": asdict(plan),
        "rows": rows,
        "wall_s": time.perf_counter() - wall,
    }
    keep_run(comm, folder, result)
    return result
