"""Modal analysis of the installed scaled joint: cost at the default discretisation and
convergence of the first frequencies.

    python benchmarks/modal_joint.py                 # timing, 1 rank
    mpiexec -n 2 python benchmarks/modal_joint.py    # timing, 2 ranks
    python benchmarks/modal_joint.py --convergence   # table of the first 10 frequencies

Timing: DOF count, wall time of mesh / interface / assembly+eigensolve, total wall and
CPU time per rank (CPU time is the fairer figure on a shared machine), peak resident
memory per rank (getrusage) for the first ``modal.n_modes`` modes (default 20).
Convergence: the first 10 frequencies for the default discretisation and its
refinements (more elements around, finer axially, one degree higher), with the
largest relative change against the default.
"""

import argparse
import sys
import time
from collections.abc import Callable

from common import backend  # noqa: F401  (before dolfinx)

import numpy as np
from mpi4py import MPI

from benchmarks.phase_timer import peak_memory_mb
from common.case import read_case
from geometry import tags
from solver.modal.classify import classify
from solver.installation import cli
from solver.modal.joint import JointCase, joint_modes

REFINEMENTS = [  # (label, overrides) -- the first one is the default discretisation
    ("24 around, 0.08 m, p=3 (default)", []),
    ("32 around, p=3", ["modal.n_circumferential=32"]),
    ("0.04 m axially, p=3", ["mesh.axial_size=0.04"]),
    ("24 around, p=2", ["modal.degree=2"]),
    ("48 around, p=2", ["modal.n_circumferential=48", "modal.degree=2"]),
    ("64 around, p=2", ["modal.n_circumferential=64", "modal.degree=2"]),
    ("96 around, p=2", ["modal.n_circumferential=96", "modal.degree=2"]),
    ("48 around, p=3", ["modal.n_circumferential=48"]),
]
TEN_MODES = ["modal.n_modes=10"]  #: the convergence table's modes


def labels(modes) -> list[str]:
    cells = {
        p: modes.mesh_data.cell_tags.find(t)
        for p, t in (("MP", tags.MP_VOLUME), ("TP", tags.TP_VOLUME))
    }
    out = []
    for u in modes.result.modes:
        w = {p: classify(u, c) for p, c in cells.items()}
        out.append(f"{w['TP'].m},{w['TP'].n}")
    return out


def timing(comm: MPI.Comm, case: JointCase, log: Callable[[str], None]) -> None:
    t0, c0 = time.perf_counter(), time.process_time()
    modes = joint_modes(comm, case, log)
    total, cpu = time.perf_counter() - t0, time.process_time() - c0
    mem = comm.gather(peak_memory_mb())
    cpu = comm.gather(cpu)
    V = modes.result.V
    log(
        f"ranks {comm.size}: dofs {V.dofmap.index_map.size_global * 3}, "
        f"modes {case.modal.n_modes}, "
        f"mesh {modes.timings_s['mesh']:.1f} s, interface {modes.timings_s['interface']:.1f} s, "
        f"assembly+eigensolve {modes.timings_s['eigen']:.1f} s, total {total:.1f} s wall "
        f"(CPU per rank {', '.join(f'{c:.1f}' for c in (cpu or []))} s), "
        f"peak memory per rank {', '.join(f'{m:.0f}' for m in (mem or []))} MB"
    )
    log("first frequencies [Hz]: " + " ".join(f"{f:.2f}" for f in modes.result.frequencies_hz))


def convergence(
    comm: MPI.Comm, cases: list[tuple[str, JointCase]], log: Callable[[str], None]
) -> None:
    rows = []
    for label, case in cases:
        t0 = time.perf_counter()
        modes = joint_modes(comm, case)
        names = labels(modes)
        rows.append(
            (
                label,
                modes.result.V.dofmap.index_map.size_global * 3,
                modes.result.frequencies_hz,
                names,
                time.perf_counter() - t0,
            )
        )
        log(f"  {label}: done ({rows[-1][4]:.0f} s)")
    ref, finest = rows[0][2], rows[-1][2]
    log(
        "| discretisation | dofs | "
        + " | ".join(f"f{i + 1} [Hz]" for i in range(10))
        + " | max change vs default | max diff. vs finest |"
    )
    log("|---|---|" + "---|" * 10 + "---|---|")
    for label, ndofs, f, _names, _ in rows:
        # sorted lists: degenerate pairs line up
        change, diff = np.max(np.abs(f / ref - 1)), np.max(np.abs(f / finest - 1))
        log(
            f"| {label} | {ndofs} | "
            + " | ".join(f"{x:.2f}" for x in f)
            + f" | {100 * change:.2f} % | {100 * diff:.2f} % |"
        )
    for label, _, _, names, _ in rows:
        log(f"TP (m,n), {label}: " + " ".join(names))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--convergence", action="store_true", help="print the convergence table")
    parser.add_argument(
        "--set", action="append", default=[], metavar="KEY=VALUE", help="case override"
    )
    args = parser.parse_args(argv)
    comm = MPI.COMM_WORLD
    try:  # every case checked before the first is computed
        if args.convergence:
            cases = [
                (label, JointCase.from_dict(read_case("scaled", args.set + extra + TEN_MODES)))
                for label, extra in REFINEMENTS
            ]
        else:
            case = JointCase.from_dict(read_case("scaled", args.set))
    except (ValueError, FileNotFoundError) as err:
        return cli.fail(comm, str(err))
    if args.convergence:
        convergence(comm, cases, cli.say(comm))
    else:
        timing(comm, case, cli.say(comm))
    return 0


if __name__ == "__main__":
    sys.exit(main())
