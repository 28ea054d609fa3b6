"""Frequency sweeps of the installed slip-joint (docs/physics.md §3, 5.7; docs/install.md "Sweeps").

After the self-weight stage (and the modal stage, whose natural frequencies are marked on the
plots), either (a) a step-wise frequency increase, --sweep steps: --f-start to --f-stop in
--f-step steps of --dwell seconds each (docs/physics.md §3: 10 -> 130 Hz in 10 Hz steps of 0.5 s), or
(b) a slow linear frequency ramp, --sweep ramp: --f-start to --f-stop over --ramp-duration
seconds (docs/physics.md §3: 0 -> 125 Hz over 13-200 s); the force amplitude is the eccentric-motor law
0.3632 f^2 N (--amplitude eccentric, default) or a fixed force [N]. A [[schedule]] in the case
file is replaced by the sweep.

Outputs in --output: sweep.csv (time_s, frequency_Hz, amplitude_N, settlement_mm,
settlement_gain_mm), sweep.png (settlement gained against time and against frequency), and
the installation outputs (history.csv, stages.csv with the gain per step, modes.csv, ...).

Without options: cases/sweep.toml (the default joint of cases/scaled.toml, 48 around, P2,
within 3 % of the converged frequencies: docs/install.md "Discretisation"; 20 modes) and
steps of 0.03 s (the published tests' 0.5 s steps: --dwell 0.5, about 16 x longer).
--quick: --case quick (the demos' smoke-run joint) and three 2 ms steps (not physics).

Usage: mpirun -n 2 python demos/sweep.py [--sweep steps|ramp] [--f-start HZ] [--f-stop HZ]
       [--f-step HZ] [--dwell S] [--ramp-duration S] [--amplitude eccentric|N]
       [--case sweep] [--set table.key=value ...] [--quick] [--output DIR]
"""

import sys
from pathlib import Path

from common import backend  # noqa: F401  (before dolfinx)

from dataclasses import asdict

from mpi4py import MPI

from solver.dynamics.loads import frequency_ramp, frequency_steps
from solver.installation import cli
from solver.post import report
from solver.post.csv import write_csv
from solver.post.plots import plot_sweep

DEFAULT_CASE = "sweep"
QUICK_CASE = "quick"
#: per sweep kind: f_start, f_stop [Hz], then f_step [Hz] and dwell [s] or the ramp duration [s]
SWEEPS = {
    "steps": {"f_start": 10.0, "f_stop": 130.0, "f_step": 10.0, "dwell": 0.03},
    "ramp": {"f_start": 0.0, "f_stop": 125.0, "ramp_duration": 1.0},
}
QUICK_SWEEPS = {
    "steps": {"f_start": 40.0, "f_stop": 120.0, "f_step": 40.0, "dwell": 0.002},
    "ramp": {"f_start": 0.0, "f_stop": 125.0, "ramp_duration": 0.012},
}


def sweep_stages(kind: str, values: dict[str, float], amplitude: float | str) -> list[dict]:
    """The sweep as [[schedule]] tables."""
    if kind == "steps":
        stages = frequency_steps(
            values["f_start"], values["f_stop"], values["f_step"], values["dwell"], amplitude
        )
    else:
        stages = frequency_ramp(
            values["f_start"], values["f_stop"], values["ramp_duration"], amplitude
        )
    return [{k: v for k, v in asdict(s).items() if v is not None} for s in stages]


def main(argv: list[str] | None = None) -> int:
    p = cli.parser(__doc__.splitlines()[0], "output/sweep", DEFAULT_CASE, QUICK_CASE)
    p.add_argument(
        "--sweep", choices=list(SWEEPS), default="steps", help="step-wise increase or linear ramp"
    )
    p.add_argument("--f-start", type=float, help="first frequency [Hz] (steps 10, ramp 0)")
    p.add_argument("--f-stop", type=float, help="last frequency [Hz] (steps 130, ramp 125)")
    p.add_argument("--f-step", type=float, help="steps: frequency step [Hz] (10)")
    p.add_argument(
        "--dwell",
        type=float,
        help="steps: duration of each step [s] (0.03; the published tests: 0.5)",
    )
    p.add_argument(
        "--ramp-duration", type=float, help="ramp: duration [s] (1; the published tests: 13-200)"
    )
    p.add_argument(
        "--amplitude", default="eccentric", help="'eccentric' (0.3632 f^2 N) or a force [N]"
    )
    p.add_argument(
        "--no-modal", action="store_true", help="skip the modal stage (no natural frequencies)"
    )
    args = p.parse_args(argv)
    comm = MPI.COMM_WORLD
    log = cli.say(comm)
    values = dict((QUICK_SWEEPS if args.quick else SWEEPS)[args.sweep])
    for key in values:
        given = getattr(args, key)
        if given is not None:
            values[key] = given
    wrong = [
        k
        for k in ("f_step", "dwell", "ramp_duration")
        if getattr(args, k) is not None and k not in values
    ]
    after = ["vibration.modal_stage=false"] if args.no_modal else []
    try:
        if wrong:
            option = "--" + wrong[0].replace("_", "-")
            raise ValueError(f"{option} does not apply to --sweep {args.sweep}")
        stages = sweep_stages(args.sweep, values, cli.amplitude(args.amplitude))

        def edit(data: dict) -> None:
            data["schedule"] = [{**s, **_direction(data)} for s in stages]

        case = cli.load_case(args, after=after, edit=edit)
        cli.prepare_output(comm, args.output)
    except ValueError as e:
        return cli.fail(comm, str(e))
    what = (
        f"{values['f_start']:g} -> {values['f_stop']:g} Hz in {values['f_step']:g} Hz steps of "
        f"{values['dwell']:g} s ({len(stages)} steps)"
        if args.sweep == "steps"
        else f"linear ramp {values['f_start']:g} -> {values['f_stop']:g} Hz over "
        f"{values['ramp_duration']:g} s"
    )
    log(
        f"sweep: {what}, amplitude {args.amplitude}"
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
    if args.sweep == "steps":
        for s in runner.stages[1:]:
            log(
                f"  {s['frequency_Hz']:7.2f} Hz  {s['amplitude_N']:8.0f} N  "
                f"gained {s['gained_mm']:+.4f} mm"
            )
    log(f"outputs in {out}: sweep.csv, sweep.png, history.csv, stages.csv")
    return code


def _direction(data: dict) -> dict:
    """The case's [vibration] direction settings for the generated stages."""
    vib = data.get("vibration", {})
    keys = {
        "direction": "direction",
        "lateral_fraction": "lateral_fraction",
        "angle_deg": "lateral_angle_deg",
    }
    return {stage_key: vib[key] for key, stage_key in keys.items() if key in vib}


if __name__ == "__main__":
    sys.exit(main())
