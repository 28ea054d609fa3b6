"""The atlas's readings of vibration branches on made-up histories: the step-wise sweep's (S7,
benchmarks/atlas/sweeps.py) settlement gained per step, the steps that settle more than their
neighbours and the natural frequency nearest to a step; the selectivity ratio of S6
(benchmarks/atlas/selectivity.py): second-half rates, modal over control."""

import numpy as np
import pytest

from benchmarks.atlas.selectivity import selectivity_ratio, sustained_rate
from benchmarks.atlas.sweeps import nearest_mode, ramp_band_gains, settling_peaks, step_gains


def test_step_gains_of_a_piecewise_linear_history():
    rates = [1.0, 0.0, 3.0, 2.0]  # mm/s in each 0.1 s step
    starts = [0.5, 0.6, 0.7, 0.8]
    t = np.linspace(0.5, 0.9, 41)  # steps of the history do not fall on the bounds only
    s = np.interp(t, [0.5, 0.6, 0.7, 0.8, 0.9], np.r_[0.0, np.cumsum(0.1 * np.array(rates))])
    rows = [(ti, 2.0 + si, 1e4) for ti, si in zip(t, s)]
    assert step_gains(rows, starts, 0.1) == pytest.approx([0.1, 0.0, 0.3, 0.2], abs=1e-12)


@pytest.mark.parametrize(
    "gains, peaks",
    [
        ([0.0, 1.0, 0.5, 2.0, 3.0], [1]),  # the last step has no next one to compare with
        ([3.0, 1.0, 2.0], []),  # nor the first a previous one
        ([0.0, 2.0, 0.0, 3.0, 0.0], [1, 3]),
        ([0.0, 0.0, 0.0], []),  # no step settles
        ([-1.0, -0.5, -1.5], []),  # heaves are not settlement
        ([1.0, 2.0, 2.0, 0.5], []),  # a tie is no peak
    ],
)
def test_settling_peaks(gains, peaks):
    assert settling_peaks(gains) == peaks


def test_nearest_mode_in_ratio():
    natural = [0.01, 70.0, 140.0]  # a rigid-body mode counts like any positive frequency
    # 140 / 100 = 1.40 < 100 / 70 = 1.43, though 100 Hz is nearer 70 Hz in Hz
    assert nearest_mode(100.0, natural) == pytest.approx((140.0, 100 / 140 - 1))
    assert nearest_mode(0.02, natural) == pytest.approx((0.01, 1.0))
    assert nearest_mode(70.0, [-5.0, 70.0])[1] == 0.0


def test_sustained_rate_is_the_second_half_rate():
    t = np.linspace(1.0, 1.1, 11)
    s = np.where(t < 1.05, 3.0 * (t - 1.0), 0.15 + 0.5 * (t - 1.05))  # 3 then 0.5 mm/s
    rows = [(ti, 2.0 + si, 1e4) for ti, si in zip(t, s)]
    assert sustained_rate(rows) == pytest.approx(0.5)


@pytest.mark.parametrize(
    "modal, control, ratio",
    [(2.0, 0.5, 4.0), (1.0, 0.0, np.inf), (0.0, 0.0, 0.0), (1.0, -1.0, np.inf)],
)
def test_selectivity_ratio(modal, control, ratio):
    def branch(rate: float) -> list:  # settling at ``rate`` [mm/s] for 0.1 s
        return [(t, rate * t, 1e4) for t in np.linspace(0.0, 0.1, 5)]

    assert selectivity_ratio(branch(modal), branch(control)) == pytest.approx(ratio)


def test_ramp_band_gains():
    t = np.linspace(0.0, 0.2, 81)  # a ramp 100 -> 120 Hz over 0.2 s: 100 Hz/s
    f = 100.0 + 100.0 * t
    s = np.where(f < 110.0, 0.0, 0.5 * (f - 110.0))  # 0.5 mm/Hz above 110 Hz
    rows = [(ti, si, 1e4) for ti, si in zip(t, s)]
    assert ramp_band_gains(rows, 100.0, 120.0, 4) == pytest.approx([0.0, 0.0, 2.5, 2.5])
