"""Frequency sweeps of the installed slip-joint (docs/physics.md §3, 5.7; docs/install.md "Sweeps").

After the self-weight stage (and the modal stage, whose natural frequencies are marked on the
plots), either (a) a step-wise frequency increase, --sweep steps: --f-start to --f-stop in
--f-step steps of --dwell seconds each (docs/physics.md §3: 10 -> 130 Hz in 10 Hz steps of 0.5 s), or
(b) a slow linear frequency ramp, --sweep ramp: --f-start to --f-stop over --ramp-duration
seconds (docs/physics.md §3: 0 -> 125 Hz over 13-200 s); the force amplitude is the eccentric-motor law
0.3632 f^2 N (--amplitude eccentric) or a fixed force [N]. The sweep is the case's [sweep]
table (``SweepPlan``; each option sets its entry, --set sweep.KEY=VALUE too); it replaces any
[[schedule]] of the case.

Outputs in --output: sweep.csv (time_s, frequency_Hz, amplitude_N, settlement_mm,
settlement_gain_mm), sweep.png (settlement gained against time and against frequency), and
the installation outputs (history.csv, stages.csv with the gain per step, modes.csv, ...).

Without options: cases/sweep.toml (the default joint of cases/scaled.toml, 48 around, P2,
within 3 % of the converged frequencies: docs/install.md "Discretisation"; 20 modes) and its
[sweep] table, the defaults: 10 -> 130 Hz in 10 Hz steps of 0.03 s at the eccentric amplitude
(the published tests' 0.5 s steps: --dwell 0.5, about 16 x longer). --quick: --case
sweep_quick (the demos' smoke-run joint) and three 2 ms steps (not physics).

Usage: mpirun -n 2 python demos/sweep.py [--sweep steps|ramp] [--f-start HZ] [--f-stop HZ]
       [--f-step HZ] [--dwell S] [--ramp-duration S] [--amplitude eccentric|N]
       [--case sweep] [--set table.key=value ...] [--quick] [--output DIR]
"""

import sys
from pathlib import Path

from common import backend  # noqa: F401  (before dolfinx)

from mpi4py import MPI

from solver.installation import cli
from solver.installation.sweep import read_sweep, sweep_case
from solver.post import report
from solver.post.csv import write_csv
from solver.post.plots import plot_sweep

DEFAULT_CASE = "sweep"
QUICK_CASE = "sweep_quick"
#: the demo's options and the [sweep] entries they set (--set sweep.KEY=VALUE wins)
PLAN_OPTIONS = {
    "sweep": "kind",
    "f_start": "f_start_hz",
    "f_stop": "f_stop_hz",
    "f_step": "f_step_hz",
    "dwell": "dwell_s",
    "ramp_duration": "duration_s",
    "amplitude": "amplitude_N",
}
#: the options of one kind of sweep only
ONLY_FOR = {"f_step": "steps", "dwell": "steps", "ramp_duration": "ramp"}


def _entries(args) -> list[str]:
    """The options given, as [sweep] overrides (ValueError on a bad --amplitude)."""
    given = []
    for option, key in PLAN_OPTIONS.items():
        value = getattr(args, option)
        if value is None:
            continue
        if option == "amplitude":
            value = cli.amplitude(value)
        given.append(f"sweep.{key}={value!r}" if isinstance(value, str) else f"sweep.{key}={value}")
    return given


def main(argv: list[str] | None = None) -> int:
    p = cli.parser(__doc__.splitlines()[0], "output/sweep", DEFAULT_CASE, QUICK_CASE)
    p.add_argument(
        "--sweep", choices=["steps", "ramp"], help="step-wise increase or linear ramp (steps)"
    )
    p.add_argument("--f-start", type=float, help="first frequency [Hz] (10)")
    p.add_argument("--f-stop", type=float, help="last frequency [Hz] (130)")
    p.add_argument("--f-step", type=float, help="steps: frequency step [Hz] (10)")
    p.add_argument(
        "--dwell",
        type=float,
        help="steps: duration of each step [s] (0.03; the published tests: 0.5)",
    )
    p.add_argument(
        "--ramp-duration", type=float, help="ramp: duration [s] (1; the published tests: 13-200)"
    )
    p.add_argument("--amplitude", help="'eccentric' (0.3632 f^2 N, default) or a force [N]")
    p.add_argument(
        "--no-modal", action="store_true", help="skip the modal stage (no natural frequencies)"
    )
    args = p.parse_args(argv)
    comm = MPI.COMM_WORLD
    log = cli.say(comm)
    after = ["vibration.modal_stage=false"] if args.no_modal else []

    def edit(data: dict) -> None:
        plan = read_sweep(data)
        for option, kind in ONLY_FOR.items():
            if getattr(args, option) is not None and plan.kind != kind:
                name = "--" + option.replace("_", "-")
                raise ValueError(f"{name} does not apply to --sweep {plan.kind}")
        sweep_case(data, plan)

    try:
        case = cli.load_case(args, before=_entries(args), after=after, edit=edit)
        cli.prepare_output(comm, args.output)
    except ValueError as e:
        return cli.fail(comm, str(e))
    plan = case.sweep
    what = (
        f"{plan.f_start_hz:g} -> {plan.f_stop_hz:g} Hz in {plan.f_step_hz:g} Hz steps of "
        f"{plan.dwell_s:g} s ({len(plan.stages())} steps)"
        if plan.kind == "steps"
        else f"linear ramp {plan.f_start_hz:g} -> {plan.f_stop_hz:g} Hz over {plan.duration_s:g} s"
    )
    amplitude = "eccentric" if plan.amplitude_N == "eccentric" else f"{plan.amplitude_N:g} N"
    log(
        f"sweep: {what}, amplitude {amplitude}"
        + (" [--quick: tiny joint, very short stages, a smoke run]" if args.quick else "")
    )
    runner, code = cli.run(comm, case, args.output, progress=not args.no_progress)
    if runner.model is None or len(runner.stages) < 2:
        return code
    out = Path(args.output)
    rows = report.sweep_rows(runner.history)
    write_csv(out / "sweep.csv", report.SWEEP_COLUMNS, rows, comm)
    plot_sweep(rows, runner.stages, runner.natural_frequencies, out / "sweep.png", comm)
    log(
        f"\nsweep: settlement gained {rows[-1]['settlement_gain_mm']:+.4f} mm over "
        f"{rows[-1]['time_s'] - runner.stages[1]['start_s']:.4g} s"
    )
    if plan.kind == "steps":
        for s in runner.stages[1:]:
            log(
                f"  {s['frequency_Hz']:7.2f} Hz  {s['amplitude_N']:8.0f} N  "
                f"gained {s['gained_mm']:+.4f} mm"
            )
    log(f"outputs in {out}: sweep.csv, sweep.png, history.csv, stages.csv")
    return code


if __name__ == "__main__":
    sys.exit(main())
