"""The installed state of the atlas: the last checkpoint of an installation run of the case
(``demos/install.py``, the state after its last completed stage), or the state it kept after
one of its stages (``[output] stage_states``), checked against the case, restored, and the
natural frequencies of the joint in that state (docs/physics.md §5.8), as left by the
stage or brought to rest first.

A modal run is kept as ``run.json`` in its folder (a later call with the same request reads it).
"""

import csv
import time
from pathlib import Path
from typing import Any

from mpi4py import MPI

from benchmarks.atlas.kept import frees_joints, keep_run, kept_run
from benchmarks.atlas.self_weight import N_MODES, contact_height
from benchmarks.atlas.stepping import advance
from common.case import read_case
from solver.installation import checkpoint
from solver.installation.case import InstallationCase, case_differences
from solver.installation.frequencies import Excitation
from solver.installation.model import JointModel, set_up_joint_model, settled_modes
from solver.modal.eigen import EigenOptions, modal_analysis
from solver.modal.interface import bonded_band

__all__ = [
    "installed_modes",
    "installed_state",
    "kept_stages",
    "modal_table",
    "restore_installed",
]


def _state_folder(run_folder: Path, stage: int | None) -> Path:
    return run_folder / "checkpoint" if stage is None else run_folder / "states" / str(stage)


def kept_stages(run_folder: Path) -> list[int]:
    """The stages after which the installation run in ``run_folder`` kept its state (sorted)."""
    states = run_folder / "states"
    if not states.is_dir():
        return []
    return sorted(int(p.name) for p in states.iterdir() if p.name.isdigit())


def modal_table(run_folder: Path) -> list[dict[str, str]]:
    """The rows of the modal stage's table of the installation run in ``run_folder`` (its
    ``modes.csv``, docs/modal.md; units in the column names); empty where it has none."""
    path = run_folder / "modes.csv"
    if not path.exists():
        return []
    with path.open() as f:
        return list(csv.DictReader(f))


def installed_state(
    comm: MPI.Comm, case: InstallationCase, run_folder: Path, stage: int | None = None
) -> dict[str, Any]:
    """The manifest of the last checkpoint of the installation run in ``run_folder`` (or of
    the state it kept after ``stage``) (collective). ValueError where there is none, it was
    written on another number of ranks or the run was of another case (its ``[output]`` table
    aside)."""
    folder = _state_folder(run_folder, stage)
    manifest = checkpoint.read_manifest(folder, comm)
    differences = [
        d
        for d in case_differences(manifest.get("case", {}), case.fingerprint())
        if not d.startswith("output.")  # what a run writes does not change its state
    ]
    if differences:
        raise ValueError(
            f"the installation run in {run_folder} is of another case (run -> now): "
            f"{', '.join(differences)}"
        )
    return manifest


def restore_installed(
    comm: MPI.Comm,
    case_name: str,
    overrides: list[str],
    run_folder: Path,
    stage: int | None = None,
    stage_overrides: list[str] | None = None,
) -> tuple[JointModel, list[Excitation], list[float]]:
    """The joint restored from the last checkpoint of the installation run in ``run_folder`` (or
    from the state it kept after ``stage``), that run's excitations and natural frequencies
    [Hz] (collective). The run must be of the case with ``overrides``; the joint is set up
    with ``stage_overrides`` on top (settings of what follows, e.g. ``contact.lagged_friction``)."""
    case = InstallationCase.from_dict(read_case(case_name, overrides))
    manifest = installed_state(comm, case, run_folder, stage)
    if stage_overrides:
        case = InstallationCase.from_dict(read_case(case_name, overrides + stage_overrides))
    model = set_up_joint_model(comm, case)
    checkpoint.restore(_state_folder(run_folder, stage), model.problem)
    excitations = [Excitation(**e) for e in manifest["excitations"]]
    return model, excitations, manifest["natural_frequencies_Hz"]


@frees_joints
def installed_modes(
    comm: MPI.Comm,
    case_name: str,
    overrides: list[str],
    folder: Path,
    run_folder: Path,
    stage: int | None = None,
    rest_s: float = 0.0,
) -> dict[str, Any]:
    """The natural frequencies [Hz] of the joint in the installed state of ``run_folder`` (or
    in the state it kept after ``stage``) and of the joint with a bonded band as high as its
    contact. With ``rest_s`` > 0 the joint is first brought to rest: the shaker off, the static
    load held for ``rest_s`` [s] with the self-weight stage's scheme and step, which damp out the
    vibration the stage left. Returns (and keeps in ``folder``/run.json) them with the state's
    time [s], settlement [mm] and contact height [m], and the wall time [s] (collective)."""
    request = {"case": case_name, "overrides": overrides, "installed": str(run_folder)}
    if stage is not None:
        request["stage"] = stage
    if rest_s > 0:
        request["rest_s"] = rest_s
    if (kept := kept_run(folder, request)) is not None:
        return kept
    wall = time.perf_counter()
    model, _, _ = restore_installed(comm, case_name, overrides, run_folder, stage)
    case, problem = model.case, model.problem
    if rest_s > 0:
        problem.set_scheme(case.self_weight_scheme())
        advance(model, problem.t + rest_s, case.self_weight.dt_s, [])
    frequencies = settled_modes(model, N_MODES)[0].frequencies_hz
    height = contact_height(model)
    band = bonded_band(model.V, model.mesh_data.facet_tags, case.material, max(height, 1e-3))
    bonded = modal_analysis(
        model.V, case.material, model.bcs, [band], EigenOptions(n_modes=N_MODES)
    ).frequencies_hz
    result = {
        "request": request,
        "name": folder.name,
        "time_s": problem.t,
        "settlement_mm": model.settlement(problem)["settlement_mm"],
        "frequencies_Hz": frequencies.tolist(),
        "contact_height_m": height,
        "bonded_Hz": bonded.tolist(),
        "wall_s": time.perf_counter() - wall,
    }
    keep_run(comm, folder, result)
    return result
