"""S8: the natural frequencies as the joint settles (docs/physics.md §5.8)."""

import numpy as np

from benchmarks.atlas import figures
from benchmarks.atlas.context import Context, Scenario
from benchmarks.atlas.installed import installed_modes, kept_stages
from benchmarks.atlas.outcome import Outcome, Row, verdict

__all__ = ["SCENARIO"]


def s8_stiffening(ctx: Context) -> Outcome:
    """S8, self-weight half: the settled joint's frequencies at half the load and at the end of
    the stage, against a bonded band as high as the contact at the end; where ``ctx.installed``
    names an installation run of the case, also in its installed state and after each of its
    vibration stages whose state it kept (``[output] stage_states``), as the stage left it and
    brought to rest (``_s8_stages``; figures ``frequencies.png`` and ``stiffening.png``)."""
    r = ctx.reference()
    (t_half, f_half), (t_end, f_end) = (
        (float(k), np.array(f)) for k, f in r["frequencies_Hz"].items()
    )
    bonded = np.array(r["bonded_Hz"])
    with np.errstate(divide="ignore"):  # a joint that is not yet held has rigid-body modes
        rise = f_end / f_half - 1
    rows = [
        Row(
            "natural frequencies rise with settlement (§5.8): the ten lowest at the end against "
            "half the load",
            f"{100 * rise.min():+.2f} % to {100 * rise.max():+.2f} % "
            f"(settlement {np.interp(t_half, r['time_s'], r['settlement_mm']):.3f} -> "
            f"{r['settlement_mm'][-1]:.3f} mm)",
            verdict(bool(np.all(rise > 0))),
        ),
        Row(
            f"settled joint against a bonded band of the contact's height "
            f"({1e3 * r['contact_height_m']:.0f} mm)",
            f"{100 * (f_end / bonded - 1).min():+.2f} % to {100 * (f_end / bonded - 1).max():+.2f} %",
            "measured",
        ),
    ]
    curves = {
        f"settled, {t_half:g} s": f_half,
        f"settled, {t_end:g} s": f_end,
        f"bonded band {1e3 * r['contact_height_m']:.0f} mm": bonded,
    }
    runs = {"reference": r}
    names = []
    if ctx.installed is not None:
        stages = [k for k in kept_stages(ctx.installed) if k >= 1]
        if stages:
            stage_rows, states = _s8_stages(ctx, stages, f_end, runs)
            rows += stage_rows
            path, name = ctx.figure("S8", "stiffening.png")
            if ctx.comm.rank == 0:
                figures.plot_stiffening(
                    r["settlement_mm"][-1],
                    f_end,
                    states,
                    path,
                    "S8: natural frequencies after each vibration stage",
                )
            names.append(name)
        else:
            rows.append(
                Row(
                    "the ten lowest after each vibration stage (§5.8)",
                    f"not measured: the installation run in {ctx.installed} kept no stage "
                    "states (`--set output.stage_states=true`)",
                    "not run",
                )
            )
        runs["installed"] = i = installed_modes(
            ctx.comm,
            ctx.case_name,
            ctx.overrides,
            ctx.output / "runs" / "modes_installed",
            ctx.installed,
        )
        f_inst, bonded_inst = np.array(i["frequencies_Hz"]), np.array(i["bonded_Hz"])
        rise = f_inst / f_end - 1
        rows += [
            Row(
                f"the ten lowest after the installation run's vibration stages (t = "
                f"{i['time_s']:.2f} s) against the end of self-weight",
                f"{100 * rise.min():+.2f} % to {100 * rise.max():+.2f} % (settlement "
                f"{r['settlement_mm'][-1]:.3f} -> {i['settlement_mm']:.3f} mm)",
                verdict(bool(np.all(rise > 0))),
            ),
            Row(
                f"installed joint against a bonded band of its contact's height "
                f"({1e3 * i['contact_height_m']:.0f} mm)",
                f"{100 * (f_inst / bonded_inst - 1).min():+.2f} % to "
                f"{100 * (f_inst / bonded_inst - 1).max():+.2f} %",
                "measured",
            ),
        ]
        curves[f"installed, {i['time_s']:.2f} s"] = f_inst
        curves[f"bonded band {1e3 * i['contact_height_m']:.0f} mm (installed)"] = bonded_inst
    path, name = ctx.figure("S8", "frequencies.png")
    if ctx.comm.rank == 0:
        figures.plot_frequencies(curves, path, "S8: natural frequencies of the settled joint")
    return ctx.outcome(SCENARIO, rows, runs, [name, *names])


def _s8_stages(
    ctx: Context, stages: list[int], f_settled: np.ndarray, runs: dict
) -> tuple[list[Row], dict[str, tuple[list[float], list[list[float]]]]]:
    """S8 after each vibration stage whose state the installation run kept: the ten lowest
    against those before the stage (after self-weight for the first), against a bonded band
    of the contact's height and, a probe, with the joint brought to rest after each stage (the
    static load held as long as the self-weight stage's hold) against the joint at rest before
    it. Returns the rows and, for ``figures.plot_stiffening``, both kinds of state's
    settlements [mm] and frequencies [Hz] (the runs join ``runs``)."""
    rises, against_bonded, at_rest = [], [], []
    before = rested = f_settled
    for k in stages:
        m, r = (
            installed_modes(
                ctx.comm,
                ctx.case_name,
                ctx.overrides,
                ctx.output / "runs" / f"modes_stage_{k}{suffix}",
                ctx.installed,
                stage=k,
                rest_s=rest_s,
            )
            for suffix, rest_s in (("", 0.0), ("_at_rest", ctx.case().self_weight.hold_s))
        )
        runs[f"stage {k}"], runs[f"stage {k} at rest"] = m, r
        f, bonded, f_rest = (
            np.array(x) for x in (m["frequencies_Hz"], m["bonded_Hz"], r["frequencies_Hz"])
        )
        rises.append((k, m, f / before - 1))
        against_bonded.append((k, m, f / bonded - 1))
        at_rest.append((k, r, f_rest / rested - 1))
        before, rested = f, f_rest
    states = {
        label: ([m["settlement_mm"] for _, m, _ in kind], [m["frequencies_Hz"] for _, m, _ in kind])
        for label, kind in (("as the stage left it", rises), ("brought to rest", at_rest))
    }
    rows = [
        Row(
            "the ten lowest after each vibration stage against those before it (§5.8)",
            "; ".join(
                f"stage {k} ({m['settlement_mm']:.3f} mm): {100 * r.min():+.2f} % to "
                f"{100 * r.max():+.2f} %"
                for k, m, r in rises
            ),
            verdict(all(bool(np.all(r >= 0)) for _, _, r in rises)),
        ),
        Row(
            "after each vibration stage against a bonded band of its contact's height",
            "; ".join(
                f"stage {k} ({1e3 * m['contact_height_m']:.0f} mm): {100 * d.min():+.2f} % to "
                f"{100 * d.max():+.2f} %"
                for k, m, d in against_bonded
            ),
            "measured",
        ),
        Row(
            f"probe: the same with the joint brought to rest after each stage (the shaker off, "
            f"the static load held {1e3 * ctx.case().self_weight.hold_s:g} ms, as in the "
            "self-weight stage's hold, with "
            "its scheme and step), against the joint at rest before it",
            "; ".join(
                f"stage {k} ({m['settlement_mm']:.3f} mm, contact {1e3 * m['contact_height_m']:.0f}"
                f" mm): {100 * r.min():+.2f} % to {100 * r.max():+.2f} %"
                for k, m, r in at_rest
            )
            + f"; after stage {stages[-1]} at rest against the end of self-weight: "
            f"{100 * (rested / f_settled - 1).min():+.2f} % to "
            f"{100 * (rested / f_settled - 1).max():+.2f} %",
            "measured",
        ),
    ]
    return rows, states


SCENARIO = Scenario(
    "S8",
    "stiffening",
    "natural frequencies of the settled joint rise with settlement; against a bonded band "
    "of the same height",
    s8_stiffening,
)
