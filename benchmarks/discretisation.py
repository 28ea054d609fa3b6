"""The installation run's discretisation against coarser and finer ones: the first 10 natural
frequencies of the joint with a bonded band, the dofs and the cost per time step.

For each discretisation (elements around and Lagrange degree; the case's axial sizes and its
contact zone): the dofs, the first 10 natural frequencies of the joint with a 50 mm bonded band
at the TP's lower edge (``solver.modal.interface.bonded_band``), their largest deviation from the
reference (24 around, degree 3: within 0.33 % of 48 around, degree 3 without the contact zone,
docs/modal.md; with the contact zone 48 around, degree 3 exceeds 23 GB on 2 ranks), and the wall
time per step of the first 0.3 s of the self-weight stage with the case's contact settings (the
TP lands and starts to slide).
Prints a markdown table.

    mpirun -n 2 python benchmarks/discretisation.py [--case CASE] [--set TABLE.KEY=VALUE ...]
"""

import argparse
import sys
import time

from common import backend  # noqa: F401

import numpy as np
from mpi4py import MPI

from common.case import read_case
from solver.dynamics.time_loop import run
from solver.installation import cli
from solver.installation.case import InstallationCase
from solver.installation.model import free_dropped_joints, set_up_joint_model
from solver.modal.eigen import EigenOptions, modal_analysis
from solver.modal.interface import bonded_band

#: (label, case overrides); the last one is the reference
DISCRETISATIONS = [
    (
        "8 around, 0.25 m, degree 2 (cases/coarse.toml)",
        ["mesh.n_circumferential=8", "mesh.axial_size=0.25"],
    ),
    ("24 around, degree 2", ["mesh.n_circumferential=24"]),
    ("32 around, degree 2", ["mesh.n_circumferential=32"]),
    ("48 around, degree 2 (cases/scaled.toml)", []),
    ("64 around, degree 2", ["mesh.n_circumferential=64"]),
    ("24 around, degree 3 (reference)", ["mesh.n_circumferential=24", "contact.degree=3"]),
]
BAND_M = 0.05
STEPS = 30


def measure(comm: MPI.Comm, case: InstallationCase) -> dict:
    model = set_up_joint_model(comm, case)
    band = bonded_band(model.V, model.mesh_data.facet_tags, case.material, BAND_M)
    frequencies = modal_analysis(
        model.V, case.material, model.bcs, [band], EigenOptions(n_modes=10)
    ).frequencies_hz
    dt = case.self_weight.dt_s
    comm.Barrier()
    t0 = time.perf_counter()
    rows = run(model.problem, STEPS * dt, dt, progress=False)
    comm.Barrier()
    return {
        "dofs": model.n_dofs,
        "frequencies": np.sort(frequencies)[:10],
        "s_per_step": (time.perf_counter() - t0) / len(rows),
        "newton": np.mean([r["newton_iterations"] for r in rows]),
    }


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--case", default="scaled", help="case file or preset name in cases/")
    p.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="TABLE.KEY=VALUE",
        help="case override, for every discretisation",
    )
    a = p.parse_args(argv)
    comm = MPI.COMM_WORLD
    say = cli.say(comm)
    try:  # every case checked before the first is computed
        cases = [
            InstallationCase.from_dict(read_case(a.case, a.set + overrides))
            for _, overrides in DISCRETISATIONS
        ]
    except (ValueError, FileNotFoundError) as err:
        return cli.fail(comm, str(err))
    rows = []
    for (label, _), case in zip(DISCRETISATIONS, cases):
        r = measure(comm, case)
        rows.append((label, r))
        free_dropped_joints()  # the last joint's PETSc objects, before the next (larger) one
        say(
            f"{label}: {r['dofs']} dofs, {r['s_per_step']:.2f} s/step (Newton {r['newton']:.2f}/step), "
            f"frequencies {' '.join(f'{f:.2f}' for f in r['frequencies'])} Hz",
        )
    reference = rows[-1][1]["frequencies"]
    say(
        "\n| discretisation | dofs | "
        + " | ".join(f"f{i + 1} [Hz]" for i in range(10))
        + " | largest deviation from the reference | s/step (first 0.3 s of self-weight) |"
    )
    say("|---|---|" + "---|" * 10 + "---|---|")
    for label, r in rows:
        deviation = np.max(np.abs(r["frequencies"] / reference - 1))
        say(
            f"| {label} | {r['dofs']} | "
            + " | ".join(f"{f:.2f}" for f in r["frequencies"])
            + f" | {100 * deviation:.2f} % | {r['s_per_step']:.2f} |"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
