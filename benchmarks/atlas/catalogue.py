"""The scenarios of the atlas (docs/physics.md §5 observations), each a function of a
:class:`Context` returning an :class:`~benchmarks.atlas.outcome.Outcome`; scenarios not yet in
the atlas are listed with what they need."""

import shutil
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from mpi4py import MPI

from benchmarks.atlas import figures
from benchmarks.atlas.amplitude import (
    BRACKET,
    BRANCH_PERIODS,
    FACTOR_RANGE,
    added_settlement,
    amplitude_runs,
    settles,
)
from benchmarks.atlas.continuation import continued_stage
from benchmarks.atlas.direction import direction_runs
from benchmarks.atlas.dismount import dismount_runs, lift_rate, released, separated
from benchmarks.atlas.installed import installed_modes, installed_state, kept_stages, modal_table
from benchmarks.atlas.outcome import Outcome, Row, verdict
from benchmarks.atlas.selectivity import selectivity_ratio, selectivity_runs, sustained_rate
from benchmarks.atlas.self_weight import self_weight_run
from benchmarks.atlas.sweeps import (
    STEPS_HZ,
    nearest_mode,
    ramp_band_gains,
    settling_peaks,
    step_gains,
    sweep_runs,
    unexcited_run,
)
from common.case import read_case
from solver.dynamics.loads import eccentric_amplitude
from solver.installation.case import InstallationCase
from solver.installation.frequencies import Excitation
from solver.post import report

__all__ = ["SCENARIOS", "Context", "Scenario"]

LOW_FRICTION = ["friction.mu_s=0.0625", "friction.mu_d=0.05"]  #: docs/physics.md §4 study values
MESH_AGREEMENT = 0.05  #: S1: settlement of the two meshes within this fraction [-]
PULL_FACTORS = (1.0, 1.25)  #: S5: pulls alone, multiples of the self-weight force
AMPLITUDE_N = 3600.0  #: S5: vibration amplitude (docs/physics.md §3) [N]
#: S7: the step-wise sweep's dwell and the slow ramp's duration, in vibration stages
#: (``vibration.stage_duration_s``: 0.03 and 0.1 s on the default joint), the fast ramp's speed-up
#: and the ramps' span about the best mode (a fraction of its frequency)
SWEEP_DWELL, RAMP_SLOW, RAMP_SPEED_UP, RAMP_SPAN = 0.3, 1.0, 4.0, 0.03
#: S6: the vibration halves' cases, and their lead-in and branches, in vibration stages
SLOW_DECAY, MODAL_DAMPING = ["friction.d_c=1"], ['damping.model="modal"']
SELECTIVITY_LEAD_IN = SELECTIVITY_BRANCH = 0.5
NEAR_MODE = 0.05  #: S7: a step within this fraction of a natural frequency is at that mode
OFF_MODE = 0.1  #: S7 probe: a step farther than this fraction from every natural frequency
RAMP_BANDS = 8  #: S7 probe: parts of the ramps' span


@dataclass
class Context:
    """Where and on what the scenarios run: the case (preset name or file) with its overrides,
    the output folder (one sub-folder per scenario and per shared run)."""

    comm: MPI.Comm
    case_name: str
    overrides: list[str]
    output: Path
    #: output folder of an installation run of the case (``demos/install.py``): S2 and S4
    #: read its stages, S3, S4 and S5 also run from its last checkpoint, S8 also has the
    #: frequencies there
    installed: Path | None = None

    def case(self, extra: list[str] = ()) -> InstallationCase:
        return InstallationCase.from_dict(read_case(self.case_name, [*self.overrides, *extra]))

    def joint(self) -> str:
        """The joint in words (for the page)."""
        c = self.case()
        return (
            f"`{self.case_name}` {' '.join(self.overrides)}: {c.mesh.n_circumferential} around, "
            f"{1e3 * c.mesh.axial_size:g} mm axially ({1e3 * c.mesh.contact_axial_size:g} mm in "
            f"the contact zone, {1e3 * c.mesh.contact_zone_above:g} mm above the TP's lower "
            f"edge), degree {c.contact.degree}, mu at the "
            + (
                "previous step's slip speed"
                if c.contact.lagged_friction
                else "step's own slip speed"
            )
        ).replace("` :", "`:")

    def self_weight(
        self, name: str, extra: list[str] = (), modes_at_s=(), until_s: float | None = None
    ) -> dict[str, Any]:
        return self_weight_run(
            self.comm,
            self.case_name,
            [*self.overrides, *extra],
            self.output / "runs" / name,
            modes_at_s,
            until_s,
        )

    def reference(self) -> dict[str, Any]:
        """The case's self-weight stage with the modes at half the load and at its end (S1, S6,
        S8 share it)."""
        sw = self.case().self_weight
        return self.self_weight("reference", modes_at_s=(0.5 * sw.ramp_time_s, sw.duration_s))

    def figure(self, key: str, name: str) -> tuple[Path, str]:
        """Path of figure ``name`` of scenario ``key`` and its path relative to the folder."""
        folder = self.output / key
        if self.comm.rank == 0:
            folder.mkdir(parents=True, exist_ok=True)
        return folder / name, name


def _events(r: dict[str, Any]) -> str:
    sizes = ", ".join(f"{1e3 * e:.0f}" for e in r["events_mm"])
    n = len(r["events_mm"])
    return f"{n} event{'' if n == 1 else 's'} ({sizes} um)"


def s1_self_weight(ctx: Context) -> Outcome:
    """S1: the self-weight ramp on the case's mesh and on one with half its axial size."""
    axial = ctx.case().mesh.axial_size
    labels = (f"{1e3 * axial:g} mm", f"{0.5e3 * axial:g} mm")
    runs = {
        labels[0]: ctx.reference(),
        labels[1]: ctx.self_weight("half_axial", [f"mesh.axial_size={0.5 * axial}"]),
    }
    rows = [
        Row(
            f"stick-slip steps under the ramp, {label} mesh (at least 2 events, §5.1)",
            f"{_events(r)}; settlement {r['settlement_mm'][-1]:.4f} mm",
            verdict(len(r["events_mm"]) >= 2),
        )
        for label, r in runs.items()
    ]
    s = [r["settlement_mm"][-1] for r in runs.values()]
    rows.append(
        Row(
            f"settlement of the two meshes within {100 * MESH_AGREEMENT:g} %",
            f"{s[0]:.4f} mm against {s[1]:.4f} mm ({100 * (s[1] / s[0] - 1):+.2f} %)",
            verdict(abs(s[1] / s[0] - 1) < MESH_AGREEMENT),
        )
    )
    path, name = ctx.figure("S1", "settlement.png")
    if ctx.comm.rank == 0:
        figures.plot_settlement(runs, path, "S1: self-weight ramp, two axial mesh sizes")
    return _outcome(ctx, "S1", rows, runs, [name, "../runs/reference/contact_status.png"])


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
            "stages of the sequence in the run (docs/physics.md §3 asks for the ten best-ranked "
            "modes: `--full`)",
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
    return _outcome(ctx, "S2", rows, runs, names)


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
    return _outcome(ctx, "S3", rows, {"amplitude": r}, names)


def s4_modes(ctx: Context) -> Outcome:
    """S4 on the installation run ``ctx.installed``: the settlement rate over the second half of
    each of its modal stages (S2's, all at the modal amplitude) by the rank of the mode, whether
    the (m, n) = (2, 1) mode is the most effective (a probe: the modal stage's indicator of
    those modes, ``_resonant_slip_rows``), and from the installed state, at the lowest
    anti-symmetric mode, axial forcing against axial plus the case's lateral fraction
    (``benchmarks.atlas.direction``)."""
    if ctx.installed is None:
        raise ValueError("S4 reads an installation run: --installed RUN")
    case = ctx.case()
    amplitude = case.vibration.amplitude_N
    manifest = installed_state(ctx.comm, case, ctx.installed)
    excitations = [Excitation(**e) for e in manifest["excitations"]]
    modal = sorted(
        (
            (report.sustained_rate_mm_s(s), excitations[s["stage"] - 1])
            for s in manifest["stages"]
            if s["stage"] >= 1 and s["steps"] and excitations[s["stage"] - 1].role == "modal"
        ),
        key=lambda p: p[1].rank,
    )
    rows = []
    if modal:
        rows.append(
            Row(
                f"settlement rate over the second half per ranked mode at {amplitude / 1e3:g} kN "
                "(S2's stages, each from the state the one before left)",
                "; ".join(
                    f"rank {e.rank}, ({e.m}, {e.n}), {e.frequency_Hz:.2f} Hz: {rate:.3f} mm/s"
                    for rate, e in modal
                ),
                "measured",
            )
        )
        best_rate, best = max(modal, key=lambda p: p[0])
        measured = (
            f"the fastest: ({best.m}, {best.n}) at {best.frequency_Hz:.2f} Hz, {best_rate:.3f} mm/s"
        )
        m2n1 = [(rate, e) for rate, e in modal if (e.m, e.n) == (2, 1)]
        if m2n1 and (best.m, best.n) != (2, 1):
            rate, e = m2n1[0]
            ratio = f" ({rate / best_rate:.2f} x)" if best_rate > 0 else ""
            measured += f"; (2, 1) at {e.frequency_Hz:.2f} Hz {rate:.3f} mm/s{ratio}"
        elif not m2n1:
            measured += "; no (2, 1) stage in the run"
        rows.append(
            Row(
                "the most effective mode is (m, n) = (2, 1) (§5.4; stages in the order of S2)",
                measured,
                verdict((best.m, best.n) == (2, 1)),
            )
        )
        rows += _resonant_slip_rows(ctx.installed, modal, amplitude, case.vibration.direction)
    r = direction_runs(
        ctx.comm,
        ctx.case_name,
        ctx.overrides,
        ctx.output / "runs" / "direction_installed",
        ctx.installed,
        amplitude,
    )
    lateral = f"axial + {100 * r['lateral_fraction']:g} % lateral"
    names = []
    if r["mode"] is None:
        rows.append(
            Row(
                f"{lateral} settles more than axial alone at an anti-symmetric mode (§5.4)",
                "not run: the run has no m = 1 mode among the modes of its modal stage (or no "
                "modal stage)",
                "not reproduced",
            )
        )
    else:
        e = Excitation(**r["mode"])
        gain = {d: b[-1][1] - b[0][1] for d, b in r["branches"].items()}
        ratio = f" ({gain['both'] / gain['axial']:.2f} x)" if gain["axial"] > 0 else ""
        rows.append(
            Row(
                f"from the installed state (t = {r['request']['time_s']:.2f} s), at the lowest "
                f"anti-symmetric mode (m, n) = (1, {e.n}), {e.frequency_Hz:.2f} Hz (rank "
                f"{e.rank}, driven at {e.drive_Hz:.2f} Hz), {amplitude / 1e3:g} kN: {lateral} "
                "settles more than axial alone (§5.4)",
                f"{1e3 * gain['both']:.1f} um against {1e3 * gain['axial']:.1f} um{ratio} in "
                f"{1e3 * case.vibration.stage_duration_s:g} ms",
                verdict(gain["both"] > gain["axial"]),
            )
        )
        reversed_ratio = (
            f" ({gain['both reversed'] / gain['axial']:.2f} x)" if gain["axial"] > 0 else ""
        )
        rows.append(
            Row(
                "probe: the same with the lateral part reversed (the modal force of a lateral "
                "part adds to the axial part's or opposes it, by the orientation of the mode)",
                f"{1e3 * gain['both reversed']:.1f} um against {1e3 * gain['axial']:.1f} um"
                f"{reversed_ratio}",
                "measured",
            )
        )
        path, name = ctx.figure("S4", "direction.png")
        if ctx.comm.rank == 0:
            figures.plot_branches(
                {
                    "axial": r["branches"]["axial"],
                    lateral: r["branches"]["both"],
                    f"{lateral}, reversed": r["branches"]["both reversed"],
                },
                path,
                f"S4: the ({e.m}, {e.n}) mode at {e.frequency_Hz:.1f} Hz from the installed state",
            )
        names.append(name)
    return _outcome(ctx, "S4", rows, {"direction": r}, names)


def _branch_state(b: dict[str, Any]) -> str:
    t, s, n = np.array(b["rows"]).T
    return (
        f"after {1e3 * (t[-1] - t[0]):.0f} ms the TP {s[0] - s[-1]:+.3f} mm up "
        f"({lift_rate(b['rows']):+.2f} mm/s over the second half), normal force "
        f"{1e-3 * n[-1]:.2f} kN"
    )


def _release_word(b: dict[str, Any], settled_normal_N: float, slip_rate_mm_s: float) -> str:
    """How dismount branch ``b`` ends, in words: separated or released (by
    ``benchmarks.atlas.dismount.released``, from a state with the contact normal force
    ``settled_normal_N`` [N] and the event threshold ``slip_rate_mm_s`` [mm/s]), or it holds,
    lifting or not, and where it stands against its first-contact position."""
    rows = b["rows"]
    if separated(rows, settled_normal_N):
        return "separated"
    if released(rows, settled_normal_N, slip_rate_mm_s):
        return "released: above its first-contact position and lifting"
    place = "below" if rows[-1][1] >= 0.0 else "above"
    where = f"{abs(rows[-1][1]):.3f} mm {place} its first-contact position at the end"
    if lift_rate(rows) > slip_rate_mm_s:
        return f"holds, lifting, {where}"
    return f"holds, {where}"


def _dismount_rows(r: dict[str, Any], state: str, slip_rate_mm_s: float) -> list[Row]:
    """The S5 rows of the dismount runs ``r`` from ``state`` (words), with the case's event
    threshold ``slip_rate_mm_s`` [mm/s] (``_release_word``)."""
    b, out = r["branches"], r["pull_out_N"]
    n0 = r["settled"]["normal_N"]
    settled = (
        f"{state} {r['settled']['settlement_mm']:.3f} mm, normal force "
        f"{1e-3 * r['settled']['normal_N']:.2f} kN, rigid Coulomb pull-out "
        f"{1e-3 * out['mu_d']:.2f} / {1e-3 * out['mu_s']:.2f} kN (mu_d / mu_s)"
    )
    pull = r["self_weight_N"] * PULL_FACTORS[0]
    first = b[f"pull {PULL_FACTORS[0]:g} x"]
    rows = [
        Row(
            f"{state}: pull alone at the self-weight force ({1e-3 * pull:g} kN) does not "
            "release (§5.5)",
            f"{_branch_state(first)}; {_release_word(first, n0, slip_rate_mm_s)}; {settled}",
            verdict(not first["released"]),
        )
    ]
    for factor in PULL_FACTORS[1:]:
        branch = b[f"pull {factor:g} x"]
        rows.append(
            Row(
                f"{state}: pull alone at {factor:g} x the self-weight force "
                f"({1e-3 * factor * r['self_weight_N']:g} kN)",
                f"{_branch_state(branch)}; {_release_word(branch, n0, slip_rate_mm_s)}",
                "measured",
            )
        )
    if "modal" not in b:  # the pull alone released the joint: no pulled state to vibrate
        rows.append(
            Row(
                f"{state}: pull + vibration: the best mode releases, the control does not",
                f"not run: the pull alone releases the joint (rigid pull-out with mu_s "
                f"{1e-3 * out['mu_s']:.2f} kN against the {1e-3 * pull:g} kN pull)",
                "not reproduced",
            )
        )
        return rows
    for name, wanted in (("modal", True), ("control", False)):
        branch = b[name]
        rows.append(
            Row(
                f"{state}: pull + {branch['amplitude_N'] / 1e3:g} kN at the "
                f"{'best mode' if wanted else 'control'} ({branch['frequency_Hz']:.2f} Hz, "
                f"driven at {branch['forcing_Hz']:.2f} Hz) "
                f"{'releases' if wanted else 'does not release'}",
                f"{_branch_state(branch)}; {_release_word(branch, n0, slip_rate_mm_s)}",
                verdict(branch["released"] == wanted),
            )
        )
    lift = {k: b[k]["rows"][0][1] - b[k]["rows"][-1][1] for k in ("modal", "control")}
    rows.append(
        Row(
            f"{state}: pull + vibration lifts the TP more at the best mode than at the control",
            f"{lift['modal']:.3f} mm against {lift['control']:.3f} mm "
            f"({lift['modal'] / lift['control']:.1f} x)"
            if lift["control"] > 0
            else f"{lift['modal']:.3f} mm against {lift['control']:.3f} mm",
            "measured",
        )
    )
    rows.append(
        Row(
            f"{state}: resonance-selective release: the modal branch releases, the control "
            "does not",
            f"modal {_release_word(b['modal'], n0, slip_rate_mm_s)}, control "
            f"{_release_word(b['control'], n0, slip_rate_mm_s)}",
            verdict(b["modal"]["released"] and not b["control"]["released"]),
        )
    )
    return rows


def _motors_rows(
    r: dict[str, Any], base: dict[str, Any], state: str, slip_rate_mm_s: float
) -> list[Row]:
    """S5 probe rows: the dismount runs ``r`` with the motors' force at the best mode, made where
    those at the atlas's amplitude (``base``) did not release; the peak upward force of both
    against the rigid Coulomb pull-out (``_release_word`` with ``slip_rate_mm_s`` [mm/s])."""
    pull, out = base["self_weight_N"] * PULL_FACTORS[0], base["pull_out_N"]
    forces = (
        base["branches"]["modal"]["amplitude_N"],
        float(eccentric_amplitude(base["branches"]["modal"]["frequency_Hz"])),
    )
    peaks = "; ".join(f"pull + {f / 1e3:.2f} kN: peak {(pull + f) / 1e3:.2f} kN" for f in forces)
    rows = [
        Row(
            f"probe: {state}: the peak upward force of pull + vibration against the rigid "
            "Coulomb pull-out (a quasi-static pull above it releases)",
            f"{peaks}; pull-out {1e-3 * out['mu_d']:.2f} / {1e-3 * out['mu_s']:.2f} kN "
            "(mu_d / mu_s)",
            "measured",
        )
    ]
    b, n0 = r["branches"], r["settled"]["normal_N"]
    if "modal" not in b:  # the pull alone released the joint: no pulled state to vibrate
        return rows
    parts = [
        f"{name} ({b[name]['frequency_Hz']:.2f} Hz, driven at {b[name]['forcing_Hz']:.2f} Hz): "
        f"{_branch_state(b[name])}; {_release_word(b[name], n0, slip_rate_mm_s)}"
        for name in ("modal", "control")
    ]
    rows.append(
        Row(
            f"probe: {state}: pull + the eccentric motors' force at the best mode, 0.3632 f^2 = "
            f"{forces[1] / 1e3:.2f} kN (the experiments' exciter, docs/physics.md §3), at the "
            "best mode and at the control with the same force: the modal branch releases, the "
            "control does not",
            "; ".join(parts),
            "measured",
        )
    )
    return rows


def _plot_dismount(ctx: Context, r: dict[str, Any], file: str, title: str) -> str:
    """Figure ``file`` of S5: settlement of every branch of the dismount runs ``r``."""
    path, name = ctx.figure("S5", file)

    def label(key: str, branch: dict[str, Any]) -> str:
        if key.startswith("pull"):
            return f"{key} the self-weight force alone"
        force, f = 1e-3 * branch["amplitude_N"], branch["frequency_Hz"]
        return f"pull + {force:.2f} kN, {key} ({f:.1f} Hz)"

    if ctx.comm.rank == 0:
        figures.plot_branches(
            {label(k, v): v["rows"] for k, v in r["branches"].items()}, path, title
        )
    return name


def _resonant_slip_rows(
    run_folder: Path, modal: list[tuple[float, Excitation]], amplitude_N: float, direction: str
) -> list[Row]:
    """S4 probe: the linear indicator the modal stage ranks the modes by (the resonant interface
    slip, docs/modal.md, in its ``modes.csv`` for the motors' amplitude 0.3632 f^2 at the
    eccentric point; it scales with the force) for each modal stage's mode at the stages'
    amplitude ``amplitude_N`` [N] and at the motors' (none where the run kept no table)."""
    table = {int(r["mode"]): r for r in modal_table(run_folder)}
    part = "lateral" if direction == "lateral" else "axial"  # "both": its axial part
    column = f"resonant_slip_{part}_um"
    parts = []
    for _, e in modal:
        if e.mode in table:
            motors_N = float(eccentric_amplitude(e.frequency_Hz))
            slip = float(table[e.mode][column])
            parts.append(
                f"({e.m}, {e.n}) at {e.frequency_Hz:.2f} Hz: {slip * amplitude_N / motors_N:.1f} "
                f"um ({slip:.1f} um at {motors_N / 1e3:.2f} kN)"
            )
    if not parts:
        return []
    return [
        Row(
            f"probe: the modal stage's indicator for each mode, the linear resonant interface slip "
            f"(modal force / (2 zeta omega^2) x slip per unit modal amplitude, zeta the case's "
            "damping ratio), "
            f"{part} at the eccentric point, at {amplitude_N / 1e3:g} kN (and at the motors' "
            "0.3632 f^2)",
            "; ".join(parts),
            "measured",
        )
    ]


def s5_dismount(ctx: Context) -> Outcome:
    """S5: pulls alone at 1 and 1.25 times the self-weight force; the first pull plus vibration
    at the best mode and at the control frequency (``benchmarks.atlas.dismount``), each phase
    half as long as the case's vibration stages (0.05 s on the default joint): from the joint
    settled by self-weight and, where ``ctx.installed`` names an installation run of the case,
    from its last checkpoint."""
    half_stage = 0.5 * ctx.case().vibration.stage_duration_s
    runs = {
        "settled": dismount_runs(
            ctx.comm,
            ctx.case_name,
            ctx.overrides,
            ctx.output / "runs" / "dismount",
            PULL_FACTORS,
            AMPLITUDE_N,
            half_stage,
        )
    }
    slip_rate = ctx.case().output.slip_rate_mm_s
    rows = _dismount_rows(runs["settled"], "settled by self-weight", slip_rate)
    names = [
        _plot_dismount(ctx, runs["settled"], "dismount.png", "S5: dismount from the settled joint")
    ]
    if ctx.installed is not None:
        runs["installed"] = r = dismount_runs(
            ctx.comm,
            ctx.case_name,
            ctx.overrides,
            ctx.output / "runs" / "dismount_installed",
            PULL_FACTORS,
            AMPLITUDE_N,
            half_stage,
            ctx.installed,
        )
        state = f"installed (t = {r['settled']['time_s']:.2f} s)"
        rows += _dismount_rows(r, state, slip_rate)
        held = "modal" in r["branches"] and not r["branches"]["modal"]["released"]
        if held:  # the probe: the force of the experiments' exciter
            runs["installed, motors"] = motors = dismount_runs(
                ctx.comm,
                ctx.case_name,
                ctx.overrides,
                ctx.output / "runs" / "dismount_installed_motors",
                PULL_FACTORS[:1],
                None,
                half_stage,
                ctx.installed,
            )
            rows += _motors_rows(motors, r, state, slip_rate)
            names.append(
                _plot_dismount(
                    ctx,
                    motors,
                    "dismount_motors.png",
                    "S5: dismount from the installed joint, the motors' force",
                )
            )
        names.append(
            _plot_dismount(
                ctx, r, "dismount_installed.png", "S5: dismount from the installed joint"
            )
        )
    return _outcome(ctx, "S5", rows, runs, names)


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
    return _outcome(ctx, "S6", rows, runs, names)


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
    return _outcome(ctx, "S8", rows, runs, [name, *names])


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
            + ", ".join(f"{f:g} Hz {0.3632 * f**2 / 1e3:.2f}" for f in freqs)
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
    return _outcome(ctx, "S7", rows, {"sweeps": r, "unexcited": unexcited}, names)


def _outcome(
    ctx: Context, key: str, rows: list[Row], runs: dict[str, dict], figure_names: list[str]
) -> Outcome:
    """The outcome of scenario ``key`` with the wall times of the runs it used."""
    return Outcome(
        key,
        SCENARIOS[key].title,
        ctx.joint(),
        rows,
        {r["name"]: r["wall_s"] for r in runs.values()},
        ctx.comm.size,
        figure_names,
    )


@dataclass(frozen=True)
class Scenario:
    """A scenario: its title, its criterion, and the function that runs it."""

    title: str
    criterion: str
    run: Callable[[Context], Outcome]
    #: it reads an installation run of the case (``--installed``)
    installed: bool = False


SCENARIOS: dict[str, Scenario] = {
    "S1": Scenario(
        "self-weight ramp, two axial mesh sizes",
        "stick-slip steps (count and size of the events); settlement of both meshes; the same "
        "qualitative behaviour",
        s1_self_weight,
    ),
    "S2": Scenario(
        "reference sequence, ten best-ranked modes and a control at 3.6 kN",
        "per stage the settlement gained and the sustained rate; modal stages at least 5 times "
        "the control; the last 20 % of a stage adds less than 5 % of its gain",
        s2_sequence,
        installed=True,
    ),
    "S3": Scenario(
        "amplitude-driven settlement at two non-modal frequencies",
        "the amplitude threshold bracketed to 10 %; above it settlement off resonance, below "
        "it none",
        s3_amplitude,
        installed=True,
    ),
    "S4": Scenario(
        "which modes work",
        "settlement rate per ranked mode at equal force; axial against axial plus 5 % lateral "
        "at an anti-symmetric mode",
        s4_modes,
        installed=True,
    ),
    "S5": Scenario(
        "dismount",
        "pull alone at 1 and 1.25 times the self-weight force; pull plus vibration at the best "
        "mode releases, at the control frequency it does not",
        s5_dismount,
    ),
    "S6": Scenario(
        "friction and damping",
        "lower friction settles more under self-weight; d_c = 1 against 100 and Rayleigh "
        "against modal damping: the selectivity ratio of S2 (its two-stage form: one mode, "
        "the control)",
        s6_friction,
    ),
    "S7": Scenario(
        "sweeps",
        "step-wise 10 to 130 Hz; a fast linear ramp across the best mode settles less than a "
        "slow one",
        s7_sweeps,
    ),
    "S8": Scenario(
        "stiffening",
        "natural frequencies of the settled joint rise with settlement; against a bonded band "
        "of the same height",
        s8_stiffening,
    ),
}


def run_scenario(ctx: Context, key: str) -> Outcome:
    """Run scenario ``key`` (collective); its outcome is saved in ``output/key``."""
    t0 = time.perf_counter()
    outcome = SCENARIOS[key].run(ctx)
    if ctx.comm.rank == 0:
        outcome.save(ctx.output / key / "outcome.json")
        print(f"{key}: {outcome.title} ({time.perf_counter() - t0:.0f} s)", flush=True)
    return outcome
