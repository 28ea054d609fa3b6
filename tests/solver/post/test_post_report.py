"""The stage gains and frequency-selectivity lines of the installation summary (no finite
elements involved)."""

import numpy as np
import pytest

from solver.installation.frequencies import Excitation
from solver.installation.planning import StagePlan
from solver.post.report import (
    SELECTIVE,
    format_selectivity,
    format_stabilisation,
    format_summary,
    frequency_selectivity,
    late_gain,
    slip_episodes,
    stabilised,
    stage_summary,
    stick_slip_events,
    sustained_rate_mm_s,
)


def _stage(k: int, f: float, start: float, end: float, gained: float, second_half=None) -> dict:
    """A stage summary; without ``second_half`` the stage settles at a constant rate."""
    return {
        "stage": k,
        "frequency_Hz": f,
        "start_s": start,
        "end_s": end,
        "gained_mm": gained,
        "gained_second_half_mm": 0.5 * gained if second_half is None else second_half,
        "steps": 10,
    }


def _excitation(f: float, role: str, amplitude=3600.0) -> Excitation:
    return Excitation(f, amplitude, role, 0, 0, 0, 0, "")


def test_late_gain_interpolates_between_rows():
    t, s = np.array([0.0, 1.0, 2.0, 3.0, 4.0]), np.array([0.0, 1.0, 1.5, 1.5, 2.0])
    assert late_gain(t, s, 0.5) == pytest.approx(0.5)  # s(4) - s(2)
    assert late_gain(t, s, 0.2) == pytest.approx(0.4)  # s(4) - s(3.2) = 2 - 1.6
    assert late_gain(t, s, 1.0) == pytest.approx(2.0)


def test_stage_summary_gains_start_from_the_previous_stage():
    """The stage's gains count from the last row of the stages before it (2.0 s, 3.0 mm)."""
    history = [
        {"stage": 0, "time_s": 1.0, "settlement_mm": 2.5, "newton_iterations": 1},
        {"stage": 0, "time_s": 2.0, "settlement_mm": 3.0, "newton_iterations": 1},
    ]
    rows = [
        {"stage": 1, "time_s": 2.0 + 0.01 * k, "settlement_mm": s, "newton_iterations": 3}
        for k, s in enumerate([3.5, 3.6, 3.6, 3.6, 3.7], start=1)
    ]
    plan = StagePlan("vibration 1", 2.0, 2.05, 0.01, 100.0, 3600.0)
    s = stage_summary(1, plan, rows, history + rows, slip_rate_mm_s=1.0)
    assert s["gained_mm"] == pytest.approx(0.7)
    assert s["gained_second_half_mm"] == pytest.approx(0.1)  # s(2.05) - s(2.025) = 3.7 - 3.6
    assert s["gained_last_20pct_mm"] == pytest.approx(0.1)  # s(2.05) - s(2.04)


def test_sustained_rate_is_the_second_half_gain_over_its_duration():
    """0.02 mm over the second half (0.015 s) of a 0.03 s stage: 1.333 mm/s, whatever the first
    half gained."""
    s = _stage(1, 100.0, 2.1, 2.13, 0.6, second_half=0.02)
    assert sustained_rate_mm_s(s) == pytest.approx(0.02 / 0.015)


def test_rates_compare_stages_of_different_lengths():
    """Modal 0.05 mm in 0.03 s (1.667 mm/s) against control 0.01 mm in 0.06 s (0.1667 mm/s):
    10 x; a modal stage at another amplitude and the lead-in are not compared."""
    stages = [
        _stage(0, 0.0, 0.0, 2.0, 2.4),
        _stage(1, 68.0, 2.0, 2.1, 0.7),
        _stage(2, 300.0, 2.1, 2.13, 0.05),
        _stage(3, 450.0, 2.13, 2.19, 0.01),
        _stage(4, 500.0, 2.19, 2.22, 0.2),
    ]
    excitations = [
        _excitation(68.0, "lead-in", "eccentric"),
        _excitation(300.0, "modal"),
        _excitation(450.0, "control"),
        _excitation(500.0, "modal", 7200.0),
    ]
    rows = frequency_selectivity(stages, excitations)
    assert [r["frequency_Hz"] for r in rows] == [300.0]
    assert np.isclose(rows[0]["rate_mm_s"], 0.05 / 0.03)
    assert np.isclose(rows[0]["stage_rate_mm_s"], 0.05 / 0.03)
    assert np.isclose(rows[0]["control_rate_mm_s"], 0.01 / 0.06)
    assert np.isclose(rows[0]["ratio"], 10.0) and np.isclose(rows[0]["stage_ratio"], 10.0)
    lines = format_selectivity(rows)
    assert "shown by this run" in lines[0] and "NOT" not in lines[0]
    assert "10.00 x the control" in lines[-1]


def test_verdict_is_on_the_second_half_of_each_stage():
    """A coarse-joint run's stages: the control settles 33.95 um, all but 0.97 um of it
    in its first half (an event that stabilises), the modal stage 59.00 um, 38.32 um of it in
    its second half: 1.74 x over the whole stage, 39.5 x over the second half."""
    stages = [
        _stage(0, 0.0, 0.0, 2.0, 2.4),
        _stage(1, 70.98, 2.10, 2.15, 0.03395, 0.00097),
        _stage(2, 141.96, 2.15, 2.20, 0.05900, 0.03832),
    ]
    rows = frequency_selectivity(
        stages, [_excitation(70.98, "control"), _excitation(141.96, "modal")]
    )
    assert rows[0]["ratio"] == pytest.approx(0.03832 / 0.00097)
    assert rows[0]["stage_ratio"] == pytest.approx(0.05900 / 0.03395)
    assert rows[0]["control_rate_mm_s"] == pytest.approx(0.00097 / 0.025)
    lines = format_selectivity(rows)
    assert "shown by this run" in lines[0] and "NOT" not in lines[0]
    assert "39.51 x the control (whole stage +1.1800 mm/s = 1.74 x)" in lines[-1]


def test_a_control_that_settles_as_much_is_reported():
    stages = [
        _stage(0, 0.0, 0.0, 2.0, 2.4),
        _stage(1, 352.0, 2.0, 2.03, 0.0556),
        _stage(2, 451.0, 2.03, 2.06, 0.085),
        _stage(3, 487.0, 2.06, 2.09, 0.0926),
    ]
    excitations = [
        _excitation(352.0, "modal"),
        _excitation(451.0, "control"),
        _excitation(487.0, "modal"),
    ]
    rows = frequency_selectivity(stages, excitations)
    assert [round(r["ratio"], 3) for r in rows] == [
        round(0.0556 / 0.085, 3),
        round(0.0926 / 0.085, 3),
    ]
    assert all(r["ratio"] < SELECTIVE for r in rows)
    assert "NOT shown" in format_selectivity(rows)[0]


def test_nothing_settled_is_not_selectivity():
    """A control that did not settle makes a settling modal stage infinitely selective, and a
    modal stage that did not settle either not selective at all."""
    stages = [
        _stage(0, 0.0, 0.0, 2.0, 2.4),
        _stage(1, 352.0, 2.0, 2.03, 0.0),
        _stage(2, 451.0, 2.03, 2.06, 0.0),
        _stage(3, 487.0, 2.06, 2.09, 0.01),
    ]
    excitations = [
        _excitation(352.0, "modal"),
        _excitation(451.0, "control"),
        _excitation(487.0, "modal"),
    ]
    rows = frequency_selectivity(stages, excitations)
    assert [r["ratio"] for r in rows] == [0.0, np.inf]
    assert "NOT shown" in format_selectivity(rows)[0]


def test_no_control_no_lines():
    stages = [_stage(0, 0.0, 0.0, 2.0, 2.4), _stage(1, 352.0, 2.0, 2.03, 0.05)]
    assert frequency_selectivity(stages, [_excitation(352.0, "modal")]) == []
    assert format_selectivity([]) == []


def test_summary_of_a_run_without_vibration_stages():
    """A run of the self-weight stage alone (no excitation chosen) says so in its summary."""
    summary = {
        "total_settlement_mm": 2.4,
        "stick_slip_events": 3,
        "steps": 210,
        "end_time_s": 2.1,
        "normal_force_N": 2e4,
        "friction_force_z_N": 9e3,
        "stick_fraction": 0.5,
        "slip_fraction": 0.1,
        "open_fraction": 0.4,
    }
    stage = _stage(0, 0.0, 0.0, 2.1, 2.4) | {
        "name": "self-weight",
        "settlement_end_mm": 2.4,
        "stick_slip_events": 3,
        "newton_iterations_mean": 2.0,
    }
    text = format_summary(summary, [stage], [])
    assert "excitation frequencies: none" in text.splitlines()


def test_stabilisation_lines_sort_the_vibration_stages():
    """A coarse-joint run's stages (gain and last-20 % gain in mm): 68 Hz and the
    71 Hz control end at rest, 100, 142 and 487 Hz still settle; a stage without settlement
    and the self-weight stage are reported apart / left out."""

    def st(f, gained, late):
        return {"frequency_Hz": f, "steps": 10, "gained_mm": gained, "gained_last_20pct_mm": late}

    stages = [
        st(0.0, 2.4439, 0.2699),
        st(68.0, 0.6693, -0.00004),
        st(100.0, 0.1094, 0.01945),
        st(70.98, 0.03395, 0.00038),
        st(141.96, 0.0590, 0.01443),
        st(486.79, 0.1727, 0.03175),
        st(300.0, 0.0, 0.0),
    ]
    lines = format_stabilisation(stages)
    assert lines[1] == "  stabilised: 68.0 Hz (-0.0 %), 71.0 Hz (1.1 %)"
    assert lines[2] == "  still settling: 100.0 Hz (17.8 %), 142.0 Hz (24.5 %), 486.8 Hz (18.4 %)"
    assert lines[3] == "  no settlement: 300.0 Hz"
    assert stabilised(1.0, 0.049) and not stabilised(1.0, 0.051) and not stabilised(0.0, 0.0)
    assert format_stabilisation([st(0.0, 2.4, 0.3)]) == []


def test_slip_episodes_count_and_size():
    """Two slides of 0.3 and 0.5 mm at 10 mm/s between rests (one row = 10 ms): two events of
    those sizes; a rate below the threshold is no event."""
    t = 0.01 * np.arange(1, 31)
    rate = np.zeros(30)
    rate[5:8], rate[15:20] = 10.0, 10.0  # mm/s
    s = np.cumsum(rate * 0.01)
    assert slip_episodes(t, s, 0.0, 0.0, 1, 1.0) == pytest.approx([0.3, 0.5])
    assert stick_slip_events(t, s, 0.0, 0.0, 1, 1.0) == 2
    assert slip_episodes(t, 0.05 * s, 0.0, 0.0, 1, 1.0) == []
