"""Modal analysis of the installed scaled slip-joint with a bonded band at the TP lower edge.

Writes to --output: modes.csv (frequencies, (m, n), dominant part, participation,
interface slip, ranking), modes.png (deformed shapes) and modes.bp (ParaView, VTX;
"time" = mode number), and prints the table.

--quick is --case modal_quick (degree 2, 0.2 m axially, 10 modes).

Usage: mpirun -n 2 python demos/modal.py [--case scaled] [--band 0.05] [--quick]
       [--output DIR] [--set modal.degree=3 --set mesh.n_circumferential=64 ...]
"""

import sys

from common import backend  # noqa: F401  (before dolfinx)

from mpi4py import MPI

from solver.installation import cli
from solver.modal.joint import JointCase, joint_modes
from solver.modal.outputs import format_table, write_outputs
from solver.modal.ranking import JointParts, describe_modes

DEFAULT_CASE = "scaled"
QUICK_CASE = "modal_quick"


def main(argv: list[str] | None = None) -> int:
    parser = cli.case_parser(__doc__.splitlines()[0], "output/modal", DEFAULT_CASE, QUICK_CASE)
    parser.add_argument(
        "--band", type=float, help="bonded band height at the TP lower edge [m] (default 0.05)"
    )
    args = parser.parse_args(argv)
    comm = MPI.COMM_WORLD

    def log(message: str) -> None:
        if comm.rank == 0:
            print(message, flush=True)

    band = [] if args.band is None else [f"modal.band_height={args.band!r}"]
    try:
        case = JointCase.from_dict(cli.read(args, after=band))
        output = cli.prepare_output(comm, args.output)
    except ValueError as e:
        return cli.fail(comm, str(e))
    log(f"modal analysis of {cli.case_name(args)}: {comm.size} rank(s)")
    modes = joint_modes(comm, case, log)
    V = modes.result.V
    log("classifying modes")
    parts = JointParts.for_joint(V, modes.mesh_data, case.joint)
    records = describe_modes(modes.result, case.material, parts, zeta=case.modal.zeta)
    log(format_table(records))
    log("writing outputs")
    paths = write_outputs(modes.result, records, output)
    for kind, path in paths.items():
        log(f"  {kind}: {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
