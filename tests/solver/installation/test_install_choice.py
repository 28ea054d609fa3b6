"""Choice of the excitation frequencies from a mode ranking (no finite elements involved)."""

import numpy as np
import pytest

from solver.installation.frequencies import choose_frequencies
from solver.installation.settings import VibrationSettings
from solver.modal.indicators import resonant_slip
from solver.modal.ranking import ModeRecord

pytestmark = pytest.mark.mpi


def _record(mode: int, f: float, m: int, n: int, rank: int) -> ModeRecord:
    return ModeRecord(
        mode, f, m, n, "TP", m, n, m, n, 1.0, 1.0, 0, 0, 0, 0, 0, 1.0 / rank, 0.0, rank
    )


# the experiments' modes (docs/physics.md §5.9) with a made-up ranking; 86 Hz is a degenerate pair whose
# partners rank differently (the forcing point excites one of them, as on the joint)
RECORDS = [
    _record(1, 50.0, 1, 0, 3),
    _record(2, 86.0, 3, 0, 2),
    _record(3, 86.4, 3, 0, 6),
    _record(4, 106.0, 4, 0, 4),
    _record(5, 120.0, 2, 1, 5),
    _record(6, 150.0, 1, 1, 1),
    _record(7, 400.0, 2, 2, 1),
]


def test_best_ranks_plus_m2n1_plus_control():
    chosen = choose_frequencies(RECORDS, VibrationSettings(n_frequencies=2, max_frequency_hz=300.0))
    roles = [e.role for e in chosen]
    assert roles[:2] == ["lead-in", "lead-in"] and [e.frequency_Hz for e in chosen[:2]] == [
        68.0,
        100.0,
    ]
    modal = [e for e in chosen if e.role == "modal"]
    # ranks 1 and 2 below 300 Hz (400 Hz excluded; the 86 Hz pair counted once), then (2, 1)
    assert sorted(e.frequency_Hz for e in modal) == [86.0, 120.0, 150.0]
    assert "m = 2, n = 1" in next(e for e in modal if e.frequency_Hz == 120.0).reason
    (control,) = [e for e in chosen if e.role == "control"]
    assert all(e.frequency_Hz != 86.4 for e in chosen)
    # the point of [86 / 2, 150] farthest in ratio from all natural and lead-in frequencies: the
    # geometric mean of 50 Hz and the 68 Hz lead-in (a factor 1.166 from both; 43 Hz is 1.163
    # from 50 Hz, the gap between 120 and 150 Hz 1.118 from either side)
    assert control.frequency_Hz == pytest.approx(np.sqrt(50.0 * 68.0), abs=0.05)
    assert "a factor 1.17 from the nearest natural frequency (50.0 Hz)" in control.reason
    # without a lead-in: the geometric mean of 50 and 86 Hz (a factor 1.311 from both)
    alone = choose_frequencies(
        RECORDS, VibrationSettings(n_frequencies=2, max_frequency_hz=300.0, lead_in_hz=())
    )
    (control,) = [e for e in alone if e.role == "control"]
    assert control.frequency_Hz == pytest.approx(np.sqrt(50.0 * 86.0), abs=0.05)
    assert "a factor 1.31 " in control.reason
    assert all(e.amplitude_N == 3600.0 for e in chosen if e.role != "lead-in")
    assert all(e.reason for e in chosen)


def test_single_frequency_control_stays_below_the_limit():
    records = [_record(1, 233.0, 0, 0, 1)]
    chosen = choose_frequencies(
        records, VibrationSettings(n_frequencies=1, lead_in_hz=(), max_frequency_hz=300.0)
    )
    control = next(e for e in chosen if e.role == "control")
    # [233 / 2, 300]: an octave below the mode beats 300 Hz (a factor 1.29 above it)
    assert control.frequency_Hz == pytest.approx(0.5 * 233.0)
    assert [e.role for e in chosen] == ["control", "modal"]  # increasing frequency


def test_pair_partner_is_not_a_second_frequency():
    """The joint's case: one pair partner ranks high, the other (orthogonal to the forcing)
    low; only one of them is excited, and the control is not squeezed between them."""
    records = [
        _record(1, 138.27, 1, 0, 8),
        _record(2, 140.48, 1, 0, 17),
        _record(3, 337.4, 1, 0, 3),
    ]
    chosen = choose_frequencies(
        records, VibrationSettings(n_frequencies=3, lead_in_hz=(), max_frequency_hz=300.0)
    )
    assert [e.frequency_Hz for e in chosen if e.role == "modal"] == [138.27]
    control = next(e for e in chosen if e.role == "control")
    assert control.frequency_Hz == pytest.approx(0.5 * 138.27)  # not between 138.27 and 140.48


def test_rigid_body_modes_are_not_excited():
    """A TP the contact does not hold has ~0 Hz modes with unbounded resonant slip (rank 1):
    they are not excitation frequencies."""
    records = [_record(1, 0.0, 1, 0, 1), _record(2, 1e-3, 1, 0, 2), _record(3, 140.0, 1, 0, 3)]
    chosen = choose_frequencies(
        records, VibrationSettings(n_frequencies=1, lead_in_hz=(), max_frequency_hz=300.0)
    )
    assert [e.frequency_Hz for e in chosen if e.role == "modal"] == [140.0]
    # an undamped mode: infinite resonant slip, no division by zero
    assert resonant_slip(0.1, 1e-3, 0.0, 3600.0, 0.01) == np.inf


def test_m2n1_mode_is_added_above_the_limit():
    """docs/physics.md §5.4: the lowest (2, 1) mode is excited even above max_frequency_hz (on a coarse,
    stiff mesh it lies far above the ranked modes), unless m2n1_mode is false; the control
    then lies in the octave below the lowest mode, not between the dense higher modes."""
    records = [
        _record(1, 142.0, 1, 0, 4),
        _record(2, 352.0, 1, 0, 1),
        _record(3, 380.0, 2, 0, 2),
        _record(4, 487.0, 2, 1, 3),
        _record(5, 487.1, 2, 1, 5),
    ]
    chosen = choose_frequencies(
        records, VibrationSettings(n_frequencies=1, lead_in_hz=(), max_frequency_hz=300.0)
    )
    assert [(e.role, e.frequency_Hz) for e in chosen] == [
        ("control", pytest.approx(71.0)),
        ("modal", 142.0),
        ("modal", 487.0),
    ]
    assert "above the ranked choice's 300 Hz" in chosen[-1].reason
    without = choose_frequencies(
        records,
        VibrationSettings(n_frequencies=1, lead_in_hz=(), max_frequency_hz=300.0, m2n1_mode=False),
    )
    assert [e.frequency_Hz for e in without if e.role == "modal"] == [142.0]


@pytest.mark.parametrize("name", ["m2n1_mode", "control", "modal_stage"])
def test_switches_must_be_booleans(name):
    with pytest.raises(ValueError, match=f"{name} must be true or false"):
        VibrationSettings(**{name: "yes"})
