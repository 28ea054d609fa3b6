"""Pictures of the runs (PNG, matplotlib without a display; rank 0 draws): the settlement
history, the contact status of the slave points, frequency sweeps, dismount stages and the
parameter study's summary."""

import os
import textwrap
from pathlib import Path
from typing import Any

import numpy as np
from mpi4py import MPI

from solver.contact import NitscheContact, Status

__all__ = [
    "plot_contact_status",
    "plot_dismount",
    "plot_history",
    "plot_parameter_study",
    "plot_sweep",
]


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
        ax_f.bar(
            [s["frequency_Hz"] for s in steps],
            [s["gained_mm"] for s in steps],
            width=0.4 * min(np.diff([s["frequency_Hz"] for s in steps]), default=10.0),
            alpha=0.3,
            label="gained per stage",
        )
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


def plot_dismount(
    history: list[dict[str, float]], table: list[dict[str, Any]], path: Path, comm: MPI.Comm
) -> None:
    """Settlement and axial force against time, dismount stages shaded (rank 0)."""
    if comm.rank != 0 or not history:
        return
    os.environ.setdefault("MPLBACKEND", "Agg")
    import matplotlib.pyplot as plt

    t = np.array([r["time_s"] for r in history])
    fig, (ax, ax_f) = plt.subplots(2, 1, figsize=(9, 6), sharex=True)
    ax.plot(t, [r["settlement_mm"] for r in history], "k-", lw=1)
    ax.set_ylabel("settlement [mm] (down +)")
    ax_f.plot(
        t,
        [1e-3 * r["axial_force_N"] for r in history],
        "tab:blue",
        lw=1,
        label="axial force on the TP top (up +)",
    )
    ax_f.plot(
        t,
        [1e-3 * r["normal_force_N"] for r in history],
        "tab:red",
        lw=1,
        label="contact normal force",
    )
    ax_f.set_xlabel("time [s]")
    ax_f.set_ylabel("force [kN]")
    ax_f.legend(loc="best", fontsize=8)
    colours = {
        "install": "tab:green",
        "pull ramp": "tab:orange",
        "pull alone": "gold",
        "pull + vibration": "tab:purple",
    }
    seen = set()
    for row in table:
        for a in (ax, ax_f):
            label = row["role"] if a is ax and row["role"] not in seen else None
            a.axvspan(
                row["start_s"], row["end_s"], color=colours[row["role"]], alpha=0.15, label=label
            )
        seen.add(row["role"])
    if table:  # the dismount stages and the end of the installation before them
        t0, t1 = table[0]["start_s"], table[-1]["end_s"]
        ax.set_xlim(t0 - 0.3 * (t1 - t0), t1)
    ax.legend(loc="best", fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def plot_parameter_study(rows: list[dict[str, Any]], path: Path, comm: MPI.Comm) -> None:
    """Per stage (grouped bars) for each variant (rank 0): the settlement gained [mm] and, for
    the vibration stages, the sustained rate over the stage's second half [mm/s]."""
    if comm.rank != 0 or not rows:
        return
    os.environ.setdefault("MPLBACKEND", "Agg")
    import matplotlib.pyplot as plt

    names = list(dict.fromkeys(r["variant"] for r in rows))
    n_stages = 1 + max(r["stage"] for r in rows)
    x = np.arange(len(names))
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(max(6, 1.8 * len(names)), 7), sharex=True)
    panels = (
        (top, "gained_mm", range(n_stages), "settlement gained in the stage [mm]"),
        (bottom, "sustained_rate_mm_s", range(1, n_stages), "rate over its second half [mm/s]"),
    )
    for ax, key, stages, ylabel in panels:
        width = 0.8 / max(len(stages), 1)
        for j, k in enumerate(stages):
            value = [
                next((r[key] for r in rows if r["variant"] == n and r["stage"] == k), np.nan)
                for n in names
            ]
            label = next(
                (
                    f"{r['role'] or r['name']}"
                    + (f" ({r['frequency_Hz']:.0f} Hz)" if r["frequency_Hz"] else "")
                    for r in rows
                    if r["stage"] == k and r["variant"] == names[0]
                ),
                f"stage {k}",
            )
            offset = (j - 0.5 * (len(stages) - 1)) * width
            ax.bar(x + offset, value, width, label=label, color=f"C{k}")  # a stage's colour
        ax.set_ylabel(ylabel)
        ax.axhline(0.0, color="k", lw=0.5)
        if len(stages):
            ax.legend(fontsize=7)
    labels = [
        next(
            f"{r['variant']}\n{textwrap.fill(r['value'], 20)}"
            + ("" if r["status"] == "done" else f"\n[{r['status']}]")
            for r in rows
            if r["variant"] == n
        )
        for n in names
    ]
    bottom.set_xticks(x, labels, fontsize=7)
    top.set_title("one-at-a-time parameter study (legend: stages of the base case)")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
