"""Reports of an installation run: stage summaries, stick-slip events, frequency selectivity,
the tables and the printed summary.

Files of a run (in the output folder; CSV headers carry units; the pictures are
``solver.post.plots``', the ParaView files ``solver.post.paraview``'s):

* ``history.csv``: one row per accepted time step (``HISTORY_COLUMNS``);
* ``stages.csv``: one row per stage (settlement gained, stick-slip events, ...);
* ``frequencies.csv``: the excitation stages and the reason for each;
* ``settlement.png`` (settlement and excitation frequency against time),
  ``stage_gain.png`` (settlement gained per stage against frequency),
  ``contact_status_<k>.png`` (contact status unwrapped in angle and z after stage k);
* ``displacement_<k>.bp`` (VTX) and ``contact_<k>.vtp`` (slave points with status,
  pressure, slip velocity) after stage k;
* ``summary.txt``: the one-screen summary printed at the end, with the frequency selectivity
  of the run (``frequency_selectivity``).

Stick-slip events: the TP slips as a whole while its settlement rate, averaged over one
excitation period in vibration stages (one step otherwise), exceeds ``slip_rate_mm_s``;
an event is a transition from below to above that rate.
"""

from dataclasses import asdict
from pathlib import Path
from typing import Any

import numpy as np
from mpi4py import MPI

from solver.contact import NitscheContact, Status
from solver.post.csv import write_csv

HISTORY_COLUMNS = [
    "time_s",
    "dt_s",
    "stage",
    "frequency_Hz",
    "amplitude_N",
    "axial_force_N",
    "settlement_mm",
    "newton_iterations",
    "step_cuts",
    "stick_fraction",
    "slip_fraction",
    "normal_force_N",
]
STAGE_COLUMNS = [
    "stage",
    "name",
    "start_s",
    "end_s",
    "dt_s",
    "frequency_Hz",
    "amplitude_N",
    "steps",
    "settlement_start_mm",
    "settlement_end_mm",
    "gained_mm",
    "gained_second_half_mm",
    "gained_last_20pct_mm",
    "stick_slip_events",
    "newton_iterations_mean",
    "newton_iterations_max",
    "step_cuts",
    "natural_frequency_Hz",
    "steps_per_period",
    "algorithmic_damping",
    "period_error",
    "physical_damping",
    "wall_s",
    "reason",
]

#: docs/physics.md §5.2 "each event comes to rest", judged by the criterion of
#: docs/scenarios.md, S2: the last LATE of a stage ...
LATE = 0.2
LATE_SHARE = 0.05  #: ... adds less than LATE_SHARE of the stage's gain [-]


def slip_episodes(
    time_s: np.ndarray,
    settlement_mm: np.ndarray,
    s0_mm: float,
    t0_s: float,
    window: int,
    slip_rate_mm_s: float,
) -> list[float]:
    """Settlement [mm] gained in each stick -> slip -> stick episode of the TP as a whole (see the
    module docstring; an episode still running at the end counts up to there)."""
    t = np.concatenate([[t0_s], time_s])
    s = np.concatenate([[s0_mm], settlement_mm])
    if len(t) < 2:
        return []
    window = min(window, len(t) - 1)  # a stage shorter than one period: its mean rate
    rate = (s[window:] - s[:-window]) / (t[window:] - t[:-window])  # over rows i .. i + window
    above = np.concatenate([[False], rate > slip_rate_mm_s, [False]])
    first = np.flatnonzero(~above[:-1] & above[1:])  # window starts of each episode's first ...
    last = np.flatnonzero(above[:-1] & ~above[1:]) - 1  # ... and last rate above the threshold
    return [float(s[j + window] - s[i]) for i, j in zip(first, last)]


def stick_slip_events(
    time_s: np.ndarray,
    settlement_mm: np.ndarray,
    s0_mm: float,
    t0_s: float,
    window: int,
    slip_rate_mm_s: float,
) -> int:
    """Transitions stick -> slip of the TP as a whole (see the module docstring)."""
    return len(slip_episodes(time_s, settlement_mm, s0_mm, t0_s, window, slip_rate_mm_s))


def late_gain(time_s: np.ndarray, settlement_mm: np.ndarray, fraction: float) -> float:
    """Settlement gained over the last ``fraction`` of the time span of a history [mm]
    (linear between the rows; the first row is the state the stage started from)."""
    t, s = np.asarray(time_s), np.asarray(settlement_mm)
    return float(s[-1] - np.interp(t[-1] - fraction * (t[-1] - t[0]), t, s))


def stage_summary(
    index: int, plan, rows: list[dict], history: list[dict], slip_rate_mm_s: float
) -> dict[str, Any]:
    """Summary of stage ``index`` from its history rows."""
    before = [r for r in history if r["stage"] < index]
    s0 = before[-1]["settlement_mm"] if before else 0.0
    t0 = before[-1]["time_s"] if before else plan.start_s
    t = np.array([r["time_s"] for r in rows])
    s = np.array([r["settlement_mm"] for r in rows])
    its = np.array([r["newton_iterations"] for r in rows]) if rows else np.zeros(1)
    window = max(1, round(1.0 / (plan.frequency_Hz * plan.dt_s))) if plan.frequency_Hz > 0 else 1
    ts, ss = np.r_[t0, t], np.r_[s0, s]
    return {
        "stage": index,
        "name": plan.name,
        "start_s": plan.start_s,
        "end_s": plan.end_s,
        "dt_s": plan.dt_s,
        "frequency_Hz": plan.frequency_Hz,
        "amplitude_N": plan.amplitude_N,
        "steps": len(rows),
        "settlement_start_mm": s0,
        "settlement_end_mm": float(s[-1]) if len(s) else s0,
        "gained_mm": (float(s[-1]) if len(s) else s0) - s0,
        "gained_second_half_mm": late_gain(ts, ss, 0.5),
        "gained_last_20pct_mm": late_gain(ts, ss, LATE),
        "stick_slip_events": stick_slip_events(t, s, s0, t0, window, slip_rate_mm_s),
        "newton_iterations_mean": float(its.mean()),
        "newton_iterations_max": int(its.max()),
        "step_cuts": int(sum(r.get("step_cuts", 0) for r in rows)),
        "natural_frequency_Hz": plan.natural_frequency_Hz,
        "steps_per_period": plan.steps_per_period,
        "algorithmic_damping": plan.algorithmic_damping,
        "period_error": plan.period_error,
        "physical_damping": plan.physical_damping,
        "reason": plan.reason,
    }


def write_stage_table(stages: list[dict], path: Path, comm: MPI.Comm) -> None:
    """``stages.csv``: one row per stage (``STAGE_COLUMNS``)."""
    write_csv(path, STAGE_COLUMNS, stages, comm)


CHOICE_COLUMNS = ["frequency_Hz", "amplitude_N", "role", "mode", "m", "n", "rank", "reason"]


def write_choice(excitations, path: Path, comm: MPI.Comm) -> None:
    """``frequencies.csv``: frequency_Hz, amplitude_N, role, mode, m, n, rank, reason."""
    write_csv(path, CHOICE_COLUMNS, [asdict(e) for e in excitations], comm)


def format_stage(s: dict) -> str:
    """One line per stage: frequency, steps, settlement, events, Newton iterations, step cuts and,
    for a vibration stage, the time scheme's algorithmic damping and period error there."""
    f = f"{s['frequency_Hz']:7.2f} Hz" if s["frequency_Hz"] else "   static "
    line = (
        f"{s['name']:>12}: {f}, {s['steps']:5d} steps, settlement {s['settlement_end_mm']:8.4f} mm "
        f"({s['gained_mm']:+.4f} mm), {s['stick_slip_events']} stick-slip event(s), "
        f"Newton {s['newton_iterations_mean']:.2f}/step, {s.get('step_cuts', 0)} step cut(s)"
    )
    if s.get("steps_per_period"):
        natural = (
            f", mode {s['natural_frequency_Hz']:.2f} Hz" if s.get("natural_frequency_Hz") else ""
        )
        line += (
            f"\n{'':>14}{s['steps_per_period']:.1f} steps/period{natural}: algorithmic damping "
            f"{100 * max(0.0, s['algorithmic_damping']):.4f} % (physical {100 * s['physical_damping']:.3g} %), "
            f"period error {100 * s['period_error']:+.3f} %"
        )
    return line


#: frequency-driven settlement (docs/physics.md §5.2), judged by the criterion of
#: docs/scenarios.md, S2: a modal stage settles >= SELECTIVE x as fast as the control [-]
SELECTIVE = 5.0


def stabilised(gained_mm: float, late_gained_mm: float) -> bool:
    """A stage whose event came to rest (docs/physics.md §5.2), by the criterion of
    docs/scenarios.md, S2: it settled (gain > 0) and its last ``LATE`` added less than
    ``LATE_SHARE`` of its gain."""
    return gained_mm > 0 and abs(late_gained_mm) < LATE_SHARE * gained_mm


def format_stabilisation(stages: list[dict]) -> list[str]:
    """Summary lines: which vibration stages ended at rest (docs/physics.md §5.2; ``stabilised``,
    the criterion of docs/scenarios.md, S2), with the share of their gain in their last 20 %;
    none without vibration stages."""
    groups: dict[str, list[str]] = {"stabilised": [], "still settling": [], "no settlement": []}
    for s in stages:
        if not s["frequency_Hz"] or not s["steps"]:
            continue
        f = f"{s['frequency_Hz']:.1f} Hz"
        if s["gained_mm"] <= 0:
            groups["no settlement"].append(f)
        else:
            share = f"{f} ({100 * s['gained_last_20pct_mm'] / s['gained_mm']:.1f} %)"
            key = (
                "stabilised"
                if stabilised(s["gained_mm"], s["gained_last_20pct_mm"])
                else "still settling"
            )
            groups[key].append(share)
    if not any(groups.values()):
        return []
    return [
        f"settlement events (docs/physics.md §5.2; docs/scenarios.md, S2: stabilised when the last "
        f"{100 * LATE:g} % of the stage adds < {100 * LATE_SHARE:g} % of its gain):",
        *(f"  {key}: {', '.join(items)}" for key, items in groups.items() if items),
    ]


def sustained_rate_mm_s(stage: dict[str, Any]) -> float:
    """A stage's sustained settlement rate: its gain over its second half over that half's
    duration [mm/s] (``stage_summary``; the first half also holds the event in which the joint
    settles to the depth that holds the new excitation)."""
    return 2 * stage["gained_second_half_mm"] / (stage["end_s"] - stage["start_s"])


def rate_ratio(rate: float, control_rate: float) -> float:
    """A settlement rate over the control's [-]: inf where only the first settles, 0 where
    neither does."""
    return rate / control_rate if control_rate > 0 else (np.inf if rate > 0 else 0.0)


def frequency_selectivity(stages: list[dict], excitations) -> list[dict[str, float]]:
    """Sustained settlement rate of each modal vibration stage over that of the control stage
    at the same amplitude (docs/physics.md §5.2: frequency-driven settlement).

    ``stages`` are the stage summaries (stage 0 the self-weight, stage k >= 1 excited by
    ``excitations[k - 1]``). The sustained rate is the gain over the second half of a stage
    over its duration [mm/s]: the first half also holds the event in which the joint settles
    to the depth that holds the new excitation (docs/physics.md §5.2: each event comes to
    rest), which at a non-modal frequency is all it settles, and the tail of the previous
    stage. The rate over the whole stage is given too. One row per modal stage: frequency_Hz,
    rate_mm_s, stage_rate_mm_s, control_Hz, control_rate_mm_s, control_stage_rate_mm_s, ratio
    (sustained; when the control did not settle: inf if the modal stage did, else 0),
    stage_ratio; empty without a control.
    """
    roles = {k + 1: e for k, e in enumerate(excitations)}

    def rates(s: dict) -> tuple[float, float]:
        return sustained_rate_mm_s(s), s["gained_mm"] / (s["end_s"] - s["start_s"])

    controls = [s for s in stages if s["stage"] in roles and roles[s["stage"]].role == "control"]
    if not controls or not controls[0]["steps"]:
        return []
    control = controls[0]
    c, c_stage = rates(control)
    rows = []
    for s in stages:
        e = roles.get(s["stage"])
        if (
            e is None
            or e.role != "modal"
            or not s["steps"]
            or e.amplitude_N != roles[control["stage"]].amplitude_N
        ):
            continue
        r, r_stage = rates(s)
        rows.append(
            {
                "frequency_Hz": s["frequency_Hz"],
                "rate_mm_s": r,
                "stage_rate_mm_s": r_stage,
                "control_Hz": control["frequency_Hz"],
                "control_rate_mm_s": c,
                "control_stage_rate_mm_s": c_stage,
                "ratio": rate_ratio(r, c),
                "stage_ratio": rate_ratio(r_stage, c_stage),
            }
        )
    return rows


def format_selectivity(rows: list[dict[str, float]]) -> list[str]:
    """Summary lines of ``frequency_selectivity`` (none without a control stage)."""
    if not rows:
        return []
    shown = all(r["ratio"] >= SELECTIVE for r in rows)
    return [
        f"frequency selectivity (docs/physics.md §5.2; docs/scenarios.md, S2: modal stages settle "
        f">= {SELECTIVE:g} x faster than the control, over the second half of each stage): "
        f"{'shown' if shown else 'NOT shown'} by this run",
        f"  control {rows[0]['control_Hz']:8.2f} Hz: {rows[0]['control_rate_mm_s']:+.4f} mm/s "
        f"(whole stage {rows[0]['control_stage_rate_mm_s']:+.4f} mm/s)",
        *(
            f"  modal   {r['frequency_Hz']:8.2f} Hz: {r['rate_mm_s']:+.4f} mm/s = {r['ratio']:.2f} x the "
            f"control (whole stage {r['stage_rate_mm_s']:+.4f} mm/s = {r['stage_ratio']:.2f} x)"
            for r in rows
        ),
    ]


def contact_counts(contact: NitscheContact) -> dict[str, float]:
    """Fractions of the slave points open / stick / slip (all ranks)."""
    comm = contact.V.mesh.comm
    st = contact.state.status
    counts = comm.allreduce(np.array([np.count_nonzero(st == s) for s in Status]), op=MPI.SUM)
    return {
        f"{s.name.lower()}_fraction": float(c / max(counts.sum(), 1))
        for s, c in zip(Status, counts)
    }


def summary(stages: list[dict], contact: NitscheContact, history: list[dict]) -> dict[str, Any]:
    normal, friction = contact.forces()
    return {
        "total_settlement_mm": history[-1]["settlement_mm"] if history else 0.0,
        "stick_slip_events": int(sum(s["stick_slip_events"] for s in stages)),
        "steps": len(history),
        "end_time_s": history[-1]["time_s"] if history else 0.0,
        "normal_force_N": normal,
        "friction_force_z_N": float(friction[2]),
        **contact_counts(contact),
    }


def format_summary(summary: dict, stages: list[dict], excitations) -> str:
    lines = ["", "=" * 78, "installation summary", "-" * 78]
    lines += [format_stage(s) for s in stages]
    lines += [
        "-" * 78,
        (
            f"total settlement {summary['total_settlement_mm']:.4f} mm after "
            f"{summary['end_time_s']:.4g} s ({summary['steps']} steps), "
            f"{summary['stick_slip_events']} stick-slip event(s)"
        ),
        (
            f"final contact: {100 * summary['stick_fraction']:.1f} % stick, "
            f"{100 * summary['slip_fraction']:.1f} % slip, "
            f"{100 * summary['open_fraction']:.1f} % open of the TP contact points; "
            f"normal force {summary['normal_force_N'] / 1e3:.2f} kN, "
            f"axial friction {summary['friction_force_z_N'] / 1e3:.2f} kN"
        ),
        "excitation frequencies: "
        + (", ".join(f"{e.frequency_Hz:.1f} Hz ({e.role})" for e in excitations) or "none"),
        *format_stabilisation(stages),
        *format_selectivity(frequency_selectivity(stages, excitations)),
        "=" * 78,
    ]
    return "\n".join(lines)


def write_summary(summary: dict, stages, excitations, path: Path, comm: MPI.Comm) -> None:
    if comm.rank == 0:
        path.write_text(format_summary(summary, stages, excitations) + "\n")


SWEEP_COLUMNS = ["time_s", "frequency_Hz", "amplitude_N", "settlement_mm", "settlement_gain_mm"]


def sweep_rows(history: list[dict], first_stage: int = 1) -> list[dict[str, float]]:
    """Rows of the stages from ``first_stage`` on (the sweep after self-weight): time [s],
    excitation frequency [Hz] and amplitude [N], settlement [mm] and the settlement gained
    since the sweep started [mm]."""
    before = [r for r in history if r["stage"] < first_stage]
    s0 = before[-1]["settlement_mm"] if before else 0.0
    return [
        {
            "time_s": r["time_s"],
            "frequency_Hz": r["frequency_Hz"],
            "amplitude_N": r["amplitude_N"],
            "settlement_mm": r["settlement_mm"],
            "settlement_gain_mm": r["settlement_mm"] - s0,
        }
        for r in history
        if r["stage"] >= first_stage
    ]
