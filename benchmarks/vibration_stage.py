"""Cost of one vibration stage of the installation run, step by step, from the settled joint.

Sets up the case's joint, settles it under the self-weight stage (ramp and hold with the case's
settings) or restores that state from ``--checkpoint`` (written there on the first run), or
starts from the installed state of an installation run (``--installed RUN``; with ``--stage N``
the state that run kept after its stage N), then
runs ``--steps`` steps of a stage at ``--frequency`` with the case's forcing, direction and
vibration scheme and the amplitude ``--amplitude`` (N, or "eccentric": the motors' 0.3632 f^2 N).
A restored state must have been written with the same case and overrides (``--set``);
``--stage-set`` overrides apply to the stage only, from a settled state of ``--checkpoint``
(e.g. the step or the friction law of the stage, for a convergence study). Prints per step the wall time, Newton
and GMRES iterations, factorisations and the residual norms of the Newton iterations; then the
mean per step, its ratio to one triangular solve with the zone's factors and the phase
breakdown (``benchmarks/phase_timer.py``).

    mpirun -n 2 python benchmarks/vibration_stage.py --case scaled --steps 12
    mpirun -n 2 python benchmarks/vibration_stage.py --case scaled --set self_weight.scheme=\\"generalised-alpha\\" \\
        --set self_weight.rho_inf=0 --checkpoint output/settled_scaled_rho0
    mpirun -n 2 python benchmarks/vibration_stage.py --frequency 320.91 --amplitude 3600 \\
        --steps 12 --installed output/install
    mpirun -n 2 python benchmarks/vibration_stage.py --frequency 149.63 --amplitude 3600 \\
        --steps 240 --installed output/install --stage 3   # run with output.stage_states=true
    mpirun -n 2 python benchmarks/vibration_stage.py --steps 224 --checkpoint output/settled \\
        --stage-set time.steps_per_period=32
"""

import argparse
import sys
import time
from pathlib import Path

from common import backend  # noqa: F401

import numpy as np
from mpi4py import MPI

from benchmarks.atlas.installed import restore_installed
from benchmarks.phase_timer import PhaseTimer
from common.case import read_case
from common.timing import recording
from solver.dynamics.loads import Schedule
from solver.dynamics.time_loop import run
from solver.installation import checkpoint, cli
from solver.installation.case import InstallationCase
from solver.installation.model import attach_vibration, set_up_joint_model


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--case", default="scaled", help="case file or preset name in cases/")
    p.add_argument(
        "--set", action="append", default=[], metavar="TABLE.KEY=VALUE", help="case override"
    )
    p.add_argument(
        "--stage-set",
        action="append",
        default=[],
        metavar="TABLE.KEY=VALUE",
        help="case override of the stage only (e.g. time.steps_per_period, "
        "contact.lagged_friction): the settled state of --checkpoint or --installed is the "
        "one of --set",
    )
    p.add_argument("--frequency", type=float, default=68.0, help="forcing frequency [Hz]")
    p.add_argument("--amplitude", default="eccentric", help='force amplitude [N] or "eccentric"')
    p.add_argument("--steps", type=int, default=16, help="time steps of the stage")
    p.add_argument(
        "--checkpoint",
        default=None,
        help="folder of the settled state: restored if it exists, else written after settling "
        "(without --installed, --stage-set needs it to exist)",
    )
    p.add_argument(
        "--installed",
        type=Path,
        metavar="RUN",
        help="start from the last checkpoint of a demos/install.py run of the case instead",
    )
    p.add_argument(
        "--stage",
        type=int,
        metavar="N",
        help="with --installed: start from the state that run kept after its stage N (a run "
        "with --set output.stage_states=true; 0: the self-weight stage)",
    )
    a = p.parse_args(argv)
    if not (a.frequency > 0 and a.steps > 0):
        p.error("--frequency and --steps must be positive")
    if a.stage is not None and a.installed is None:
        p.error("--stage needs --installed")
    if a.stage_set and a.installed is None and not (a.checkpoint and Path(a.checkpoint).exists()):
        p.error("--stage-set needs --installed or the settled state of an existing --checkpoint")
    try:
        amplitude = cli.amplitude(a.amplitude)
    except ValueError as err:
        p.error(str(err))
    comm = MPI.COMM_WORLD
    say = cli.say(comm)
    try:
        case = InstallationCase.from_dict(read_case(a.case, a.set + a.stage_set))
    except (ValueError, FileNotFoundError) as err:
        p.error(str(err))
    if a.installed is not None:
        try:
            model = restore_installed(comm, a.case, a.set, a.installed, a.stage, a.stage_set)[0]
        except (ValueError, FileNotFoundError) as err:
            p.error(str(err))
    else:
        model = set_up_joint_model(comm, case)
    problem = model.problem
    per_rank = comm.allgather(model.contact.slave.num_points)
    say(
        f"{a.case}: {model.n_dofs} dofs, {sum(per_rank)} slave points (per rank {per_rank}), "
        f"{model.contact.master.num_facets} master facets, {comm.size} rank(s) "
        f"({case.mesh.partition} partition)"
    )
    record = {"case": a.case, "overrides": a.set}
    if a.installed is not None:
        kept = "" if a.stage is None else f", after its stage {a.stage}"
        say(f"installed state restored from {a.installed}{kept} (t = {problem.t:.3f} s)")
    elif a.checkpoint is not None and checkpoint.exists(a.checkpoint, comm):
        saved = checkpoint.read_manifest(a.checkpoint, comm)
        if {key: saved.get(key) for key in record} != record:
            p.error(
                f"{a.checkpoint} holds a state of --case {saved.get('case')} with --set {saved.get('overrides')}"
            )
        checkpoint.restore(a.checkpoint, problem)
        say(f"settled state restored from {a.checkpoint} (t = {problem.t:.3f} s)")
    else:
        t0 = time.perf_counter()
        model.run_self_weight()
        say(f"self-weight stage: {time.perf_counter() - t0:.1f} s")
        if a.checkpoint is not None:
            checkpoint.save(a.checkpoint, problem, record)
    settled = model.settlement(problem)["settlement_mm"]
    dt = 1.0 / (a.frequency * case.time.steps_per_period)
    stage = case.vibration.stage(a.steps * dt, a.frequency, amplitude)
    attach_vibration(model, Schedule([stage], start_s=problem.t))
    problem.set_scheme(case.vibration_scheme())
    say(
        f"settlement {settled:.4f} mm; {a.frequency} Hz, amplitude {amplitude}, "
        f"{case.vibration.forcing} forcing, dt = {dt:.3e} s",
    )
    cuts = problem.failed_steps
    timer = PhaseTimer()
    last = [time.perf_counter(), 0, 0]
    newton = []

    def log(problem) -> dict:
        now = time.perf_counter()
        gmres, factorisations = timer.gmres, timer.calls["factorisation"]
        result = problem.last_result
        newton.append(result.iterations)
        say(
            f"  t = {problem.t:.6f} s: {now - last[0]:6.2f} s, Newton {result.iterations}, "
            f"GMRES {gmres - last[1]}, factorisations {factorisations - last[2]}, settlement "
            f"{model.settlement(problem)['settlement_mm']:.5f} mm; ||F|| [N] "
            + " ".join(f"{r:.1e}" for r in result.residual_norms),
        )
        last[:] = [now, gmres, factorisations]
        return {}

    t0 = time.perf_counter()
    with recording(timer):
        rows = run(problem, problem.t + a.steps * dt, dt, observers=[log], progress=False)
    wall = time.perf_counter() - t0
    say(
        f"{len(rows)} steps: {wall / len(rows):.3f} s/step, Newton {np.mean(newton):.2f}/step, "
        f"GMRES {timer.gmres / len(rows):.1f}/step, {timer.calls['factorisation']} "
        f"factorisations, {problem.failed_steps - cuts} step cuts; one triangular solve "
        f"{1e3 * timer.triangular_solve_s():.1f} ms, step / solve = "
        f"{wall / len(rows) / timer.triangular_solve_s():.0f}"
    )
    timer.report(comm, len(rows), int(sum(newton)), say)
    return 0


if __name__ == "__main__":
    sys.exit(main())
