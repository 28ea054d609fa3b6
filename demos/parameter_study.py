"""One-at-a-time parameter study of the installation (docs/physics.md §4, 5.6; docs/install.md "Parameter
study").

From a base case (reference friction mu_s/mu_d = 0.5/0.4, d_c = 100 s/m, Rayleigh damping),
each variant changes one thing: friction 0.0625/0.05, d_c = 1 s/m, modal damping, the axial
mesh size halved. Every variant runs the installation pipeline (self-weight, modal stage, one
stage at the best-ranked natural frequency and one at the non-modal control frequency, 3.6 kN)
into its own sub-folder of --output. Written as the study goes: summary.csv (settlement per
stage per variant, mm, and the sustained rate over each stage's second half, mm/s) and
summary.png (both per stage and variant).

Without options: cases/parameter_study.toml (the default joint of cases/scaled.toml, 48
around, P2, within 3 % of the converged frequencies: docs/install.md "Discretisation").
--quick: --case parameter_study_quick (the tiny joint with the landing contact settings, a
12 ms self-weight ramp and one 2 ms stage at 100 Hz, eccentric amplitude, without the modal
stage) for every variant (a smoke run, not physics).

Usage: mpirun -n 2 python demos/parameter_study.py [--variants low_friction slow_decay ...]
       [--case parameter_study] [--set table.key=value ...] [--quick] [--output DIR]
"""

import sys
import time
from pathlib import Path

from common import backend  # noqa: F401  (before dolfinx)

from mpi4py import MPI

from solver.installation import cli
from solver.installation.model import free_dropped_joints
from solver.post.csv import write_csv
from solver.post.plots import plot_parameter_study
from solver.installation.parameter_study import (
    SUMMARY_COLUMNS,
    select,
    summary_rows,
    variants,
)

DEFAULT_CASE = "parameter_study"
QUICK_CASE = "parameter_study_quick"


def main(argv: list[str] | None = None) -> int:
    p = cli.parser(__doc__.splitlines()[0], "output/parameter_study", DEFAULT_CASE, QUICK_CASE)
    p.add_argument(
        "--variants",
        nargs="+",
        metavar="NAME",
        help="run only these variants besides the base case "
        "(low_friction, slow_decay, modal_damping, fine_mesh)",
    )
    args = p.parse_args(argv)
    comm = MPI.COMM_WORLD
    log = cli.say(comm)
    try:
        base = cli.load_case(args)
        study = variants(base)
        if args.variants is not None:
            study = select(study, args.variants)
        cases = [cli.load_case(args, after=v.overrides) for v in study]
        cli.prepare_output(comm, args.output)
    except ValueError as e:
        return cli.fail(comm, str(e))
    out = Path(args.output)
    log(
        f"parameter study: {len(study)} runs ({', '.join(v.name for v in study)}) into {out}/<name>"
        + (" [--quick: tiny joint, one 2 ms stage, a smoke run]" if args.quick else "")
    )
    rows: list[dict] = []
    code = 0
    for k, (variant, case) in enumerate(zip(study, cases)):
        log(f"\n[{k + 1}/{len(study)}] {variant.name}: {variant.parameter} = {variant.value}")
        wall = time.perf_counter()
        try:
            runner, status_code = cli.run(
                comm, case, out / variant.name, progress=not args.no_progress, log=lambda s: None
            )
            status = "done" if status_code == 0 else "stopped"
        except ValueError as e:  # e.g. modal damping: time step above its stability limit
            log(f"  not run: {e}")
            status, runner = "invalid", None
        if status != "done":
            code = 1
        if runner is not None:
            new = summary_rows(variant, runner.stages, runner.excitations, status)
            rows += new
            for r in new:
                log(
                    f"  {r['name']:>12} {r['role']:>11} {r['frequency_Hz']:8.2f} Hz: "
                    f"gained {r['gained_mm']:+.4f} mm ({r['sustained_rate_mm_s']:+.3f} mm/s over "
                    f"the second half), settlement {r['settlement_end_mm']:.4f} mm"
                )
        log(f"  {status} in {time.perf_counter() - wall:.1f} s")
        del runner
        free_dropped_joints()  # this variant's joint, before the next one is set up
        write_csv(out / "summary.csv", SUMMARY_COLUMNS, rows, comm)
        plot_parameter_study(rows, out / "summary.png", comm)
    log(f"\nsummary: {out / 'summary.csv'}, {out / 'summary.png'}")
    if comm.rank == 0:
        finals = {r["variant"]: r["settlement_end_mm"] for r in rows}
        for name, s in finals.items():
            print(f"  {name:>14}: final settlement {s:.4f} mm", flush=True)
    return code


if __name__ == "__main__":
    sys.exit(main())
