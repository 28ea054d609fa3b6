"""SPEC 5 vibration scenarios on the joint: frequency- against amplitude-driven settlement.

From one settled state the run branches (state saved with solver.checkpoint):

1. self-weight stage of the case (10 kN ramp), then the modal stage of the settled joint
   (solver.installation.settled_modes, ranking by solver.modal_report.describe_modes) and
   the frequency choice of the installation run (choose_frequencies: best-ranked natural
   frequency f_r, non-modal control f_c);
2. lead-in: ``--lead-in`` s at f_c with the amplitude A (``--amplitude``): the quasi-static
   share of the settlement that a force of amplitude A causes at any frequency (SPEC 3 runs
   68 and 100 Hz first for this reason);
3. from the state after the lead-in, three branches of ``--duration`` s each:
   (a) f_r at A, (b) f_c at A, (c) f_c at ``--factor`` x A.

Printed and written to ``--output``/scenarios.csv (units in the header): the settlement
gained in each branch [mm] and the SPEC 5 criteria: frequency-driven (a) >= 5 (b)
(SPEC 5.2), amplitude-driven (c) > 5 (b) (5.3), stabilisation of (a): its last 20 % adds less
than 5 % of its gain (5.2).

    mpirun -n 2 python benchmarks/scenarios.py                       # coarse joint (as demos/install.py)
    python benchmarks/scenarios.py --set mesh.n_circumferential=16 --duration 0.1
"""

import argparse
import csv
import pathlib
import sys
import time

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent.parent))

from solver import backend  # noqa: E402,F401

import numpy as np  # noqa: E402
from mpi4py import MPI  # noqa: E402

from solver import checkpoint  # noqa: E402
from solver.case import read_case  # noqa: E402
from solver.dynamics import run  # noqa: E402
from solver.installation import (  # noqa: E402
    InstallationCase,
    attach_vibration,
    build_joint_model,
    choose_frequencies,
    settled_modes,
)
from solver.loads import Schedule, Stage  # noqa: E402
from solver.modal_report import JointParts, describe_modes  # noqa: E402
from solver.demo_cli import COARSE_FRICTIONAL  # noqa: E402  (the default run's joint and contact settings)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--case", default="scaled")
    p.add_argument("--set", action="append", default=[], metavar="TABLE.KEY=VALUE")
    p.add_argument("--amplitude", type=float, default=3600.0, help="force amplitude A [N]")
    p.add_argument("--factor", type=float, default=2.0, help="amplitude factor of branch (c)")
    p.add_argument("--lead-in", type=float, default=0.05, help="lead-in duration [s]")
    p.add_argument("--duration", type=float, default=0.05, help="branch duration [s]")
    p.add_argument("--output", default="output/scenarios")
    a = p.parse_args(argv)
    comm = MPI.COMM_WORLD
    say = print if comm.rank == 0 else (lambda *args, **kw: None)
    out = pathlib.Path(a.output)
    case = InstallationCase.from_dict(read_case(a.case, COARSE_FRICTIONAL + a.set))
    model = build_joint_model(comm, case)
    problem, sw, steps = model.problem, case.self_weight, case.time.steps_per_period
    say(f"joint: {model.n_dofs} dofs, {comm.size} rank(s)")

    def settlement() -> float:
        return model.settlement(problem)["settlement_mm"]

    def stage(frequency: float, amplitude: float, duration: float) -> np.ndarray:
        """Run one harmonic stage from the current state; (time [s], settlement [mm]) rows."""
        t0 = problem.t
        attach_vibration(model, Schedule([Stage(duration, frequency, amplitude)], start_s=t0))
        rows = [(t0, settlement())]

        def observe(pr) -> dict:
            rows.append((pr.t, settlement()))
            return {}

        dt = 1.0 / (frequency * steps)
        run(problem, t0 + duration, duration / max(1, round(duration / dt)), observers=[observe], progress=False)
        return np.array(rows)

    wall = time.perf_counter()
    run(problem, sw.duration_s, sw.dt_s, progress=False)
    s0 = settlement()
    say(f"self-weight: settlement {s0:.4f} mm ({time.perf_counter() - wall:.0f} s)")
    result, _ = settled_modes(model, case.vibration.n_modes)
    records = describe_modes(result, case.material, JointParts.for_joint(model.V, model.mesh_data, model.placed),
                             zeta=case.damping.zeta, m_max=min(12, (2 * case.mesh.n_circumferential - 1) // 2))
    chosen = choose_frequencies(records, case.vibration)
    f_r = next(e.frequency_Hz for e in sorted(chosen, key=lambda e: e.rank) if e.role == "modal")
    f_c = next(e.frequency_Hz for e in chosen if e.role == "control")
    say(f"natural frequencies [Hz]: {np.round(result.frequencies_hz, 2)}")
    say(f"ranked natural frequency f_r = {f_r:.2f} Hz, control f_c = {f_c:.2f} Hz")

    lead = stage(f_c, a.amplitude, a.lead_in)
    say(f"lead-in at f_c, {a.amplitude:.0f} N: +{lead[-1, 1] - lead[0, 1]:.4f} mm")
    branch_dir = out / "after_lead_in"
    checkpoint.save(branch_dir, problem, {})
    branches = {"a: f_r, A": (f_r, a.amplitude), "b: f_c, A": (f_c, a.amplitude),
                "c: f_c, factor A": (f_c, a.factor * a.amplitude)}
    gains, histories = {}, {}
    for name, (f, amp) in branches.items():
        checkpoint.restore(branch_dir, problem)
        problem.rebuild_solver()
        h = stage(f, amp, a.duration)
        histories[name] = h
        gains[name] = h[-1, 1] - h[0, 1]
        say(f"branch {name:18s} {f:8.2f} Hz {amp:7.0f} N: +{gains[name]:.5f} mm "
            f"({time.perf_counter() - wall:.0f} s)")

    h = histories["a: f_r, A"]
    late = h[-1, 1] - np.interp(h[0, 0] + 0.8 * a.duration, h[:, 0], h[:, 1])
    b = gains["b: f_c, A"]
    criteria = {
        "frequency-driven: gain(a) >= 5 gain(b)": gains["a: f_r, A"] >= 5 * max(b, 0.0) and gains["a: f_r, A"] > 0,
        "amplitude-driven: gain(c) > 5 gain(b)": gains["c: f_c, factor A"] > 5 * max(b, 0.0)
        and gains["c: f_c, factor A"] > 0,
        "stabilised: last 20 % of (a) < 5 % of its gain": abs(late) < 0.05 * abs(gains["a: f_r, A"]),
    }
    for text, ok in criteria.items():
        say(f"  {'yes' if ok else 'NO ':3s}  {text}")
    if comm.rank == 0:
        out.mkdir(parents=True, exist_ok=True)
        with open(out / "scenarios.csv", "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(["branch", "frequency_Hz", "amplitude_N", "duration_s", "gained_mm"])
            for name, (freq, amp) in branches.items():
                w.writerow([name, f"{freq:.4f}", f"{amp:.1f}", a.duration, f"{gains[name]:.6g}"])
    return 0


if __name__ == "__main__":
    sys.exit(main())
