"""docs/physics.md §5 observations reproduced by the joint model: scenario tests on a coarse joint.

cases/scenario.toml: the coarse joint of cases/coarse.toml (8 elements around, 0.25 m axially,
10 mm axially in the contact zone, P2) with the self-weight of 10 kN ramped over 1 s (half the
§3 ramp time) in 10 ms steps, which resolve the TP's axial oscillation on the wedge (about
24 Hz) so that the TP moves in stick-slip steps rather than sliding steadily.

* §5.1: under the slowly increasing axial load the TP settles in stick-slip steps: several
  stick -> slip transitions of the TP as a whole (solver.post.report.stick_slip_events), with
  intervals at rest in between.
* §5.6 (first half): lower friction (mu_s/mu_d = 0.0625/0.05) settles more under the same load
  than the reference friction (0.5/0.4), compared at a quarter of the ramp.
* §5.8: the natural frequencies of the settled joint (contact tangent of the current contact
  set, solver.installation.model.settled_modes) rise with settlement: the lowest modes at the
  end of the ramp lie above those at half the load.

The vibration scenarios are test_install_vibration.py (§5.2, 5.3, 5.6) and
test_install_dismount.py (§5.5, 5.7); docs/install.md reports their measured outcome.
"""

import numpy as np
import pytest
from mpi4py import MPI

from common.case import read_case
from solver.dynamics.time_loop import run
from solver.installation.case import InstallationCase
from solver.installation.model import set_up_joint_model, settled_modes
from solver.post.report import stick_slip_events

pytestmark = pytest.mark.mpi

LOW_FRICTION = ["friction.mu_s=0.0625", "friction.mu_d=0.05"]
N_MODES = 6


def _self_weight(overrides: list[str], modes_at: tuple[float, ...] = (), end: float = 1.0):
    """Run the self-weight ramp up to ``end`` (fraction of the ramp); return the history
    (time [s], settlement [mm]) and the settled joint's frequencies [Hz] at the times
    ``modes_at`` (fractions of the ramp)."""
    case = InstallationCase.from_dict(read_case("scenario", overrides))
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
    return np.array(history), frequencies


@pytest.fixture(scope="module")
def reference():
    return _self_weight([], modes_at=(0.5, 1.0))


def test_stick_slip_settlement_under_slowly_increasing_load(reference):
    (history, _) = reference
    t, s = history.T
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
    (history, _) = reference
    low, _ = _self_weight(LOW_FRICTION, end=0.25)
    t, s_low = low[-1]
    s_ref = np.interp(t, *history.T)
    print(
        f"\nsettlement at {t:.2f} s (2.5 kN): mu 0.5/0.4 {s_ref:.3f} mm, mu 0.0625/0.05 {s_low:.3f} mm"
    )
    assert t == pytest.approx(0.25)
    assert s_low > 2.0 * s_ref > 0


def test_natural_frequencies_rise_with_settlement(reference):
    """Modes of the settled joint at 5 kN and at 10 kN (contact set tied): the contact band
    grows with settlement, so every one of the lowest modes stiffens."""
    (_, (f_half, f_end)) = reference
    print(f"\nfrequencies [Hz] at 5 kN {np.round(f_half, 2)}, at 10 kN {np.round(f_end, 2)}")
    assert np.all(f_end > f_half)
