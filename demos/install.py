"""Vibration-assisted installation of the scaled slip-joint (docs/physics.md §3, 5; docs/install.md).

Stages: self-weight (10 kN ramped over 2 s, stick-slip settlement), modal analysis of the
settled joint with the contact tangent and a ranked choice of excitation frequencies,
vibration at those frequencies plus a non-modal control, and a report. Outputs go to
--output as the run goes (case.json, history.csv, stages.csv, modes.csv, frequencies.csv,
plots, ParaView files, summary.txt); a killed run continues with --resume, which refuses a
case that would compute something else (exit code 2, naming the keys that differ).

The default case is cases/scaled.toml: the reference sequence (the 68 Hz and 100 Hz lead-in,
then at 3.6 kN the four best-ranked natural frequencies of the settled joint up to 330 Hz, the
(2, 1) mode and a non-modal control, 0.1 s each) on the converged joint (48 elements around,
degree 2); --full is --case scaled_full (the ten best-ranked natural frequencies, a 300 mm
contact zone), --quick is --case install_quick (a smoke run on a tiny joint).

Usage: mpirun -n 2 python demos/install.py [--case scaled] [--set table.key=value ...]
       [--mu-s 0.5 --mu-d 0.4 --d-c 100] [--damping rayleigh|modal]
       [--forcing eccentric|face|shaker]
       [--quick | --full] [--output DIR] [--resume]
"""

import argparse
import sys

from common import backend  # noqa: F401  (before dolfinx)

from mpi4py import MPI

from solver.installation import cli
from solver.installation.runner import Installation

DEFAULT_CASE = "scaled"
QUICK_CASE = "install_quick"
FULL_CASE = "scaled_full"


def parse(argv: list[str] | None) -> argparse.Namespace:
    p = cli.parser(
        __doc__.splitlines()[0], "output/install", DEFAULT_CASE, QUICK_CASE, named=cli.NAMED
    )
    p.add_argument(
        "--full",
        action="store_true",
        help=f"--case {FULL_CASE}: the reference sequence with the ten best-ranked natural "
        "frequencies",
    )
    p.add_argument(
        "--resume",
        action="store_true",
        help="continue from the last checkpoint in --output (the same case only)",
    )
    return p.parse_args(argv)


def main(argv: list[str] | None = None) -> int:
    args = parse(argv)
    comm = MPI.COMM_WORLD
    try:
        if args.full:
            if args.case is not None or args.quick:
                raise ValueError(
                    f"--full is --case {FULL_CASE}; it cannot be combined with --case or --quick"
                )
            args.case = FULL_CASE
        case = cli.load_case(args)
        cli.prepare_output(comm, args.output)
    except ValueError as e:
        return cli.fail(comm, str(e))
    runner = Installation(comm, case, args.output, progress=not args.no_progress)
    try:
        runner.run(resume=args.resume)
    except ValueError as e:  # --resume without a checkpoint, or with one of another case
        return cli.fail(comm, str(e))
    except RuntimeError as e:  # the time loop gave up (Newton failed at the minimum step)
        if comm.rank == 0:
            print(
                f"\nrun stopped: {e}\nresults up to this point are in {args.output} "
                "(history.csv, stages.csv)",
                file=sys.stderr,
            )
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
