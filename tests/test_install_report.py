"""The frequency-selectivity lines of the installation summary (no finite elements involved)."""

import numpy as np

from solver.installation import Excitation
from solver.report import SELECTIVE, format_selectivity, frequency_selectivity


def _stage(k: int, f: float, start: float, end: float, gained: float) -> dict:
    return {"stage": k, "frequency_Hz": f, "start_s": start, "end_s": end, "gained_mm": gained, "steps": 10}


def _excitation(f: float, role: str, amplitude=3600.0) -> Excitation:
    return Excitation(f, amplitude, role, 0, 0, 0, 0, "")


def test_rates_compare_stages_of_different_lengths():
    """Modal 0.05 mm in 0.03 s (1.667 mm/s) against control 0.01 mm in 0.06 s (0.1667 mm/s):
    10 x; a modal stage at another amplitude and the lead-in are not compared."""
    stages = [_stage(0, 0.0, 0.0, 2.0, 2.4), _stage(1, 68.0, 2.0, 2.1, 0.7),
              _stage(2, 300.0, 2.1, 2.13, 0.05), _stage(3, 450.0, 2.13, 2.19, 0.01),
              _stage(4, 500.0, 2.19, 2.22, 0.2)]
    excitations = [_excitation(68.0, "lead-in", "eccentric"), _excitation(300.0, "modal"),
                   _excitation(450.0, "control"), _excitation(500.0, "modal", 7200.0)]
    rows = frequency_selectivity(stages, excitations)
    assert [r["frequency_Hz"] for r in rows] == [300.0]
    assert np.isclose(rows[0]["rate_mm_s"], 0.05 / 0.03)
    assert np.isclose(rows[0]["control_rate_mm_s"], 0.01 / 0.06)
    assert np.isclose(rows[0]["ratio"], 10.0)
    lines = format_selectivity(rows)
    assert "shown by this run" in lines[0] and "NOT" not in lines[0]
    assert "10.00 x the control" in lines[-1]


def test_a_control_that_settles_as_much_is_reported():
    stages = [_stage(0, 0.0, 0.0, 2.0, 2.4), _stage(1, 352.0, 2.0, 2.03, 0.0556),
              _stage(2, 451.0, 2.03, 2.06, 0.085), _stage(3, 487.0, 2.06, 2.09, 0.0926)]
    excitations = [_excitation(352.0, "modal"), _excitation(451.0, "control"), _excitation(487.0, "modal")]
    rows = frequency_selectivity(stages, excitations)
    assert [round(r["ratio"], 3) for r in rows] == [round(0.0556 / 0.085, 3), round(0.0926 / 0.085, 3)]
    assert all(r["ratio"] < SELECTIVE for r in rows)
    assert "NOT shown" in format_selectivity(rows)[0]


def test_nothing_settled_is_not_selectivity():
    """A control that did not settle makes a settling modal stage infinitely selective, and a
    modal stage that did not settle either not selective at all."""
    stages = [_stage(0, 0.0, 0.0, 2.0, 2.4), _stage(1, 352.0, 2.0, 2.03, 0.0),
              _stage(2, 451.0, 2.03, 2.06, 0.0), _stage(3, 487.0, 2.06, 2.09, 0.01)]
    excitations = [_excitation(352.0, "modal"), _excitation(451.0, "control"), _excitation(487.0, "modal")]
    rows = frequency_selectivity(stages, excitations)
    assert [r["ratio"] for r in rows] == [0.0, np.inf]
    assert "NOT shown" in format_selectivity(rows)[0]


def test_no_control_no_lines():
    stages = [_stage(0, 0.0, 0.0, 2.0, 2.4), _stage(1, 352.0, 2.0, 2.03, 0.05)]
    assert frequency_selectivity(stages, [_excitation(352.0, "modal")]) == []
    assert format_selectivity([]) == []
