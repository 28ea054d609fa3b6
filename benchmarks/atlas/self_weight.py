"""The self-weight runs of the atlas: the case's self-weight stage from rest, with the natural
frequencies of the settled joint at given times and a bonded band of the
contact's height at the end (for docs/physics.md §5.1, 5.6 and 5.8).

A run is kept as ``run.json`` in its folder with the overrides it was made with; a later call
with the same case and overrides reads it instead of running again (S1's reference run is S6's
and S8's).
"""

import time
from pathlib import Path
from typing import Any

import numpy as np
from mpi4py import MPI

from benchmarks.atlas.kept import frees_joints, keep_run, kept_run
from common.case import read_case
from solver.contact import Status
from solver.installation.case import InstallationCase
from solver.installation.model import JointModel, set_up_joint_model, settled_modes
from solver.modal.eigen import EigenOptions, modal_analysis
from solver.modal.interface import bonded_band
from solver.post import plots
from solver.post.report import slip_episodes

__all__ = ["contact_height", "self_weight_run"]

N_MODES = 10  #: natural frequencies per modal analysis


def contact_height(model: JointModel) -> float:
    """Height [m] above the TP's lower edge of the highest slave point in contact (all ranks)."""
    contact = model.contact
    z = contact.slave.points[:, 2] - model.placed.tp_offset
    touching = contact.state.status != Status.OPEN
    return model.comm.allreduce(float(z[touching].max(initial=0.0)), op=MPI.MAX)


@frees_joints
def self_weight_run(
    comm: MPI.Comm,
    case_name: str,
    overrides: list[str],
    folder: Path,
    modes_at_s: tuple[float, ...] = (),
    until_s: float | None = None,
) -> dict[str, Any]:
    """The self-weight stage of the case up to ``until_s`` [s] (None: the whole stage), the
    natural frequencies [Hz] of the settled joint at the times ``modes_at_s`` [s] and, at the end,
    of the joint with a bonded band as high as the contact; the contact status map at the end
    (``contact_status.png``). Returns (and keeps in ``folder``/run.json) the history (time [s],
    settlement [mm]), the stick-slip events [mm], the frequencies, Newton iterations per step
    and the wall time [s] (collective)."""
    request = {
        "case": case_name,
        "overrides": overrides,
        "modes_at_s": list(modes_at_s),
        "until_s": until_s,
    }
    if (kept := kept_run(folder, request)) is not None:
        return kept
    wall = time.perf_counter()
    case = InstallationCase.from_dict(read_case(case_name, overrides))
    model = set_up_joint_model(comm, case)
    sw = case.self_weight
    time_s, settlement_mm, newton = [], [], []

    def observe(problem) -> dict:
        time_s.append(problem.t)
        settlement_mm.append(model.settlement(problem)["settlement_mm"])
        newton.append(problem.last_result.iterations if problem.last_result else 0)
        return {}

    frequencies = {}
    end = sw.duration_s if until_s is None else until_s
    for t_end in sorted({*modes_at_s, end}):
        model.run_self_weight(t_end, [observe])
        if t_end in modes_at_s:
            frequencies[f"{t_end:g}"] = settled_modes(model, N_MODES)[0].frequencies_hz.tolist()
    height = contact_height(model)
    band = bonded_band(model.V, model.mesh_data.facet_tags, case.material, max(height, 1e-3))
    bonded = modal_analysis(
        model.V, case.material, model.bcs, [band], EigenOptions(n_modes=N_MODES)
    ).frequencies_hz
    if comm.rank == 0:
        folder.mkdir(parents=True, exist_ok=True)
    comm.Barrier()
    plots.plot_contact_status(
        model.contact,
        model.placed,
        folder / "contact_status.png",
        f"after {time_s[-1]:.3g} s of self-weight",
    )
    t, s = np.array(time_s), np.array(settlement_mm)
    result = {
        "request": request,
        "name": folder.name,
        "dofs": model.n_dofs,
        "time_s": time_s,
        "settlement_mm": settlement_mm,
        "ramp_time_s": sw.ramp_time_s,
        "force_N": sw.force_N,
        "events_mm": slip_episodes(t, s, 0.0, 0.0, 1, case.output.slip_rate_mm_s),
        "newton_per_step": float(np.mean(newton)),
        "frequencies_Hz": frequencies,
        "contact_height_m": height,
        "bonded_Hz": bonded.tolist(),
        "wall_s": time.perf_counter() - wall,
    }
    keep_run(comm, folder, result)
    return result
