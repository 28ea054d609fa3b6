"""The self-weight stage with its own (dissipative) time scheme against the vibration stages' scheme.

The self-weight stage of a case may use a cheaper scheme than the vibration stages
([self_weight] scheme, rho_inf), on the condition that its settlement and stick-slip events
stay within 5 % of a run with the vibration stages' scheme ([time]) at the same step. This
benchmark runs the stage both ways from rest and prints, for each: wall time, steps, Newton
iterations, the settlement at the end of the ramp and of the hold, and the stick-slip events
(count and the settlement of each, ``solver.post.report.slip_episodes``), then the relative
differences.

    mpirun -n 2 python benchmarks/self_weight_scheme.py --case CASE --set 'self_weight.scheme="S"'

The first run takes the case's [self_weight] scheme, which is the [time] scheme unless the
case sets one (the cases in cases/ do not), so the scheme to compare is given with ``--set``.
The comparison of docs/dynamics.md (generalised-alpha rho_inf = 0 against the vibration
scheme, generalised-alpha rho_inf = 0.7, on the coarse joint):

    mpirun -n 2 python benchmarks/self_weight_scheme.py --case coarse \\
        --set 'self_weight.scheme="generalised-alpha"' --set self_weight.rho_inf=0
"""

import argparse
import sys
import time

from common import backend  # noqa: F401

import numpy as np
from mpi4py import MPI

from common.case import read_case
from solver.installation import cli
from solver.installation.case import InstallationCase
from solver.installation.model import set_up_joint_model
from solver.post.report import slip_episodes


def self_weight(comm: MPI.Comm, case: InstallationCase) -> dict:
    """Run the self-weight stage of ``case`` from rest; its figures."""
    t0 = time.perf_counter()
    model = set_up_joint_model(comm, case)
    rows = model.run_self_weight(observers=[model.settlement])
    t = np.array([r["time_s"] for r in rows])
    s = np.array([r["settlement_mm"] for r in rows])
    events = slip_episodes(t, s, 0.0, 0.0, 1, case.output.slip_rate_mm_s)
    return {
        "wall_s": time.perf_counter() - t0,
        "steps": len(rows),
        "newton": sum(r["newton_iterations"] for r in rows) / len(rows),
        "ramp_mm": float(np.interp(case.self_weight.ramp_time_s, t, s)),
        "end_mm": float(s[-1]),
        "events": events,
    }


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--case", default="scaled", help="case file or preset name in cases/")
    p.add_argument(
        "--set", action="append", default=[], metavar="TABLE.KEY=VALUE", help="case override"
    )
    a = p.parse_args(argv)
    comm = MPI.COMM_WORLD
    say = cli.say(comm)
    try:
        own = InstallationCase.from_dict(read_case(a.case, a.set))
        vibration = InstallationCase.from_dict(read_case(a.case, a.set + ['self_weight.scheme=""']))
    except (ValueError, FileNotFoundError) as err:
        return cli.fail(comm, str(err))
    results = {}
    for name, case in (("self-weight scheme", own), ("vibration scheme", vibration)):
        r = results[name] = self_weight(comm, case)
        say(
            f"{name} ({case.self_weight_scheme()}): {r['steps']} steps in {r['wall_s']:.1f} s, Newton "
            f"{r['newton']:.2f}/step; settlement {r['ramp_mm']:.4f} mm at the end of the ramp, {r['end_mm']:.4f} mm "
            f"at the end; {len(r['events'])} stick-slip events of "
            f"{', '.join(f'{1e3 * e:.1f}' for e in r['events'])} um",
        )
    a_, b_ = results["self-weight scheme"], results["vibration scheme"]
    say(
        f"difference (self-weight scheme against vibration scheme): settlement at the end "
        f"{100 * (a_['end_mm'] / b_['end_mm'] - 1):+.2f} %, at the end of the ramp "
        f"{100 * (a_['ramp_mm'] / b_['ramp_mm'] - 1):+.2f} %, events {len(a_['events'])} against "
        f"{len(b_['events'])}, largest event {1e3 * max(a_['events'], default=0):.1f} against "
        f"{1e3 * max(b_['events'], default=0):.1f} um; wall time {a_['wall_s']:.0f} against {b_['wall_s']:.0f} s"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
