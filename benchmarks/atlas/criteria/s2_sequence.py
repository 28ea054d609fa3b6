"""S2: the reference sequence of an installation run, stage by stage (docs/physics.md §5.2)."""

import shutil
from typing import Any

import numpy as np

from benchmarks.atlas import figures
from benchmarks.atlas.context import Context, Scenario
from benchmarks.atlas.continuation import continued_stage
from benchmarks.atlas.installed import installed_state, kept_stages
from benchmarks.atlas.outcome import Outcome, Row, verdict
from benchmarks.atlas.selectivity import sustained_rate
from solver.installation.frequencies import Excitation
from solver.post import report

__all__ = ["SCENARIO"]


def _stage_label(s: dict[str, Any], e: Excitation) -> str:
    """A vibration stage of an installation run (``s``, its excitation ``e``) in words."""
    what = {
        "lead-in": "lead-in",
        "control": "control (non-modal)",
        "modal": f"mode of rank {e.rank}, (m, n) = ({e.m}, {e.n}), {e.frequency_Hz:.2f} Hz",
    }[e.role]
    return f"{s['name']} at {e.drive_Hz:.2f} Hz, {what}"


def s2_sequence(ctx: Context) -> Outcome:
    """S2 on the reference sequence of the installation run ``ctx.installed`` (its stages up
    to its last checkpoint): per vibration stage the settlement gained, the rate over its
    second half and the share of its last 20 %; the modal stages against the control
    (``solver.post.report``'s criteria, as in the run's summary); a probe: the best-ranked
    mode's stage continued (``_continued_rows``)."""
    if ctx.installed is None:
        raise ValueError("S2 reads an installation run: --installed RUN")
    manifest = installed_state(ctx.comm, ctx.case(), ctx.installed)
    excitations = [Excitation(**e) for e in manifest["excitations"]]
    stages = [s for s in manifest["stages"] if s["stage"] >= 1]
    rows = []
    for s in stages:
        gain, late = s["gained_mm"], s["gained_last_20pct_mm"]
        share = late / gain if gain > 0 else float("nan")
        rows.append(
            Row(
                f"{_stage_label(s, excitations[s['stage'] - 1])}: the last "
                f"{100 * report.LATE:g} % adds less than {100 * report.LATE_SHARE:g} % of the "
                "stage's gain (§5.2)",
                f"gained {1e3 * gain:.1f} um, {report.sustained_rate_mm_s(s):.3f} mm/s over its second half; "
                f"the last {100 * report.LATE:g} % adds "
                f"{100 * share:.1f} % (its rate {share / report.LATE:.2f} x the stage's mean)",
                verdict(report.stabilised(gain, late)),
            )
        )
    selectivity = report.frequency_selectivity(manifest["stages"], excitations)
    if selectivity:
        rows.append(
            Row(
                f"frequency-driven settlement: every modal stage settles at least "
                f"{report.SELECTIVE:g} x as fast as the control over its second half (§5.2)",
                ", ".join(
                    f"{r['frequency_Hz']:.2f} Hz {r['ratio']:.0f} x ({r['stage_ratio']:.1f} x "
                    "over the whole stage)"
                    for r in selectivity
                )
                + f"; the control at {selectivity[0]['control_Hz']:.2f} Hz "
                f"{1e3 * selectivity[0]['control_rate_mm_s']:.1f} um/s",
                verdict(all(r["ratio"] >= report.SELECTIVE for r in selectivity)),
            )
        )
    runs: dict[str, Any] = {}
    rows += _continued_rows(ctx, stages, excitations, runs)
    planned = len(manifest["plans"]) - 1
    rows.append(
        Row(
            "stages of the sequence in the run (S2's ten best-ranked modes: `--full`; "
            "docs/physics.md §3 drives each natural frequency in turn)",
            f"{len(stages)} of {planned} vibration stages to t = {manifest['time_s']:.2f} s; "
            f"modal stages at the modes of rank "
            f"{', '.join(str(e.rank) for e in excitations if e.role == 'modal')}",
            "measured",
        )
    )
    path, name = ctx.figure("S2", "sequence.png")
    names = [name]
    if ctx.comm.rank == 0:
        figures.plot_sequence(
            manifest["history"],
            manifest["stages"],
            ["self-weight", *(excitations[s["stage"] - 1].role for s in stages)],
            manifest["natural_frequencies_Hz"],
            path,
            f"S2: the installation run in {ctx.installed.name}",
        )
        last = ctx.installed / f"contact_status_{len(manifest['stages'])}.png"
        if last.exists():  # the contact at the end of the last stage (output.plots)
            shutil.copyfile(last, path.parent / "contact_status.png")
            names.append("contact_status.png")
    names = ctx.comm.bcast(names)
    if "continued" in runs:
        path, name = ctx.figure("S2", "continued.png")
        if ctx.comm.rank == 0:
            c = runs["continued"]
            s0 = c["rows"][0][1]
            figures.plot_branches(
                {
                    f"{c['plan']['name']} continued": [
                        (t, 1e3 * (s - s0), n) for t, s, n in c["rows"]
                    ]
                },
                path,
                f"S2: {c['plan']['name']} ({c['plan']['frequency_Hz']:.2f} Hz) continued",
                ylabel="settlement gained [um]",
            )
        names.append(name)
    wall = sum(s["wall_s"] for s in manifest["stages"])
    runs["installation"] = {"name": f"installation run {ctx.installed.name}", "wall_s": wall}
    return ctx.outcome(SCENARIO, rows, runs, names)


def _continued_rows(
    ctx: Context, stages: list[dict[str, Any]], excitations: list[Excitation], runs: dict
) -> list[Row]:
    """S2 probe: the stage at the best-ranked mode whose state the installation run kept,
    continued for another stage duration at the same forcing (``continued_stage``): its gain
    per fifth and its rate over its second half against the stage's (the run joins ``runs``)."""
    kept = set(kept_stages(ctx.installed))
    modal = [
        (e.rank, s)
        for s in stages
        if (e := excitations[s["stage"] - 1]).role == "modal" and s["stage"] in kept
    ]
    if not modal:
        return []
    s = min(modal, key=lambda p: p[0])[1]
    runs["continued"] = c = continued_stage(
        ctx.comm,
        ctx.case_name,
        ctx.overrides,
        ctx.output / "runs" / "continued",
        ctx.installed,
        s["stage"],
    )
    t, settlement = np.array(c["rows"])[:, :2].T
    duration = t[-1] - t[0]
    fifths = np.interp(np.linspace(t[0], t[-1], 6), t, settlement)
    return [
        Row(
            f"probe: {_stage_label(s, excitations[s['stage'] - 1])}, continued from the state "
            f"it left for another {1e3 * duration:.0f} ms at the same forcing (its phase "
            "running on): does its event stop? (§5.2)",
            f"gained {1e3 * (settlement[-1] - settlement[0]):.1f} um more ("
            + ", ".join(f"{1e3 * g:.1f}" for g in np.diff(fifths))
            + f" um per {1e3 * duration / 5:.0f} ms), {sustained_rate(c['rows']):.3f} mm/s over its "
            f"second half against {report.sustained_rate_mm_s(s):.3f} mm/s over the stage's; "
            f"{c['step_cuts']} step cut(s)",
            "measured",
        )
    ]


SCENARIO = Scenario(
    "S2",
    "reference sequence, ten best-ranked modes and a control at 3.6 kN",
    "per stage the settlement gained and the sustained rate; modal stages at least 5 times "
    "the control; the last 20 % of a stage adds less than 5 % of its gain",
    s2_sequence,
    installed=True,
)
