"""The bracketing of the atlas's amplitude threshold (S3, benchmarks/atlas/amplitude.py) and its
stick-slip criterion, on made-up branches: the factors it asks for against a threshold known in
advance, and the period-averaged rate of the settlement a branch adds to the unexcited one."""

import numpy as np
import pytest

from benchmarks.atlas.amplitude import (
    BRACKET,
    FACTOR_RANGE,
    next_factor,
    added_settlement,
    settles,
)


def bracket(threshold: float) -> dict[float, bool]:
    """The branches the search runs when every factor >= ``threshold`` settles."""
    results: dict[float, bool] = {}
    while (k := next_factor(results)) is not None:
        results[k] = k >= threshold
    return results


@pytest.mark.parametrize("threshold", [0.3, 1.0, 1.05, 2.7, 7.9])
def test_the_search_brackets_a_threshold_to_ten_percent(threshold):
    results = bracket(threshold)
    low = max(k for k, s in results.items() if not s)
    high = min(k for k, s in results.items() if s)
    assert low < threshold <= high
    assert high / low <= BRACKET
    assert len(results) <= 8  # doubling, then bisection in log


@pytest.mark.parametrize("threshold", [0.01, 100.0])
def test_a_threshold_outside_the_range_stops_the_search(threshold):
    results = bracket(threshold)
    assert all(results.values()) or not any(results.values())
    assert min(results) >= FACTOR_RANGE[0] and max(results) <= FACTOR_RANGE[1]


def test_a_stick_slip_event_is_a_period_averaged_rate_above_the_threshold():
    steps, f = 16, 100.0
    t = np.arange(5 * steps + 1) / (steps * f)
    still = [(ti, 0.0, 0.0) for ti in t]  # the baseline: no drift
    wobble = 0.01 * np.sin(2 * np.pi * f * t)  # 10 um of oscillation [mm], no net settlement
    assert not settles([(ti, si, 0.0) for ti, si in zip(t, wobble)], still, steps, 1.0)
    jump = wobble + 0.02 * (t > 0.02)  # 20 um within a step: 2 mm/s over a period
    rows = [(ti, si, 0.0) for ti, si in zip(t, jump)]
    assert settles(rows, still, steps, slip_rate_mm_s=1.0)
    assert not settles(rows, still, steps, slip_rate_mm_s=3.0)


def test_only_the_settlement_added_to_the_baseline_counts():
    steps, f = 16, 100.0
    t = np.arange(5 * steps + 1) / (steps * f)
    drift = 0.02 * (1 - np.exp(-t / 0.005))  # the unexcited state settles 20 um [mm]
    baseline = [(ti, 3.0 + si, 0.0) for ti, si in zip(t, drift)]
    same = [(ti, 3.0 + si + 0.01 * np.sin(2 * np.pi * f * ti), 0.0) for ti, si in zip(t, drift)]
    assert settles(baseline, [(ti, 3.0, 0.0) for ti in t], steps, 1.0)  # against no drift
    assert not settles(same, baseline, steps, 1.0)
    added = added_settlement(same, baseline[::2])[1]  # a baseline with other times: interpolated
    assert abs(added).max() < 0.011
