"""A vibration stage of an installation run continued (the atlas's S2 probe, docs/physics.md
§5.2 "each event comes to rest"): from the state the run kept after the stage (``[output]
stage_states``), the same excitation for another stage duration, at the step of the run's plan
of that stage. The forcing is the run's automatic schedule (``[vibration]``) with the stage
repeated, so its phase runs on from where the stage left it. Kept as ``run.json`` in its folder
(a later call with the same request reads it).
"""

import time
from dataclasses import asdict
from pathlib import Path
from typing import Any

from mpi4py import MPI

from benchmarks.atlas.installed import installed_state, restore_installed
from benchmarks.atlas.kept import frees_joints, keep_run, kept_run
from benchmarks.atlas.stepping import run_schedule
from solver.dynamics.loads import Schedule
from solver.installation.planning import StagePlan

__all__ = ["continued_stage"]


@frees_joints
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
    end, the step cuts and the wall time [s] (collective). ValueError for a case with an
    explicit ``[[schedule]]``."""
    request = {
        "case": case_name,
        "overrides": overrides,
        "installed": str(installed),
        "stage": stage,
    }
    if (kept := kept_run(folder, request)) is not None:
        return kept
    wall = time.perf_counter()
    model, excitations, _ = restore_installed(comm, case_name, overrides, installed, stage)
    case, problem = model.case, model.problem
    if case.schedule is not None:
        raise ValueError("the continued stage repeats a stage of the automatic schedule only")
    plans = [StagePlan(**p) for p in installed_state(comm, case, installed, stage)["plans"]]
    vib = case.vibration
    stages = [
        vib.stage(vib.stage_duration_s, e.drive_Hz, e.amplitude_N)
        for e in (*excitations[:stage], excitations[stage - 1])
    ]
    problem.set_scheme(case.vibration_scheme())
    cuts = problem.failed_steps
    rows = run_schedule(model, Schedule(stages, start_s=plans[1].start_s), plans[stage].dt_s)
    result = {
        "request": request,
        "name": folder.name,
        "plan": asdict(plans[stage]),
        "rows": rows,
        "step_cuts": problem.failed_steps - cuts,
        "wall_s": time.perf_counter() - wall,
    }
    keep_run(comm, folder, result)
    return result
