"""The scenario atlas: the docs/physics.md §5 observations on one joint, written to
docs/scenarios.md (``benchmarks/atlas``).

    mpirun -n 2 python benchmarks/scenarios.py --all                # every scenario in the atlas
    mpirun -n 2 python benchmarks/scenarios.py S1 S8                # a list
    mpirun -n 2 python benchmarks/scenarios.py S1 --case tiny --docs /tmp/atlas.md
    mpirun -n 2 python benchmarks/scenarios.py S2 S3 S4 S5 S8 --installed output/install  # + installed state

The joint is ``--case`` (default ``scaled``: the converged joint, 48 around, P2) with
``--set`` overrides. Each scenario prints its wall time; the page is rebuilt from every outcome
in ``--output`` and, for the scenarios not there, from the outcomes kept beside the page
(``docs/scenarios/<key>.json``).
"""

import argparse
import sys
from pathlib import Path

from common import backend  # noqa: F401

from mpi4py import MPI

from benchmarks.atlas.catalogue import SCENARIOS, Context, run_scenario
from benchmarks.atlas.installed import installed_state
from benchmarks.atlas.page import write_page


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument(
        "scenarios", nargs="*", metavar="SCENARIO", help=f"any of {', '.join(SCENARIOS)}"
    )
    p.add_argument("--all", action="store_true", help="every scenario in the atlas")
    p.add_argument("--case", default="scaled", help="case: a preset name or a TOML file")
    p.add_argument("--set", action="append", default=[], metavar="TABLE.KEY=VALUE")
    p.add_argument("--output", default="output/atlas", help="outputs of the scenarios")
    p.add_argument("--docs", default="docs/scenarios.md", help="the page to rebuild")
    p.add_argument(
        "--installed",
        type=Path,
        metavar="RUN",
        help="output folder of a demos/install.py run of the case on as many ranks: S2 and S4 "
        "read its stages, S3 varies the amplitude at its non-modal frequencies from its last "
        "checkpoint, S4 also drives an anti-symmetric mode from it, S5 also dismounts from it, "
        "S8 also has the frequencies there",
    )
    a = p.parse_args(argv)
    comm = MPI.COMM_WORLD
    keys = (
        [k for k, s in SCENARIOS.items() if a.installed is not None or not s.installed]
        if a.all
        else a.scenarios
    )
    unknown = [k for k in keys if k not in SCENARIOS]
    uninstalled = [
        k for k in keys if a.installed is None and k in SCENARIOS and SCENARIOS[k].installed
    ]
    if not keys or unknown or uninstalled:
        message = (
            f"unknown scenario(s) {', '.join(unknown)}; "
            if unknown
            else "no scenario given (a list, or --all); "
            if not keys
            else f"{', '.join(uninstalled)} read(s) an installation run of the case: "
            "--installed RUN; "
        )
        if comm.rank == 0:
            print(
                message + f"the atlas runs {', '.join(SCENARIOS)}",
                file=sys.stderr,
            )
        return 2
    ctx = Context(comm, a.case, a.set, Path(a.output), a.installed)
    try:
        case = ctx.case()  # the case and the installed state are checked before anything runs
        if a.installed is not None:
            installed_state(comm, case, a.installed)
    except (ValueError, FileNotFoundError) as err:
        if comm.rank == 0:
            print(f"error: {err}", file=sys.stderr)
        return 2
    for key in keys:
        run_scenario(ctx, key)
    if comm.rank == 0:
        write_page(Path(a.output), Path(a.docs))
        print(f"{a.docs} rebuilt", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
