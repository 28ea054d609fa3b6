"""docs/physics.md §5 vibration scenarios on the joint: frequency- against amplitude-driven settlement.

From one settled state the run branches (state saved with solver.installation.checkpoint):

1. self-weight stage of the case (10 kN ramp), then the modal stage of the settled joint
   (solver.installation.model.settled_modes, ranking by solver.modal.ranking.describe_modes) and
   the frequency choice of the installation run (choose_frequencies: best-ranked natural
   frequency f_r, non-modal control f_c);
2. lead-in: ``--lead-in`` s (rounded to whole periods) at f_c with the amplitude A
   (``--amplitude``): the quasi-static settlement that a force of amplitude A causes at any
   frequency (docs/physics.md §3 runs 68 and 100 Hz first for this reason). It must outlast the free
   vibration that switching the force on excites (decay time 1/(zeta omega) of the lowest
   mode, with the scheme's numerical damping about 0.04 s at 142 Hz): after it the joint
   holds A, so A lies below the off-resonance threshold of the next stages;
3. from the state after the lead-in, three branches of ``--duration`` s each:
   (a) f_r at A, (b) f_c at A, (c) f_c at ``--factor`` x A.

Printed and written to ``--output``/scenarios.csv (units in the header): the settlement
gained in each branch [mm] and the docs/physics.md §5 criteria: frequency-driven (a) >= 5 (b)
(docs/physics.md §5.2), amplitude-driven (c) > 5 (b) (5.3), stabilisation of each event: the last 20 %
of a stage adds less than 5 % of its gain (5.2).

    mpirun -n 2 python benchmarks/branches.py                       # cases/coarse.toml
    python benchmarks/branches.py --set mesh.n_circumferential=16 --duration 0.1

The functions are shared with tests/solver/installation/test_install_vibration.py,
tests/solver/installation/test_install_scenarios.py (``choose``) and benchmarks/atlas/.
"""

import argparse
import csv
import pathlib
import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass

from common import backend  # noqa: F401

import numpy as np
from mpi4py import MPI

from common.case import read_case
from solver.dynamics.loads import Schedule, Stage
from solver.dynamics.time_loop import Observer, run
from solver.installation import checkpoint
from solver.installation.case import InstallationCase
from solver.installation.frequencies import Excitation, choose_frequencies
from solver.installation.model import (
    JointModel,
    attach_vibration,
    set_up_joint_model,
    settled_modes,
)
from solver.modal.ranking import JointParts, describe_modes
from solver.post import report


@dataclass
class SettledJoint:
    """The joint after its self-weight stage and the frequencies chosen from its modes [Hz]."""

    model: JointModel
    f_r: float  #: best-ranked natural frequency [Hz]
    f_c: float  #: non-modal control frequency [Hz]
    frequencies_hz: np.ndarray  #: natural frequencies of the settled joint [Hz]
    chosen: list[Excitation]  #: the installation run's frequency choice


def settle(comm: MPI.Comm, overrides: list[str], case_name: str = "coarse") -> SettledJoint:
    """Build the joint of the case with ``overrides``, run its self-weight stage and choose
    f_r and f_c as the installation run does (collective)."""
    case = InstallationCase.from_dict(read_case(case_name, overrides))
    model = set_up_joint_model(comm, case)
    sw = case.self_weight
    run(model.problem, sw.duration_s, sw.dt_s, progress=False)
    return choose(model)


def choose(model: JointModel) -> SettledJoint:
    """The modes of the joint in its present state (``vibration.n_modes``) and f_r and f_c
    chosen from them as the installation run does (collective)."""
    case = model.case
    result, _ = settled_modes(model, case.vibration.n_modes)
    parts = JointParts.for_joint(model.V, model.mesh_data, model.placed)
    records = describe_modes(
        result,
        case.material,
        parts,
        zeta=case.damping.zeta,
        m_max=min(12, (2 * case.mesh.n_circumferential - 1) // 2),
    )
    chosen = choose_frequencies(records, case.vibration)
    f_r = next(e.frequency_Hz for e in sorted(chosen, key=lambda e: e.rank) if e.role == "modal")
    f_c = next(e.frequency_Hz for e in chosen if e.role == "control")
    return SettledJoint(model, f_r, f_c, result.frequencies_hz, chosen)


def harmonic_stage(
    model: JointModel,
    frequency: float,
    amplitude: float,
    duration: float,
    observers: Sequence[Observer] = (),
) -> np.ndarray:
    """Run one harmonic stage (``frequency`` [Hz], ``amplitude`` [N], ``duration`` [s]) from
    the current state, ``time.steps_per_period`` steps per period, calling ``observers`` too
    after each step; (time [s], settlement [mm]) rows from the stage start."""
    problem = model.problem
    t0 = problem.t
    attach_vibration(model, Schedule([Stage(duration, frequency, amplitude)], start_s=t0))
    rows = [(t0, model.settlement(problem)["settlement_mm"])]

    def observe(pr) -> dict:
        rows.append((pr.t, model.settlement(pr)["settlement_mm"]))
        return {}

    dt = 1.0 / (frequency * model.case.time.steps_per_period)
    n_steps = max(1, round(duration / dt))
    run(problem, t0 + duration, duration / n_steps, observers=[observe, *observers], progress=False)
    return np.array(rows)


def gain(history: np.ndarray) -> float:
    """Settlement gained over a stage [mm]."""
    return float(history[-1, 1] - history[0, 1])


def late_gain(history: np.ndarray, fraction: float = report.LATE) -> float:
    """Settlement gained over the last ``fraction`` of a stage [mm]."""
    return report.late_gain(*history.T, fraction)


def stabilised(history: np.ndarray) -> bool:
    """docs/physics.md §5.2: the stage settled, and its last 20 % added less than 5 % of its gain."""
    return report.stabilised(gain(history), late_gain(history))


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument(
        "--case", default="coarse", help="case: a preset name or a TOML file (default: coarse)"
    )
    p.add_argument("--set", action="append", default=[], metavar="TABLE.KEY=VALUE")
    p.add_argument("--amplitude", type=float, default=3600.0, help="force amplitude A [N]")
    p.add_argument("--factor", type=float, default=2.0, help="amplitude factor of branch (c)")
    p.add_argument("--lead-in", type=float, default=0.2, help="lead-in duration [s]")
    p.add_argument("--duration", type=float, default=0.15, help="branch duration [s]")
    p.add_argument("--output", default="output/scenarios")
    a = p.parse_args(argv)
    comm = MPI.COMM_WORLD
    say = print if comm.rank == 0 else (lambda *args, **kw: None)
    out = pathlib.Path(a.output)
    wall = time.perf_counter()
    joint = settle(comm, a.set, a.case)
    model, f_r, f_c = joint.model, joint.f_r, joint.f_c
    problem = model.problem
    say(f"joint: {model.n_dofs} dofs, {comm.size} rank(s)")
    say(
        f"self-weight: settlement {model.settlement(problem)['settlement_mm']:.4f} mm "
        f"({time.perf_counter() - wall:.0f} s)"
    )
    say(f"natural frequencies [Hz]: {np.round(joint.frequencies_hz, 2)}")
    say(f"ranked natural frequency f_r = {f_r:.2f} Hz, control f_c = {f_c:.2f} Hz")

    # whole periods: the force is zero where every branch starts (at phase 0)
    lead = harmonic_stage(model, f_c, a.amplitude, max(1, round(a.lead_in * f_c)) / f_c)
    say(
        f"lead-in at f_c, {a.amplitude:.0f} N: +{gain(lead):.4f} mm, "
        f"last 20 % +{late_gain(lead):.5f} mm"
    )
    branch_dir = out / "after_lead_in"
    checkpoint.save(branch_dir, problem, {})
    branches = {
        "a: f_r, A": (f_r, a.amplitude),
        "b: f_c, A": (f_c, a.amplitude),
        "c: f_c, factor A": (f_c, a.factor * a.amplitude),
    }
    histories = {}
    for name, (f, amp) in branches.items():
        checkpoint.restore(branch_dir, problem)
        problem.reset_operator()
        histories[name] = h = harmonic_stage(model, f, amp, a.duration)
        say(
            f"branch {name:18s} {f:8.2f} Hz {amp:7.0f} N: +{gain(h):.5f} mm, last 20 % "
            f"+{late_gain(h):.5f} mm ({time.perf_counter() - wall:.0f} s)"
        )

    gains = {name: gain(h) for name, h in histories.items()}
    b = max(gains["b: f_c, A"], 0.0)
    criteria = {
        "frequency-driven: gain(a) >= 5 gain(b)": gains["a: f_r, A"] >= 5 * b
        and gains["a: f_r, A"] > 0,
        "amplitude-driven: gain(c) > 5 gain(b)": gains["c: f_c, factor A"] > 5 * b
        and gains["c: f_c, factor A"] > 0,
        "stabilised: last 20 % of the lead-in < 5 % of its gain": stabilised(lead),
        "stabilised: last 20 % of (a) < 5 % of its gain": stabilised(histories["a: f_r, A"]),
        "stabilised: last 20 % of (c) < 5 % of its gain": stabilised(histories["c: f_c, factor A"]),
    }
    for text, ok in criteria.items():
        say(f"  {'yes' if ok else 'NO ':3s}  {text}")
    if comm.rank == 0:
        out.mkdir(parents=True, exist_ok=True)
        with open(out / "scenarios.csv", "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(
                [
                    "branch",
                    "frequency_Hz",
                    "amplitude_N",
                    "duration_s",
                    "gained_mm",
                    "last_20_percent_mm",
                ]
            )
            for name, (freq, amp) in branches.items():
                w.writerow(
                    [
                        name,
                        f"{freq:.4f}",
                        f"{amp:.1f}",
                        a.duration,
                        f"{gains[name]:.6g}",
                        f"{late_gain(histories[name]):.6g}",
                    ]
                )
    return 0


if __name__ == "__main__":
    sys.exit(main())
