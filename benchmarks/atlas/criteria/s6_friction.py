"""S6: friction and damping, under self-weight and in the two-stage sequence (docs/physics.md §5.6)."""

from typing import Any

import numpy as np

from benchmarks.atlas import figures
from benchmarks.atlas.context import Context, Scenario
from benchmarks.atlas.outcome import Outcome, Row, verdict
from benchmarks.atlas.selectivity import selectivity_ratio, selectivity_runs, sustained_rate
from solver.post import report

__all__ = ["SCENARIO"]

LOW_FRICTION = ["friction.mu_s=0.0625", "friction.mu_d=0.05"]  #: docs/physics.md §4 study values
#: S6: the vibration halves' cases, and their lead-in and branches, in vibration stages
SLOW_DECAY, MODAL_DAMPING = ["friction.d_c=1"], ['damping.model="modal"']
SELECTIVITY_LEAD_IN = SELECTIVITY_BRANCH = 0.5


def s6_friction(ctx: Context) -> Outcome:
    """S6: mu_s/mu_d 0.0625/0.05 against the case's friction under self-weight, compared at a
    quarter of the ramp (beyond it the low-friction TP slides out of the contact zone); d_c =
    1 s/m against the case's, and modal against the case's Rayleigh damping: the selectivity
    ratio of the two-stage sequence (``benchmarks.atlas.selectivity``)."""
    case = ctx.case()
    sw = case.self_weight
    t = 0.25 * sw.ramp_time_s
    reference = ctx.reference()
    low = ctx.self_weight("low_friction", LOW_FRICTION, until_s=t)
    s_ref = float(np.interp(t, reference["time_s"], reference["settlement_mm"]))
    s_low = low["settlement_mm"][-1]
    rows = [
        Row(
            f"lower friction settles more (§5.6), at {t:g} s ({abs(sw.force_N) * t / sw.ramp_time_s / 1e3:g} kN)",
            f"{s_low:.4f} mm against {s_ref:.4f} mm ({s_low / s_ref:.2f} x)",
            verdict(s_low > s_ref > 0),
        )
    ]
    c = case.friction
    runs: dict[str, dict] = {f"mu {c.mu_s:g}/{c.mu_d:g}": reference, "mu 0.0625/0.05": low}
    path, name = ctx.figure("S6", "friction.png")
    if ctx.comm.rank == 0:
        figures.plot_settlement(runs, path, "S6: self-weight ramp, two friction pairs")
    names = [name]
    stage = case.vibration.stage_duration_s
    variants = {  # label: (run folder, overrides)
        f"d_c {c.d_c:g} s/m, {case.damping.model}": ("selectivity", []),
        "d_c 1 s/m": ("selectivity_slow_decay", SLOW_DECAY),
        "modal damping": ("selectivity_modal_damping", MODAL_DAMPING),
    }
    selectivity = {
        label: selectivity_runs(
            ctx.comm,
            ctx.case_name,
            [*ctx.overrides, *extra],
            ctx.output / "runs" / folder,
            SELECTIVITY_LEAD_IN * stage,
            SELECTIVITY_BRANCH * stage,
        )
        for label, (folder, extra) in variants.items()
    }
    base, slow, modal = selectivity.values()

    def ratio(r: dict[str, Any]) -> float:
        return selectivity_ratio(r["branches"]["modal"]["rows"], r["branches"]["control"]["rows"])

    def described(r: dict[str, Any]) -> str:
        m, k = r["branches"]["modal"], r["branches"]["control"]
        return (
            f"{ratio(r):.1f} x ({m['frequency_Hz']:.2f} Hz, (m, n) = ({m['m']}, {m['n']}), driven "
            f"at {m['forcing_Hz']:.2f} Hz: {1e3 * sustained_rate(m['rows']):.1f} um/s; control "
            f"{k['frequency_Hz']:.2f} Hz: {1e3 * sustained_rate(k['rows']):.1f} um/s)"
        )

    def span(b: dict[str, Any]) -> float:
        return b["rows"][-1][0] - b["rows"][0][0]

    lead_s, branch_s = span(base["branches"]["lead-in"]), span(base["branches"]["control"])
    two_stage = (
        f"the two-stage sequence at {base['amplitude_N'] / 1e3:g} kN from the joint settled by "
        f"self-weight: {lead_s:.4f} s at the control frequency, then {branch_s:.4f} s at the "
        f"control and, from the same state, about as long at the best-ranked mode (whole "
        "periods); the selectivity ratio is the mode's settlement rate over the second half "
        "over the control's"
    )
    slow_control = sustained_rate(slow["branches"]["control"]["rows"])
    rows += [
        Row(
            f"d_c = 1 s/m loses the frequency selectivity (§5.6): in {two_stage}, d_c = "
            f"{c.d_c:g} s/m at least {report.SELECTIVE:g} x; d_c = 1 s/m below, its control "
            "settling",
            f"d_c {c.d_c:g} s/m: {described(base)}; d_c 1 s/m: {described(slow)}",
            verdict(ratio(base) >= report.SELECTIVE > ratio(slow) and slow_control > 0),
        ),
        Row(
            f"{case.damping.model} damping ({100 * case.damping.zeta:g} % at "
            f"{case.damping.frequency_hz:g} Hz) against modal damping ({100 * case.damping.zeta:g} "
            f"% for the {case.damping.n_modes} lowest modes of the bonded joint): the selectivity "
            f"ratio in {two_stage}",
            f"{case.damping.model}: {described(base)}; modal: {described(modal)}",
            "measured",
        ),
    ]
    path, name = ctx.figure("S6", "selectivity.png")
    if ctx.comm.rank == 0:
        curves = {}
        for label, r in selectivity.items():
            for b in ("modal", "control"):
                rows_b = np.array(r["branches"][b]["rows"])
                t0, s0 = rows_b[0, :2]
                f = r["branches"][b].get("forcing_Hz", r["branches"][b]["frequency_Hz"])
                curves[f"{label}: {b} at {f:.2f} Hz"] = np.c_[
                    rows_b[:, 0] - t0, 1e3 * (rows_b[:, 1] - s0), rows_b[:, 2]
                ].tolist()
        figures.plot_branches(
            curves,
            path,
            "S6: the best mode and the control after the lead-in",
            ylabel="settlement gained [um]",
        )
    names.append(name)
    runs |= selectivity
    return ctx.outcome(SCENARIO, rows, runs, names)


SCENARIO = Scenario(
    "S6",
    "friction and damping",
    "lower friction settles more under self-weight; d_c = 1 against 100 and Rayleigh "
    "against modal damping: the selectivity ratio of S2 (its two-stage form: one mode, "
    "the control)",
    s6_friction,
)
