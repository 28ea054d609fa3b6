"""Dismount of the installed slip-joint (docs/physics.md §3, 5.5; docs/install.md "Dismount").

From the installed state (self-weight stage, optionally --install-stages stages of vibration at
the ranked natural frequencies), the axial force on the TP top is ramped from the self-weight
force (10 kN down) to a pull (--pull, upward, default 6 kN) and held: (1) the pull alone, then
(2) the pull plus vibration at the ranked natural frequencies of the settled joint (modal stage
after self-weight). Reported per stage: the TP's axial motion (settlement decreasing = the TP
moves up) and whether it separated (contact normal force -> 0). Outputs in --output:
dismount.csv, dismount.png, and everything of the installation run (history.csv, stages.csv,
modes.csv, frequencies.csv, plots, summary.txt).

Without options: cases/dismount.toml (the default joint of cases/scaled.toml, 48 around, P2,
whose ten lowest frequencies are within 3 % of the converged ones: docs/install.md
"Discretisation") and the sequence of the case's [dismount] table (``DismountPlan``'s
defaults, the option values below; each option sets its entry, --set dismount.KEY=VALUE
too). After the self-weight stage alone this joint is held by a contact normal force of about
21 kN, so its rigid Coulomb pull-out force N (mu cos(alpha) - sin(alpha)) is 7.91-9.98 kN
(printed; docs/scenarios.md, S5): the default pull of 6 kN lies below it, a pull in
docs/physics.md §3's rig range (10-40 kN, e.g. --pull 20e3) frees this joint without
vibration. --quick: --case dismount_quick (the tiny joint with the landing contact settings)
and the very short stages of its [dismount] table (a smoke run: the TP is still sliding at the
end of its 12 ms self-weight ramp, so little normal force has built up and the pull alone
separates it).

Usage: mpirun -n 2 python demos/dismount.py [--pull 6e3] [--pull-ramp 0.05] [--pull-hold 0.05]
       [--install-stages 0] [--n-frequencies 2] [--stage-duration 0.03] [--amplitude 3600]
       [--case dismount] [--set table.key=value ...] [--quick] [--output DIR]
"""

import sys
from pathlib import Path

from common import backend  # noqa: F401  (before dolfinx)

from mpi4py import MPI

from solver.installation import cli
from solver.installation.dismount import (
    DISMOUNT_COLUMNS,
    dismount_case,
    dismount_table,
    pull_out_force,
    read_plan,
)
from solver.post.csv import write_csv
from solver.post.plots import plot_dismount

DEFAULT_CASE = "dismount"
QUICK_CASE = "dismount_quick"
#: the demo's options and the [dismount] entries they set (--set dismount.KEY=VALUE wins)
PLAN_OPTIONS = {
    "pull": "pull_N",
    "pull_ramp": "ramp_s",
    "pull_hold": "hold_s",
    "install_stages": "n_install",
    "n_frequencies": "n_frequencies",
    "stage_duration": "stage_duration_s",
    "amplitude": "amplitude_N",
}


def main(argv: list[str] | None = None) -> int:
    p = cli.parser(__doc__.splitlines()[0], "output/dismount", DEFAULT_CASE, QUICK_CASE)
    p.add_argument(
        "--pull",
        type=float,
        help="upward pulling force [N] (6 kN; docs/physics.md §3 rig: 10-40 kN)",
    )
    p.add_argument(
        "--pull-ramp", type=float, help="ramp from the self-weight force to the pull [s] (0.05)"
    )
    p.add_argument("--pull-hold", type=float, help="pull alone, held [s] (0.05)")
    p.add_argument(
        "--install-stages",
        type=int,
        help="vibration stages at the ranked frequencies before pulling (0)",
    )
    p.add_argument("--n-frequencies", type=int, help="pull + vibration stages at ranked 1..n (2)")
    p.add_argument("--stage-duration", type=float, help="each vibration stage [s] (0.03)")
    p.add_argument("--amplitude", type=float, help="vibration force amplitude [N] (3600)")
    args = p.parse_args(argv)
    comm = MPI.COMM_WORLD
    log = cli.say(comm)
    given = [
        f"dismount.{key}={getattr(args, option)}"
        for option, key in PLAN_OPTIONS.items()
        if getattr(args, option) is not None
    ]
    try:
        case = cli.load_case(
            args, before=given, edit=lambda data: dismount_case(data, read_plan(data))
        )
        cli.prepare_output(comm, args.output)
    except ValueError as e:
        return cli.fail(comm, str(e))
    plan = case.dismount
    log(
        f"dismount: {-case.self_weight.force_N / 1e3:.1f} kN self-weight, {plan.n_install} "
        f"installation stage(s), pull {plan.pull_N / 1e3:.1f} kN up (ramp {plan.ramp_s} s, "
        f"alone {plan.hold_s} s), "
        f"then {plan.n_frequencies} stage(s) of pull + {plan.amplitude_N:.0f} N at the ranked "
        f"frequencies, {plan.stage_duration_s} s each"
        + (" [--quick: tiny joint, very short stages, a smoke run]" if args.quick else "")
    )
    runner, code = cli.run(comm, case, args.output, progress=not args.no_progress)
    if runner.model is None or len(runner.stages) < 2:
        return code
    out = Path(args.output)
    table = dismount_table(runner.history, runner.stages, plan.roles(), runner.model.static)
    write_csv(out / "dismount.csv", DISMOUNT_COLUMNS, table, comm)
    plot_dismount(runner.history, table, out / "dismount.png", comm)
    installed = [r for r in runner.history if r["stage"] == plan.n_install][-1]
    normal, alpha = installed["normal_force_N"], case.joint.mp.half_angle
    low, high = (
        pull_out_force(normal, mu, alpha) for mu in (case.friction.mu_d, case.friction.mu_s)
    )
    log(
        f"\ninstalled state: settlement {installed['settlement_mm']:.4f} mm, contact normal force "
        f"{normal / 1e3:.2f} kN; rigid Coulomb pull-out estimate N (mu cos(alpha) - sin(alpha)) "
        f"= {low / 1e3:.2f} kN (mu_d) .. {high / 1e3:.2f} kN (mu_s)"
    )
    log("dismount (axial motion: + = the TP moved up)")
    for row in table:
        f = f"{row['frequency_Hz']:7.2f} Hz" if row["frequency_Hz"] else "    --    "
        log(
            f"  {row['role']:>16} {f}  static force {row['static_force_end_N'] / 1e3:+7.2f} kN  "
            f"axial motion {row['axial_motion_mm']:+9.4f} mm  normal force "
            f"{row['normal_force_end_N'] / 1e3:8.3f} kN  "
            f"{'SEPARATED' if row['separated'] else 'held'}"
        )
    first = next((r for r in table if r["separated"]), None)
    log(
        "result: "
        + (
            f"the TP separated in the '{first['role']}' stage"
            + (f" at {first['frequency_Hz']:.2f} Hz" if first["frequency_Hz"] else "")
            if first
            else "the TP did not separate"
        )
        + f"; outputs in {out}"
    )
    return code


if __name__ == "__main__":
    sys.exit(main())
