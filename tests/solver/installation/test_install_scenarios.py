"""docs/physics.md §5 observations reproduced by the joint model: the atlas's S1, a two-stage S2,
the friction half of S6, S8 and the release of S5 (docs/scenarios.md), shortened, on the
default joint.

cases/suite.toml: the joint and contact solver of the default run (cases/scaled.toml: 48
elements around, 80 mm axially, 10 mm axially in the contact zone, P2, its ten lowest
frequencies within 3 % of the converged ones) and its outer Newton tolerance (1e-5), with mu
lagged by a step (cases/scaled_lagged.toml),
an 80 mm contact zone and the self-weight of
10 kN ramped over 1 s (half the §3 ramp time) in 10 ms steps, which resolve the TP's axial
oscillation on the wedge so that the TP moves in stick-slip steps rather than sliding steadily.

* §5.1: under the slowly increasing axial load the TP settles in stick-slip steps: several
  stick -> slip transitions of the TP as a whole (solver.post.report.stick_slip_events), with
  intervals at rest in between.
* §5.6 (first half): lower friction (mu_s/mu_d = 0.0625/0.05) settles more under the same load
  than the reference friction (0.5/0.4), compared at a quarter of the ramp.
* §5.8: the natural frequencies of the settled joint (contact tangent of the current contact
  set, solver.installation.model.settled_modes) rise with settlement: the lowest modes at the
  end of the ramp lie above those at half the load.
* §5.2 (the atlas's S2 in its two-stage form, benchmarks/atlas/selectivity.py): from the
  settled joint, a lead-in at the control frequency, then the control and the best-ranked mode
  for the same time each; the mode settles at least 5 times as fast over its second half
  (three stages of 0.05 s, each with its own set-up of the contact solver: the file's most
  costly test; ``mpirun -n 2 python -m mpi4py -m pytest -s --durations=0`` on this file
  prints the times).
* §5.5 (the atlas's S5, benchmarks/atlas/dismount.py, its modal branch): from the settled
  joint, a pull between the rigid Coulomb pull-out forces with mu_d and with mu_s minus the
  amplitude holds alone; the pull plus 3.6 kN at the best-ranked mode releases the TP. (The
  peak force is above the pull-out force with mu_s; whether the release is selective, the
  atlas's S5 measures with the control as well.)

The fixture's end-of-ramp modal analysis is the installation run's
(``benchmarks.atlas.settled.choose``: the case's 20 modes and the frequency choice), and its
state is kept, so that the S2 and S5 tests start from it in any order.
"""

from pathlib import Path
from typing import NamedTuple

import numpy as np
import pytest
from mpi4py import MPI

from benchmarks.atlas.dismount import dismount_branches
from benchmarks.atlas.selectivity import selectivity_branches, selectivity_ratio
from benchmarks.atlas.stepping import joint_state
from benchmarks.atlas.settled import SettledJoint, choose
from common.case import read_case
from solver.dynamics.time_loop import run
from solver.installation import checkpoint
from solver.installation.dismount import pull_out_force
from solver.installation.case import InstallationCase
from solver.installation.model import JointModel, set_up_joint_model, settled_modes
from solver.post.report import SELECTIVE, stick_slip_events

# on 2 ranks only: the physics each verdict judges does not depend on the ranks, and the serial
# twin of these runs would double the suite's longest file (docs/install.md, design decisions)
pytestmark = [pytest.mark.mpi, pytest.mark.parallel_only]

LOW_FRICTION = ["friction.mu_s=0.0625", "friction.mu_d=0.05"]
N_MODES = 6
LEAD_IN = BRANCH = 0.05  #: the two-stage S2's lead-in and branches [s]
DISMOUNT_S = 0.05  #: S5: the pull's ramp and its hold, and the longest pull + vibration [s]


def _self_weight(
    overrides: list[str], modes_at: tuple[float, ...] = (), end: float = 1.0
) -> tuple[np.ndarray, list[np.ndarray], JointModel]:
    """Run the self-weight ramp up to ``end`` (fraction of the ramp); return the history
    (time [s], settlement [mm]), the settled joint's N_MODES lowest frequencies [Hz] at the
    times ``modes_at`` (fractions of the ramp) and the joint."""
    case = InstallationCase.from_dict(read_case("suite", overrides))
    model = set_up_joint_model(MPI.COMM_WORLD, case)
    sw = case.self_weight
    history = []

    def observe(problem):
        history.append((problem.t, model.settlement(problem)["settlement_mm"]))
        return {}

    frequencies = []
    for fraction in sorted({*modes_at, end}):
        run(model.problem, fraction * sw.duration_s, sw.dt_s, observers=[observe], progress=False)
        if fraction in modes_at:
            frequencies.append(settled_modes(model, N_MODES)[0].frequencies_hz)
    return np.array(history), frequencies, model


class Reference(NamedTuple):
    history: np.ndarray  #: (time [s], settlement [mm]) rows of the ramp
    half_load: np.ndarray  #: the N_MODES lowest frequencies at half the load [Hz]
    settled: SettledJoint  #: at the end of the ramp, its modes and the frequency choice
    saved: Path  #: the state at the end of the ramp (solver.installation.checkpoint)


@pytest.fixture(scope="module")
def reference(shared_dir) -> Reference:
    history, (half_load,), model = _self_weight([], modes_at=(0.5,))
    saved = shared_dir("end_of_ramp")
    checkpoint.save(saved, model.problem, {})
    return Reference(history, half_load, choose(model), saved)


def _end_of_ramp(reference: Reference) -> SettledJoint:
    """The joint put back at the end of the ramp: its state, the self-weight load and scheme."""
    model = reference.settled.model
    case, problem = model.case, model.problem
    problem.load.static_axial = case.static_force.history(case.self_weight)
    problem.load.schedule = problem.load.shaker = None
    checkpoint.restore(reference.saved, problem)
    problem.set_scheme(case.self_weight_scheme())
    problem.reset_operator()
    return reference.settled


def test_stick_slip_settlement_under_slowly_increasing_load(reference):
    t, s = reference.history.T
    events = stick_slip_events(t, s, 0.0, 0.0, 1, slip_rate_mm_s=1.0)
    rate = np.diff(np.r_[0.0, s]) / np.diff(np.r_[0.0, t])
    at_rest = np.mean(np.abs(rate[t > 0.2]) < 0.1)  # mm/s, after the landing
    print(
        f"\nself-weight: settlement {s[-1]:.3f} mm, {events} stick-slip events, "
        f"at rest {100 * at_rest:.0f} % of the steps after 0.2 s"
    )
    assert s[-1] > 0.5  # mm: the 10 kN push settles the TP
    assert events >= 3
    assert at_rest > 0.2
    assert np.all(np.diff(s[t > 0.2]) > -0.01)  # mm: the TP does not climb back


def test_lower_friction_settles_more(reference):
    """Up to a quarter of the ramp (2.5 kN): with mu = 0.0625/0.05 the TP slides on until the
    wedge alone nearly carries the load, so it settles several times more."""
    low, _, _ = _self_weight(LOW_FRICTION, end=0.25)
    t, s_low = low[-1]
    s_ref = np.interp(t, *reference.history.T)
    print(
        f"\nsettlement at {t:.2f} s (2.5 kN): mu 0.5/0.4 {s_ref:.3f} mm, mu 0.0625/0.05 {s_low:.3f} mm"
    )
    assert t == pytest.approx(0.25)
    assert s_low > 2.0 * s_ref > 0


def test_natural_frequencies_rise_with_settlement(reference):
    """Modes of the settled joint at 5 kN and at 10 kN (contact set tied): the contact band
    grows with settlement, so every one of the lowest modes stiffens."""
    f_half, f_end = reference.half_load, reference.settled.frequencies_hz[:N_MODES]
    print(f"\nfrequencies [Hz] at 5 kN {np.round(f_half, 2)}, at 10 kN {np.round(f_end, 2)}")
    assert np.all(f_end > f_half)


def test_modal_stage_settles_faster_than_the_control(reference, shared_dir):
    """The two-stage S2 from the end of the ramp: lead-in, control and mode at 3.6 kN."""
    r = selectivity_branches(_end_of_ramp(reference), shared_dir("selectivity"), LEAD_IN, BRANCH)
    modal, control = r["branches"]["modal"], r["branches"]["control"]
    ratio = selectivity_ratio(modal["rows"], control["rows"])
    print(
        f"\nmode {modal['frequency_Hz']:.2f} Hz (driven at {modal['forcing_Hz']:.2f} Hz) against "
        f"the control {control['frequency_Hz']:.2f} Hz: {ratio:.1f} x over the second half"
    )
    assert ratio >= SELECTIVE


def test_pull_alone_holds_pull_plus_vibration_at_the_mode_releases(reference, shared_dir):
    """The atlas's S5 (benchmarks/atlas/dismount.py) from the end of the ramp, its modal branch
    at the case's amplitude A = 3.6 kN: a pull P between the rigid Coulomb pull-out forces with
    mu_d and with mu_s minus A holds alone for DISMOUNT_S; P plus A at the best-ranked mode
    releases the TP within DISMOUNT_S (above its first-contact position, separated or lifting
    faster than the event threshold)."""
    joint = _end_of_ramp(reference)
    model = joint.model
    case = model.case
    _, _, n0 = joint_state(model)
    alpha, amplitude = case.joint.mp.half_angle, case.vibration.amplitude_N
    holds, frees = (
        pull_out_force(n0, mu, alpha) for mu in (case.friction.mu_d, case.friction.mu_s)
    )
    assert frees - holds < amplitude  # a pull P in between exists: P < holds, P + A > frees
    pull = 0.5 * (holds + frees - amplitude)
    factor = pull / abs(case.self_weight.force_N)
    r = dismount_branches(
        model,
        joint.chosen,
        list(joint.frequencies_hz),
        shared_dir("dismount"),
        (factor,),
        amplitude,
        DISMOUNT_S,
        vibrated=("modal",),
    )
    alone, modal = r["branches"][f"pull {factor:g} x"], r["branches"]["modal"]
    (t0, s0, _), (t1, s1, n1), (t2, s2, n2) = alone["rows"][0], alone["rows"][-1], modal["rows"][-1]
    print(
        f"\ndismount: normal force {n0 / 1e3:.2f} kN, pull-out {holds / 1e3:.2f} / "
        f"{frees / 1e3:.2f} kN (mu_d / mu_s); pull {pull / 1e3:.2f} kN alone: TP up "
        f"{s0 - s1:+.4f} mm in {t1 - t0:.3f} s, normal force {n1 / 1e3:.2f} kN; + {amplitude:.0f} N "
        f"at {modal['frequency_Hz']:.2f} Hz (driven at {modal['forcing_Hz']:.2f} Hz) for "
        f"{t2 - t1:.4f} s: settlement {s2:+.4f} mm, normal force {n2 / 1e3:.2f} kN"
    )
    assert not alone["released"] and s0 - s1 < 1.0 and n1 > 0.5 * n0  # mm; the contact holds
    assert modal["released"]
