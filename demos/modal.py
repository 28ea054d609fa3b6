"""Modal analysis of the installed scaled slip-joint with a bonded band at the TP lower edge.

Writes to --output: modes.csv (frequencies, (m, n), dominant part, participation,
interface slip, ranking), modes.png (deformed shapes) and modes.bp (ParaView, VTX;
"time" = mode number), and prints the table.

Usage: mpirun -n 2 python demos/modal.py [--case scaled] [--band 0.05] [--quick]
       [--output DIR] [--set modal.degree=3 --set mesh.n_circumferential=64 ...]
"""

import argparse
import sys
from pathlib import Path

from common import backend  # noqa: F401  (before dolfinx)

from mpi4py import MPI

from common.case import read_case
from solver.modal.joint import JointCase, joint_modes
from solver.modal.ranking import describe_modes, JointParts
from solver.modal.outputs import format_table, write_outputs

QUICK = ["modal.degree=2", "mesh.axial_size=0.2", "modal.n_modes=10"]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--case", default="scaled", help="case file or preset name (cases/*.toml)")
    parser.add_argument(
        "--band", type=float, help="bonded band height at the TP lower edge [m] (default 0.05)"
    )
    parser.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="override a case entry, e.g. modal.n_modes=30",
    )
    parser.add_argument(
        "--quick",
        action="store_true",
        help="coarse smoke run (24 around, 0.2 m, degree 2, 10 modes)",
    )
    parser.add_argument("--output", default="output/modal", help="output folder")
    args = parser.parse_args(argv)
    comm = MPI.COMM_WORLD

    def log(message: str) -> None:
        if comm.rank == 0:
            print(message, flush=True)

    overrides = (QUICK if args.quick else []) + args.set
    if args.band is not None:
        overrides.append(f"modal.band_height={args.band!r}")
    try:
        case = JointCase.from_dict(read_case(args.case, overrides))
    except ValueError as e:
        log(f"error: {e}")
        return 2
    log(f"modal analysis of {args.case}: {comm.size} rank(s)")
    modes = joint_modes(comm, case, log)
    V = modes.result.V
    log("classifying modes")
    parts = JointParts.for_joint(V, modes.mesh_data, case.joint)
    records = describe_modes(modes.result, case.material, parts, zeta=case.modal.zeta)
    log(format_table(records))
    log("writing outputs")
    paths = write_outputs(modes.result, records, Path(args.output))
    for kind, path in paths.items():
        log(f"  {kind}: {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
