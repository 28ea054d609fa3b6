"""S3: amplitude-driven settlement at two non-modal frequencies (docs/physics.md §5.3)."""

import numpy as np

from benchmarks.atlas import figures
from benchmarks.atlas.amplitude import (
    BRACKET,
    BRANCH_PERIODS,
    FACTOR_RANGE,
    added_settlement,
    amplitude_runs,
    settles,
)
from benchmarks.atlas.context import Context, Scenario
from benchmarks.atlas.outcome import Outcome, Row, verdict

__all__ = ["SCENARIO"]


def s3_amplitude(ctx: Context) -> Outcome:
    """S3 from the installed state of the installation run ``ctx.installed``: at its control
    and its highest lead-in frequency, the amplitude above which the settlement a branch of a
    few periods adds to the unexcited state's holds a stick-slip event, bracketed to ``BRACKET``
    (``benchmarks.atlas.amplitude``), and how the added settlement grows with the amplitude."""
    if ctx.installed is None:
        raise ValueError("S3 starts from an installation run: --installed RUN")
    case = ctx.case()
    amplitude = case.vibration.amplitude_N
    steps, slip_rate = case.time.steps_per_period, case.output.slip_rate_mm_s
    r = amplitude_runs(
        ctx.comm,
        ctx.case_name,
        ctx.overrides,
        ctx.output / "runs" / "amplitude_installed",
        ctx.installed,
    )
    rows, names = [], []
    for f, runs in r["frequencies"].items():
        baseline = runs.get("0")  # None where the baseline failed: nothing to compare with
        branches = {float(k): b for k, b in runs.items() if float(k) > 0 and baseline}
        results = {k: settles(b, baseline, steps, slip_rate) for k, b in branches.items()}
        added = {k: added_settlement(b, baseline)[1][-1] for k, b in branches.items()}
        holding = [k for k, s in results.items() if not s]
        settling = [k for k, s in results.items() if s]
        drift = baseline[-1][1] - baseline[0][1] if baseline else float("nan")
        criterion = (
            f"from the installed state (t = {r['request']['time_s']:.2f} s), at {float(f):.2f} Hz "
            f"(not at a natural frequency), branches of {BRANCH_PERIODS} periods at k x "
            f"{amplitude / 1e3:g} kN: the amplitude above which the settlement added to the "
            f"unexcited state's ({1e3 * drift:+.1f} um) holds a stick-slip event (period-averaged "
            f"rate above {slip_rate:g} mm/s), bracketed to {100 * (BRACKET - 1):.0f} %; below it "
            "none: less than a fifth of what the smallest settling amplitude adds (§5.3)"
        )
        tried = "; ".join(
            f"{k * amplitude / 1e3:.3g} kN: {1e3 * added[k]:+.1f} um"
            + (" (event)" if results[k] else "")
            for k in sorted(results)
        )
        failure = r.get("failed", {}).get(f)
        if failure is not None:
            measured = (
                f"not bracketed: the branch at {failure['factor'] * amplitude / 1e3:.3g} kN "
                f"failed ({failure['message'].split(':')[0]}); {tried}"
            )
            holds = False
        elif holding and settling and min(settling) / max(holding) <= BRACKET:
            low, high = max(holding), min(settling)
            measured = (
                f"threshold between {low * amplitude / 1e3:.3g} and {high * amplitude / 1e3:.3g} "
                f"kN ({low:.3g} to {high:.3g} A); added: {tried}"
            )
            holds = added[low] < 0.2 * added[high]
        else:
            limit = FACTOR_RANGE[1] if not settling else FACTOR_RANGE[0]
            measured = (
                f"not bracketed: {'no event up to' if not settling else 'an event down to'} "
                f"{limit * amplitude / 1e3:.3g} kN; added: {tried}"
            )
            holds = False
        rows.append(Row(criterion, measured, verdict(holds)))
        grown = sorted(k for k in added if added[k] > 0)
        if len(grown) >= 3:  # a threshold is a jump in the added settlement, not a power law
            exponent = np.polyfit(np.log(grown), np.log([added[k] for k in grown]), 1)[0]
            rows.append(
                Row(
                    "probe: the settlement added against the amplitude, a power law fitted "
                    "over the branches (a threshold would be a jump)",
                    f"added ~ A^{exponent:.2f} from {grown[0] * amplitude / 1e3:.3g} to "
                    f"{grown[-1] * amplitude / 1e3:.3g} kN ({len(grown)} branches)",
                    "measured",
                )
            )
        path, name = ctx.figure("S3", f"amplitude_{float(f):.0f}Hz.png")
        if ctx.comm.rank == 0:
            curves = {}
            for k in sorted(branches):  # the settlement added to the baseline [um]
                t, extra = added_settlement(branches[k], baseline)
                force = np.array(branches[k])[:, 2]
                curves[f"{k * amplitude / 1e3:.3g} kN"] = np.c_[t, 1e3 * extra, force].tolist()
            figures.plot_branches(
                curves,
                path,
                f"S3: {float(f):.2f} Hz from the installed state (the zero line: no excitation)",
                ylabel="settlement added [um]",
            )
        names.append(name)
    if not r["frequencies"]:
        rows.append(
            Row(
                "amplitude threshold at non-modal frequencies", "the run has none", "not reproduced"
            )
        )
    return ctx.outcome(SCENARIO, rows, {"amplitude": r}, names)


SCENARIO = Scenario(
    "S3",
    "amplitude-driven settlement at two non-modal frequencies",
    "the amplitude threshold bracketed to 10 %; above it settlement off resonance, below it none",
    s3_amplitude,
    installed=True,
)
