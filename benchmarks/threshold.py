"""Off-resonance threshold (docs/physics.md §5.3) at the control frequency: amplitude steps after a lead-in.

The joint, self-weight stage and durations of tests/solver/installation/test_install_vibration.py (1 s ramp, 0.1 s
lead-in, 0.05 s branches) and the frequencies of benchmarks/branches.py (``settle``: modal
stage, the best-ranked natural frequency f_r and the non-modal control f_c as the installation
run chooses them), then a lead-in of ``--lead-in`` s at (f_c, A) that brings the joint to the
depth at which it holds A. From that state (solver.installation.checkpoint) one branch per factor k of
``--factors``: ``--duration`` s at f_c with the amplitude k A.

Per branch: the settlement gained [mm], over the stage's second half [mm] (the sustained part,
as in the installation summary), and whether the event stabilised (solver.post.report.stabilised:
the last 20 % adds < 5 % of the gain). A branch is amplitude-driven when it gains more than 5
times the branch at k = 1 (the scenario tests' docs/physics.md §5.3 criterion); the threshold lies between
the largest factor below the first amplitude-driven branch and that branch's factor. docs/physics.md §5.2
adds that, below the threshold, a larger amplitude at a non-effective frequency gives no
additional settlement: the branches between k = 1 and the threshold show whether it does.

    mpirun -n 2 python benchmarks/threshold.py                       # cases/scenario.toml
    python benchmarks/threshold.py --factors 1 1.5 2 3 --duration 0.1

Printed and written to ``--output``/threshold.csv (units in the header).
"""

import argparse
import csv
import pathlib
import sys
import time

from common import backend  # noqa: F401

from mpi4py import MPI

from benchmarks.branches import gain, harmonic_stage, late_gain, settle
from solver.installation import checkpoint
from solver.post import report

AMPLITUDE_DRIVEN = 5.0  #: a branch gaining more than this x the gain at A is amplitude-driven [-]
#: the self-weight stage of the scenario tests (tests/solver/installation/test_install_vibration.py): 1 s ramp


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument(
        "--case", default="scenario", help="case: a preset name or a TOML file (default: scenario)"
    )
    p.add_argument("--set", action="append", default=[], metavar="TABLE.KEY=VALUE")
    p.add_argument("--amplitude", type=float, default=3600.0, help="force amplitude A [N]")
    p.add_argument(
        "--factors",
        type=float,
        nargs="+",
        default=[1.0, 1.25, 1.5, 1.75, 2.0],
        help="amplitude factors k of the branches (k A)",
    )
    p.add_argument("--lead-in", type=float, default=0.1, help="lead-in duration at (f_c, A) [s]")
    p.add_argument("--duration", type=float, default=0.05, help="branch duration [s]")
    p.add_argument("--output", default="output/threshold")
    a = p.parse_args(argv)
    if sorted(a.factors) != a.factors or a.factors[0] != 1.0:
        p.error("--factors must start with 1 and increase")
    comm = MPI.COMM_WORLD
    say = print if comm.rank == 0 else (lambda *args, **kw: None)
    out = pathlib.Path(a.output)
    wall = time.perf_counter()
    joint = settle(comm, a.set, a.case)
    model, f_c = joint.model, joint.f_c
    problem = model.problem
    say(
        f"joint: {model.n_dofs} dofs, {comm.size} rank(s); self-weight settlement "
        f"{model.settlement(problem)['settlement_mm']:.4f} mm; f_r = {joint.f_r:.2f} Hz, "
        f"control f_c = {f_c:.2f} Hz ({time.perf_counter() - wall:.0f} s)"
    )
    # whole periods: the force is zero where every branch starts (at phase 0)
    lead = harmonic_stage(model, f_c, a.amplitude, max(1, round(a.lead_in * f_c)) / f_c)
    say(
        f"lead-in at f_c, {a.amplitude:.0f} N: +{gain(lead):.4f} mm, last 20 % "
        f"+{late_gain(lead):.5f} mm"
    )
    branch_dir = out / "after_lead_in"
    checkpoint.save(branch_dir, problem, {})
    rows = []
    for k in a.factors:
        checkpoint.restore(branch_dir, problem)
        problem.reset_operator()
        h = harmonic_stage(model, f_c, k * a.amplitude, a.duration)
        row = {
            "factor": k,
            "amplitude_N": k * a.amplitude,
            "gained_mm": gain(h),
            "gained_second_half_mm": late_gain(h, 0.5),
            "stabilised": report.stabilised(gain(h), late_gain(h)),
        }
        rows.append(row)
        say(
            f"  {k:5.2f} A = {k * a.amplitude:7.0f} N: +{1e3 * row['gained_mm']:9.2f} um, second "
            f"half +{1e3 * row['gained_second_half_mm']:8.2f} um, "
            f"{'stabilised' if row['stabilised'] else 'still settling'} "
            f"({time.perf_counter() - wall:.0f} s)"
        )
    base = max(rows[0]["gained_mm"], 0.0)
    driven = [r for r in rows if r["gained_mm"] > AMPLITUDE_DRIVEN * base and r["gained_mm"] > 0]
    if driven:
        upper = driven[0]["factor"]
        lower = max(r["factor"] for r in rows if r["factor"] < upper)
        say(
            f"off-resonance threshold at {f_c:.2f} Hz: between {lower * a.amplitude:.0f} N and "
            f"{upper * a.amplitude:.0f} N (first branch gaining > {AMPLITUDE_DRIVEN:g} x the gain "
            f"at {a.amplitude:.0f} N)"
        )
    else:
        say(f"off-resonance threshold at {f_c:.2f} Hz: above {a.factors[-1] * a.amplitude:.0f} N")
    if comm.rank == 0:
        out.mkdir(parents=True, exist_ok=True)
        with open(out / "threshold.csv", "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(
                [
                    "frequency_Hz",
                    "factor",
                    "amplitude_N",
                    "duration_s",
                    "gained_mm",
                    "gained_second_half_mm",
                    "stabilised",
                ]
            )
            for r in rows:
                w.writerow(
                    [
                        f"{f_c:.4f}",
                        r["factor"],
                        f"{r['amplitude_N']:.1f}",
                        a.duration,
                        f"{r['gained_mm']:.6g}",
                        f"{r['gained_second_half_mm']:.6g}",
                        r["stabilised"],
                    ]
                )
    return 0


if __name__ == "__main__":
    sys.exit(main())
