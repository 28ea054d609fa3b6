"""Outputs of an installation run: history and stage tables, events, plots, ParaView, summary.

Files (in the output folder; CSV headers carry units):

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

import csv
import os
from pathlib import Path
from typing import Any

import numpy as np
from mpi4py import MPI

from solver.contact import NitscheContact, Status

HISTORY_COLUMNS = [
    "time_s",
    "dt_s",
    "stage",
    "frequency_Hz",
    "amplitude_N",
    "axial_force_N",
    "settlement_mm",
    "newton_iterations",
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
    "wall_s",
    "reason",
]

LATE = 0.2  #: SPEC 5.2 "each event stabilises": the last LATE of a stage ...
LATE_SHARE = 0.05  #: ... adds less than LATE_SHARE of the stage's gain [-]


def _fmt(v: Any) -> str:
    return f"{v:.10g}" if isinstance(v, float) else str(v)


class HistoryWriter:
    """``history.csv`` written per row (rank 0), starting with ``rows`` already known (resume)."""

    def __init__(self, path: Path, comm: MPI.Comm, rows: list[dict[str, float]] = ()):
        self._file = None
        if comm.rank == 0:
            path.parent.mkdir(parents=True, exist_ok=True)
            self._file = open(path, "w", newline="")
            self._writer = csv.writer(self._file)
            self._writer.writerow(HISTORY_COLUMNS)
            for row in rows:
                self.write(row)

    def write(self, row: dict[str, float]) -> None:
        if self._file is not None:
            self._writer.writerow([_fmt(row[c]) for c in HISTORY_COLUMNS])
            self._file.flush()

    def close(self) -> None:
        if self._file is not None:
            self._file.close()
            self._file = None


def stick_slip_events(
    time_s: np.ndarray,
    settlement_mm: np.ndarray,
    s0_mm: float,
    t0_s: float,
    window: int,
    slip_rate_mm_s: float,
) -> int:
    """Transitions stick -> slip of the TP as a whole (see the module docstring)."""
    t = np.concatenate([[t0_s], time_s])
    s = np.concatenate([[s0_mm], settlement_mm])
    if len(t) < 2:
        return 0
    window = min(window, len(t) - 1)  # a stage shorter than one period: its mean rate
    rate = (s[window:] - s[:-window]) / (t[window:] - t[:-window])
    slipping = np.concatenate([[False], rate > slip_rate_mm_s])
    return int(np.count_nonzero(slipping[1:] & ~slipping[:-1]))


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
        "reason": plan.reason,
    }


def write_table(rows: list[dict], columns: list[str], path: Path, comm: MPI.Comm) -> None:
    if comm.rank == 0:
        path.parent.mkdir(parents=True, exist_ok=True)
        with open(path, "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(columns)
            for r in rows:
                w.writerow([_fmt(r[c]) for c in columns])


def write_stage_table(stages: list[dict], path: Path, comm: MPI.Comm) -> None:
    write_table(stages, STAGE_COLUMNS, path, comm)


def write_choice(excitations, path: Path, comm: MPI.Comm) -> None:
    """``frequencies.csv``: frequency_Hz, amplitude_N, role, mode, m, n, rank, reason."""
    from dataclasses import asdict

    rows = [asdict(e) for e in excitations]
    write_table(
        rows,
        ["frequency_Hz", "amplitude_N", "role", "mode", "m", "n", "rank", "reason"],
        path,
        comm,
    )


def format_stage(s: dict) -> str:
    f = f"{s['frequency_Hz']:7.2f} Hz" if s["frequency_Hz"] else "   static "
    return (
        f"{s['name']:>12}: {f}, {s['steps']:5d} steps, settlement {s['settlement_end_mm']:8.4f} mm "
        f"({s['gained_mm']:+.4f} mm), {s['stick_slip_events']} stick-slip event(s), "
        f"Newton {s['newton_iterations_mean']:.2f}/step"
    )


SELECTIVE = 5.0  #: SPEC 5.2 criterion: a modal stage settles >= SELECTIVE x the control [-]


def stabilised(gained_mm: float, late_gained_mm: float) -> bool:
    """SPEC 5.2: a stage that settled (gain > 0) whose last ``LATE`` added less than
    ``LATE_SHARE`` of its gain."""
    return gained_mm > 0 and abs(late_gained_mm) < LATE_SHARE * gained_mm


def format_stabilisation(stages: list[dict]) -> list[str]:
    """Summary lines: which vibration stages ended at rest (SPEC 5.2), with the share of their
    gain in their last 20 %; none without vibration stages."""
    groups: dict[str, list[str]] = {"stabilised": [], "still settling": [], "no settlement": []}
    for s in stages:
        if not s["frequency_Hz"] or not s["steps"]:
            continue
        f = f"{s['frequency_Hz']:.1f} Hz"
        if s["gained_mm"] <= 0:
            groups["no settlement"].append(f)
        else:
            share = f"{f} ({100 * s['gained_last_20pct_mm'] / s['gained_mm']:.1f} %)"
            key = "stabilised" if stabilised(s["gained_mm"], s["gained_last_20pct_mm"]) else "still settling"
            groups[key].append(share)
    if not any(groups.values()):
        return []
    return [
        f"settlement events (SPEC 5.2: stabilised when the last {100 * LATE:g} % of the stage adds "
        f"< {100 * LATE_SHARE:g} % of its gain):",
        *(f"  {key}: {', '.join(items)}" for key, items in groups.items() if items),
    ]


def frequency_selectivity(stages: list[dict], excitations) -> list[dict[str, float]]:
    """Sustained settlement rate of each modal vibration stage over that of the control stage
    at the same amplitude (SPEC 5.2: frequency-driven settlement).

    ``stages`` are the stage summaries (stage 0 the self-weight, stage k >= 1 excited by
    ``excitations[k - 1]``). The sustained rate is the gain over the second half of a stage
    over its duration [mm/s]: the first half also holds the event in which the joint settles
    to the depth that holds the new excitation (SPEC 5.2: each event stabilises), which at a
    non-modal frequency is all it settles, and the tail of the previous stage. The rate over
    the whole stage is given too. One row per modal stage: frequency_Hz, rate_mm_s,
    stage_rate_mm_s, control_Hz, control_rate_mm_s, control_stage_rate_mm_s, ratio (sustained;
    when the control did not settle: inf if the modal stage did, else 0), stage_ratio; empty
    without a control.
    """
    roles = {k + 1: e for k, e in enumerate(excitations)}

    def rates(s: dict) -> tuple[float, float]:
        half = 0.5 * (s["end_s"] - s["start_s"])
        return s["gained_second_half_mm"] / half, s["gained_mm"] / (2 * half)

    def ratio(r: float, c: float) -> float:
        return r / c if c > 0 else (np.inf if r > 0 else 0.0)

    controls = [s for s in stages if s["stage"] in roles and roles[s["stage"]].role == "control"]
    if not controls or not controls[0]["steps"]:
        return []
    control = controls[0]
    c, c_stage = rates(control)
    rows = []
    for s in stages:
        e = roles.get(s["stage"])
        if e is None or e.role != "modal" or not s["steps"] or e.amplitude_N != roles[control["stage"]].amplitude_N:
            continue
        r, r_stage = rates(s)
        rows.append({"frequency_Hz": s["frequency_Hz"], "rate_mm_s": r, "stage_rate_mm_s": r_stage,
                     "control_Hz": control["frequency_Hz"], "control_rate_mm_s": c,
                     "control_stage_rate_mm_s": c_stage, "ratio": ratio(r, c),
                     "stage_ratio": ratio(r_stage, c_stage)})
    return rows


def format_selectivity(rows: list[dict[str, float]]) -> list[str]:
    """Summary lines of ``frequency_selectivity`` (none without a control stage)."""
    if not rows:
        return []
    shown = all(r["ratio"] >= SELECTIVE for r in rows)
    return [
        f"frequency selectivity (SPEC 5.2: modal stages settle >= {SELECTIVE:g} x faster than the "
        f"control, over the second half of each stage): {'shown' if shown else 'NOT shown'} by "
        "this run",
        f"  control {rows[0]['control_Hz']:8.2f} Hz: {rows[0]['control_rate_mm_s']:+.4f} mm/s "
        f"(whole stage {rows[0]['control_stage_rate_mm_s']:+.4f} mm/s)",
        *(f"  modal   {r['frequency_Hz']:8.2f} Hz: {r['rate_mm_s']:+.4f} mm/s = {r['ratio']:.2f} x the "
          f"control (whole stage {r['stage_rate_mm_s']:+.4f} mm/s = {r['stage_ratio']:.2f} x)"
          for r in rows),
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
        + ", ".join(f"{e.frequency_Hz:.1f} Hz ({e.role})" for e in excitations),
        *format_stabilisation(stages),
        *format_selectivity(frequency_selectivity(stages, excitations)),
        "=" * 78,
    ]
    return "\n".join(lines)


def write_summary(summary: dict, stages, excitations, path: Path, comm: MPI.Comm) -> None:
    if comm.rank == 0:
        path.write_text(format_summary(summary, stages, excitations) + "\n")


def write_state(model, folder: Path, name: str, k: int) -> None:
    """Displacement (VTX, time = simulated time) and contact points (.vtp) after stage k."""
    from dolfinx import io

    u = model.problem.u
    with io.VTXWriter(model.comm, folder / f"displacement_{k}.bp", [u], engine="BP4") as writer:
        writer.write(model.problem.t)
    write_contact_points(model.contact, folder / f"contact_{k}.vtp")


def write_contact_points(contact: NitscheContact, path) -> None:
    """Write the slave points with their state as VTK PolyData (.vtp) for ParaView (rank 0 writes).

    Point data: status (0 open, 1 stick, 2 slip), gap_m, pressure_Pa,
    tangential_traction_Pa (vector), slip_velocity_m_s (vector), at the deformed points.
    """
    comm = contact.V.mesh.comm
    st = contact.state
    fields = {
        "status": st.status.astype(np.int32),
        "gap_m": st.gap,
        "pressure_Pa": st.pressure,
        "tangential_traction_Pa": st.tangential_traction,
        "slip_velocity_m_s": st.slip_velocity,
    }
    points = comm.gather(st.coordinates, root=0)
    data = {name: comm.gather(a, root=0) for name, a in fields.items()}
    if comm.rank == 0:
        import pyvista

        cloud = pyvista.PolyData(np.concatenate(points))
        for name, parts in data.items():
            cloud.point_data[name] = np.concatenate(parts)
        cloud.save(str(path))


def plot_contact_status(contact: NitscheContact, joint, path: Path, title: str) -> None:
    """Contact status of the slave points: angle [deg] against height above the TP's end [mm]."""
    comm = contact.V.mesh.comm
    st = contact.state
    x = comm.gather(contact.slave.points, root=0)
    status = comm.gather(st.status, root=0)
    if comm.rank != 0:
        return
    os.environ.setdefault("MPLBACKEND", "Agg")
    import matplotlib.pyplot as plt

    x, status = np.concatenate(x), np.concatenate(status)
    theta = np.degrees(np.arctan2(x[:, 1], x[:, 0])) % 360
    z = 1e3 * (x[:, 2] - joint.tp_offset)
    fig, ax = plt.subplots(figsize=(8, 4))
    for s, colour in (
        (Status.OPEN, "lightgrey"),
        (Status.STICK, "tab:blue"),
        (Status.SLIP, "tab:red"),
    ):
        sel = status == s
        ax.scatter(
            theta[sel], z[sel], s=4, c=colour, label=f"{s.name.lower()} ({np.count_nonzero(sel)})"
        )
    ax.set_xlabel("angle [deg]")
    ax.set_ylabel("height above the TP lower end [mm]")
    ax.set_title(f"contact status {title}")
    ax.legend(loc="upper right", markerscale=3)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def plot_history(history: list[dict], stages: list[dict], folder: Path, comm: MPI.Comm) -> None:
    """settlement.png and stage_gain.png (rank 0)."""
    if comm.rank != 0 or not history:
        return
    os.environ.setdefault("MPLBACKEND", "Agg")
    import matplotlib.pyplot as plt

    t = np.array([r["time_s"] for r in history])
    fig, ax = plt.subplots(figsize=(9, 4))
    ax.plot(t, [r["settlement_mm"] for r in history], "k-", lw=1)
    ax.set_xlabel("time [s]")
    ax.set_ylabel("settlement [mm]")
    ax2 = ax.twinx()
    ax2.plot(t, [r["frequency_Hz"] for r in history], "tab:orange", lw=1)
    ax2.set_ylabel("excitation frequency [Hz]", color="tab:orange")
    fig.tight_layout()
    fig.savefig(folder / "settlement.png", dpi=120)
    plt.close(fig)
    vib = [s for s in stages if s["frequency_Hz"] > 0]
    fig, ax = plt.subplots(figsize=(6, 4))
    if vib:
        ax.bar([s["frequency_Hz"] for s in vib], [1e3 * s["gained_mm"] for s in vib], width=3.0)
        for s in vib:
            ax.annotate(
                s["name"].split()[-1],
                (s["frequency_Hz"], 1e3 * s["gained_mm"]),
                ha="center",
                va="bottom",
            )
    ax.set_xlabel("excitation frequency [Hz]")
    ax.set_ylabel("settlement gained in the stage [um]")
    fig.tight_layout()
    fig.savefig(folder / "stage_gain.png", dpi=120)
    plt.close(fig)


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


def plot_sweep(
    rows: list[dict], stages: list[dict], natural_hz: list[float], path: Path, comm: MPI.Comm
) -> None:
    """Settlement gained in the sweep against time (with the frequency) and against the
    excitation frequency, with the natural frequencies of the settled joint (rank 0)."""
    if comm.rank != 0 or not rows:
        return
    os.environ.setdefault("MPLBACKEND", "Agg")
    import matplotlib.pyplot as plt

    t = np.array([r["time_s"] for r in rows])
    f = np.array([r["frequency_Hz"] for r in rows])
    gain = np.array([r["settlement_gain_mm"] for r in rows])
    fig, (ax_t, ax_f) = plt.subplots(1, 2, figsize=(12, 4.2))
    ax_t.plot(t, gain, "k-", lw=1)
    ax_t.set_xlabel("time [s]")
    ax_t.set_ylabel("settlement gained in the sweep [mm]")
    twin = ax_t.twinx()
    twin.plot(t, f, color="tab:orange", lw=1)
    twin.set_ylabel("excitation frequency [Hz]", color="tab:orange")
    ax_f.plot(f, gain, "k.-", lw=0.6, ms=2, label="settlement")
    steps = [s for s in stages[1:] if s["steps"]]
    if steps and all(s["frequency_Hz"] > 0 for s in steps):
        ax_f.bar([s["frequency_Hz"] for s in steps], [s["gained_mm"] for s in steps],
                 width=0.4 * min(np.diff([s["frequency_Hz"] for s in steps]), default=10.0),
                 alpha=0.3, label="gained per stage")
    lo, hi = f.min(), f.max()
    for k, fn in enumerate(x for x in natural_hz if lo <= x <= hi):
        label = "natural frequency" if k == 0 else None
        ax_f.axvline(fn, color="tab:blue", ls=":", lw=0.8, label=label)
    ax_f.set_xlabel("excitation frequency [Hz]")
    ax_f.set_ylabel("settlement gained [mm]")
    ax_f.legend(loc="best", fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
