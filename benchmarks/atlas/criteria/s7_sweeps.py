"""S7: step-wise and ramped frequency sweeps (docs/physics.md §5.7)."""

import numpy as np

from benchmarks.atlas import figures
from benchmarks.atlas.context import Context, Scenario
from benchmarks.atlas.outcome import Outcome, Row, verdict
from benchmarks.atlas.selectivity import sustained_rate
from benchmarks.atlas.sweeps import (
    STEPS_HZ,
    nearest_mode,
    ramp_band_gains,
    settling_peaks,
    step_gains,
    sweep_runs,
    unexcited_run,
)
from solver.dynamics.loads import eccentric_amplitude

__all__ = ["SCENARIO"]

#: S7: the step-wise sweep's dwell and the slow ramp's duration, in vibration stages
#: (``vibration.stage_duration_s``: 0.03 and 0.1 s on the default joint), the fast ramp's speed-up
#: and the ramps' span about the best mode (a fraction of its frequency)
SWEEP_DWELL, RAMP_SLOW, RAMP_SPEED_UP, RAMP_SPAN = 0.3, 1.0, 4.0, 0.03
NEAR_MODE = 0.05  #: S7: a step within this fraction of a natural frequency is at that mode
OFF_MODE = 0.1  #: S7 probe: a step farther than this fraction from every natural frequency
RAMP_BANDS = 8  #: S7 probe: parts of the ramps' span


def s7_sweeps(ctx: Context) -> Outcome:
    """S7 from the joint settled by self-weight (``benchmarks.atlas.sweeps``): the step-wise
    sweep at the eccentric amplitude, where it settles against the natural frequencies; a slow
    and a fast linear ramp across the best-ranked mode at the modal stages' amplitude."""
    stage = ctx.case().vibration.stage_duration_s
    r = sweep_runs(
        ctx.comm,
        ctx.case_name,
        ctx.overrides,
        ctx.output / "runs" / "sweeps",
        SWEEP_DWELL * stage,
        RAMP_SLOW * stage,
        RAMP_SPEED_UP,
        RAMP_SPAN,
    )
    unexcited = unexcited_run(
        ctx.comm, ctx.case_name, ctx.overrides, ctx.output / "runs" / "sweeps_unexcited", r
    )
    natural, runs = r["natural_Hz"], r["runs"]
    steps, dwell = runs["steps"], r["request"]["dwell_s"]
    drift = step_gains(unexcited["rows"], steps["starts_s"], dwell)
    # the settlement each step adds to the unexcited joint's over the same time [mm]
    gains = np.subtract(step_gains(steps["rows"], steps["starts_s"], dwell), drift).tolist()
    freqs = steps["frequencies_Hz"]
    peaks = settling_peaks(gains)
    nearest = [nearest_mode(f, natural) for f in freqs]
    peak_text = "; ".join(
        f"{freqs[k]:g} Hz ({1e3 * gains[k]:.1f} um, nearest natural frequency "
        f"{nearest[k][0]:.2f} Hz, {100 * nearest[k][1]:+.1f} %)"
        for k in peaks
    )
    at_modes = [k for k in peaks if abs(nearest[k][1]) <= NEAR_MODE]
    f0, f1, df = STEPS_HZ
    rows = [
        Row(
            f"step-wise {f0:g} to {f1:g} Hz in {df:g} Hz steps of {1e3 * dwell:g} ms (the published "
            f"0.5 s shortened) at the eccentric amplitude 0.3632 f^2 N, from the joint settled by "
            f"self-weight (t = {r['settled']['time_s']:.2f} s): settlement at natural frequencies "
            f"only (§5.2): the steps that add more settlement to the unexcited joint's than both "
            f"their neighbours (the next one with the larger force) lie within "
            f"{100 * NEAR_MODE:g} % of a natural frequency",
            "added per step to the unexcited joint's settlement: "
            + ", ".join(f"{f:g} Hz {1e3 * g:.1f}" for f, g in zip(freqs, gains))
            + f" um (the unexcited joint: {1e3 * sum(drift):+.1f} um over the sweep's "
            f"{len(freqs) * dwell:g} s); local maxima: {peak_text or 'none'}",
            verdict(bool(peaks) and at_modes == peaks),
        )
    ]
    best, (low, high) = r["best"], r["ramp_Hz"]
    off = [k for k in range(len(freqs)) if abs(nearest[k][1]) > OFF_MODE]
    settled = sum(g for g in gains if g > 0)
    rows.append(
        Row(
            f"probe: where the step-wise sweep settles: the steps farther than "
            f"{100 * OFF_MODE:g} % from every natural frequency, and the force amplitude of "
            "each step",
            f"{1e3 * sum(max(gains[k], 0.0) for k in off):.1f} of the {1e3 * settled:.1f} um "
            f"added ({', '.join(f'{freqs[k]:g}' for k in off)} Hz); force "
            + ", ".join(f"{f:g} Hz {eccentric_amplitude(f) / 1e3:.2f}" for f in freqs)
            + " kN",
            "measured",
        )
    )
    lead = runs["lead-in"]["rows"]
    gained = {
        n: runs[n]["rows"][-1][1] - runs[n]["rows"][0][1] for n in ("lead-in", "slow", "fast")
    }
    speed_up = r["request"]["speed_up"]
    rows += [
        Row(
            f"linear ramps {low:.2f} to {high:.2f} Hz across the best-ranked mode "
            f"({best['frequency_Hz']:.2f} Hz, (m, n) = ({best['m']}, {best['n']}), centred on its "
            f"time-discrete frequency {best['centre_Hz']:.2f} Hz) at "
            f"{r['amplitude_N'] / 1e3:g} kN, after a lead-in of {lead[-1][0] - lead[0][0]:.4f} s "
            f"at {low:.2f} Hz: a pass {speed_up:g} x faster settles less (§5.7)",
            "; ".join(
                f"{name} ({runs[name]['duration_s']:g} s, {runs[name]['sweep_rate_Hz_s']:.0f} "
                f"Hz/s): {1e3 * gained[name]:.1f} um"
                for name in ("slow", "fast")
            )
            + f" ({gained['fast'] / gained['slow']:.2f} x)",
            verdict(gained["slow"] > max(gained["fast"], 0.0)),
        ),
        Row(
            f"probe: where the ramps settle: the settlement gained in each {RAMP_BANDS}th of "
            "their span, and the lead-in's rate at its end (second half)",
            "; ".join(
                f"{name}: "
                + ", ".join(
                    f"{1e3 * g:.1f}"
                    for g in ramp_band_gains(runs[name]["rows"], low, high, RAMP_BANDS)
                )
                + " um"
                for name in ("slow", "fast")
            )
            + f"; lead-in {1e3 * gained['lead-in']:+.1f} um, at its end "
            f"{sustained_rate(lead):.2f} mm/s against the slow ramp's mean "
            f"{gained['slow'] / runs['slow']['duration_s']:.2f} mm/s",
            "measured",
        ),
    ]
    names = []
    path, name = ctx.figure("S7", "steps.png")
    if ctx.comm.rank == 0:
        t, s, _ = np.array(steps["rows"]).T
        starts = np.array(steps["starts_s"])
        step_of = np.clip(np.searchsorted(starts, t, side="right") - 1, 0, len(freqs) - 1)
        history = [
            {"time_s": ti, "settlement_mm": si, "frequency_Hz": freqs[k]}
            for ti, si, k in zip(t, s, step_of)
        ]
        stages = [
            {"start_s": a, "end_s": a + dwell, "frequency_Hz": f, "gained_mm": g}
            for a, f, g in zip(starts, freqs, gains)
        ]
        figures.plot_sequence(
            history,
            stages,
            ["sweep step"] * len(stages),
            natural,
            path,
            "S7: step-wise sweep at the eccentric amplitude (bars: added to the unexcited joint)",
        )
    names.append(name)
    path, name = ctx.figure("S7", "ramps.png")
    if ctx.comm.rank == 0:
        curves = {}
        for label in ("slow", "fast"):
            t, s, _ = np.array(runs[label]["rows"]).T
            f = low + (high - low) * (t - t[0]) / runs[label]["duration_s"]
            curves[f"{label}: {runs[label]['duration_s']:g} s"] = (f, 1e3 * (s - s[0]))
        figures.plot_ramps(
            curves,
            natural,
            best["centre_Hz"],
            path,
            f"S7: linear ramps across the {best['frequency_Hz']:.2f} Hz mode",
        )
    names.append(name)
    return ctx.outcome(SCENARIO, rows, {"sweeps": r, "unexcited": unexcited}, names)


SCENARIO = Scenario(
    "S7",
    "sweeps",
    "step-wise 10 to 130 Hz; a fast linear ramp across the best mode settles less than a slow one",
    s7_sweeps,
)
