"""Wall time per phase of an installation run: set-up, self-weight, modal stage, each vibration stage.

Runs the installation pipeline of a case (default: ``cases/scaled.toml``, the default run of
``demos/install.py``; ``--case scaled_full``: its ``--full``) with the phase timer of
``benchmarks/phase_timer.py`` and prints, per time-stepping stage: steps, wall time, s/step,
Newton iterations and GMRES iterations per step (or the contact points' traction iterations
per step), factorisations, step cuts, the mean time of one triangular solve with the contact
zone's LU factors and the ratio (time per step) / (one triangular solve), then the phase
breakdown of the stage's steps. The last lines are a table of the whole run; where the run
stops (Newton failed at the minimum step, or the contact band left the contact zone), a table
of the stages before the stop and exit code 1.

    mpirun -n 2 python benchmarks/installation_run.py                 # cases/scaled.toml
    mpirun -n 2 python benchmarks/installation_run.py --case scaled_full
    mpirun -n 2 python benchmarks/installation_run.py --set vibration.n_frequencies=1
    mpirun -n 2 python benchmarks/installation_run.py --output DIR --resume   # a killed run
"""

import argparse
import sys
import time

from common import backend  # noqa: F401

from mpi4py import MPI

from benchmarks.phase_timer import PhaseTimer, peak_memory_mb
from common.case import read_case
from common.timing import recording
from solver.installation.case import InstallationCase
from solver.installation import cli
from solver.installation.runner import Installation


class StageProfile:
    """``on_stage`` hook of ``Installation``: one phase report per stage and a summary table."""

    def __init__(self, comm: MPI.Comm, timer: PhaseTimer):
        self.comm, self.timer = comm, timer
        self.say = cli.say(comm)
        self.rows: list[dict] = []
        self._start = 0.0

    def __call__(self, event: str, data) -> None:
        if event == "start":
            self.timer.reset()
            self._start = time.perf_counter()
        elif event == "modal":
            self.rows.append({"phase": "modal stage", "wall_s": data})
        elif event == "end":
            wall = time.perf_counter() - self._start
            steps = data["steps"]
            newton = data["newton_iterations_mean"] * steps
            solve = self.timer.triangular_solve_s()
            row = {
                "phase": f"{data['name']} ({data['frequency_Hz']:.1f} Hz)"
                if data["frequency_Hz"]
                else data["name"],
                "wall_s": wall,
                "steps": steps,
                "s_per_step": wall / max(steps, 1),
                "newton_per_step": data["newton_iterations_mean"],
                "gmres_per_step": self.timer.gmres / max(steps, 1),
                "tractions_per_step": self.timer.traction_iterations / max(steps, 1),
                "factorisations": self.timer.calls.get("factorisation", 0),
                "step_cuts": data["step_cuts"],
                "solve_ms": 1e3 * solve,
                "ratio": wall / max(steps, 1) / solve,
            }
            self.rows.append(row)
            self.say(
                f"{row['phase']}: {steps} steps in {wall:.1f} s ({row['s_per_step']:.3f} s/step), Newton "
                f"{row['newton_per_step']:.2f}/step, GMRES {row['gmres_per_step']:.1f}/step, traction "
                f"iterations {row['tractions_per_step']:.1f}/step, "
                f"{row['factorisations']} factorisations, {row['step_cuts']} step cuts; one triangular "
                f"solve {row['solve_ms']:.1f} ms, step / solve = {row['ratio']:.1f}",
            )
            self.timer.report(self.comm, steps, int(round(newton)), self.say)

    def table(self, setup_s: float, total_s: float) -> None:
        self.say(
            "\n| phase | wall [s] | steps | s/step | Newton/step | GMRES/step | traction iterations/step "
            "| factorisations | step cuts | triangular solve [ms] | step / solve |"
        )
        self.say("|---|---|---|---|---|---|---|---|---|---|---|")
        self.say(f"| set-up | {setup_s:.1f} | | | | | | | | | |")
        for r in self.rows:
            if "steps" not in r:
                self.say(f"| {r['phase']} | {r['wall_s']:.1f} | | | | | | | | | |")
                continue
            self.say(
                f"| {r['phase']} | {r['wall_s']:.1f} | {r['steps']} | {r['s_per_step']:.3f} | "
                f"{r['newton_per_step']:.2f} | {r['gmres_per_step']:.1f} | "
                f"{r['tractions_per_step']:.1f} | {r['factorisations']} | "
                f"{r['step_cuts']} | {r['solve_ms']:.1f} | {r['ratio']:.1f} |"
            )
        self.say(f"| **total** | **{total_s:.1f}** ({total_s / 60:.1f} min) | | | | | | | | | |")
        memory = self.comm.gather(peak_memory_mb())
        self.say(f"peak resident memory per rank: {', '.join(f'{m:.0f}' for m in memory or [])} MB")


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--case", default="scaled", help="case file or preset name in cases/")
    p.add_argument(
        "--set", action="append", default=[], metavar="TABLE.KEY=VALUE", help="case override"
    )
    p.add_argument("--output", default="output/installation_run", help="output folder of the run")
    p.add_argument("--resume", action="store_true", help="continue from the checkpoint in --output")
    a = p.parse_args(argv)
    comm = MPI.COMM_WORLD
    t0 = time.perf_counter()
    try:
        case = InstallationCase.from_dict(read_case(a.case, a.set))
    except ValueError as e:
        return cli.fail(comm, str(e))
    timer = PhaseTimer()
    profile = StageProfile(comm, timer)
    runner = Installation(comm, case, a.output, progress=False, on_stage=profile)
    stopped = ""
    try:
        with recording(timer):
            runner.run(resume=a.resume)
    except ValueError as e:  # --resume without a checkpoint, or with one of another case
        return cli.fail(comm, str(e))
    except RuntimeError as e:  # Newton failed at the minimum step, or the band left the zone
        stopped = str(e)
    setup_s = runner.model.timings_s["set-up"] if runner.model is not None else 0.0
    profile.table(setup_s, time.perf_counter() - t0)
    if stopped:  # the table holds the stages before the stop
        profile.say(f"\nrun stopped: {stopped}")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
