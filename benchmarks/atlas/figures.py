"""Figures of the atlas (PNG, matplotlib without a display; call on rank 0)."""

import itertools
import os
from pathlib import Path

import numpy as np

__all__ = [
    "plot_branches",
    "plot_frequencies",
    "plot_ramps",
    "plot_sequence",
    "plot_settlement",
    "plot_stiffening",
]


def _pyplot():
    os.environ.setdefault("MPLBACKEND", "Agg")
    import matplotlib.pyplot as plt

    return plt


def plot_settlement(runs: dict[str, dict], path: Path, title: str) -> None:
    """Settlement [mm] against time [s] of self-weight runs (``self_weight_run`` results by
    label), the axial force [kN] on a second axis."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(8, 4))
    for label, r in runs.items():
        n = len(r["events_mm"])
        ax.plot(
            r["time_s"],
            r["settlement_mm"],
            lw=1.2,
            label=f"{label} ({n} stick-slip event{'' if n == 1 else 's'})",
        )
    ax.set_xlabel("time [s]")
    ax.set_ylabel("settlement [mm]")
    ax.set_title(title)
    ax.legend(loc="lower right")
    r = next(iter(runs.values()))
    t = np.linspace(0.0, max(r["time_s"]), 200)
    ax2 = ax.twinx()
    ax2.plot(t, 1e-3 * abs(r["force_N"]) * np.minimum(t / r["ramp_time_s"], 1.0), "k:", lw=0.8)
    ax2.set_ylabel("axial force (dotted) [kN]")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def plot_frequencies(series: dict[str, list[float]], path: Path, title: str) -> None:
    """Natural frequencies [Hz] against mode number, one marker series per state."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(7, 4))
    for (label, f), marker in zip(series.items(), itertools.cycle("os^dv<>")):
        ax.plot(np.arange(1, len(f) + 1), f, marker, ms=6, mfc="none", label=label)
    ax.set_xlabel("mode number")
    ax.set_ylabel("natural frequency [Hz]")
    ax.set_title(title)
    ax.legend(loc="upper left")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def plot_stiffening(
    settled_mm: float,
    settled_Hz: list[float],
    states: dict[str, tuple[list[float], list[list[float]]]],
    path: Path,
    title: str,
) -> None:
    """The change [%] of each natural frequency from the joint settled by self-weight
    (``settled_mm``, ``settled_Hz``) against the settlement [mm]: per kind of state (label ->
    its settlements [mm] and frequencies [Hz]) one line per mode, a colour per mode number."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(8, 4.5))
    f0 = np.asarray(settled_Hz)
    colours = plt.get_cmap("tab10").colors
    styles = itertools.cycle([("o", "--", "none"), ("s", "-", None)])  # marker, line, face
    for (label, (settlement, frequencies)), (marker, line, face) in zip(states.items(), styles):
        x = [settled_mm, *settlement]
        change = 100 * (np.vstack([f0, *frequencies]) / f0 - 1)
        for j in range(len(f0)):
            ax.plot(
                x,
                change[:, j],
                ls=line,
                marker=marker,
                mfc=face,
                ms=4,
                lw=0.9,
                color=colours[j % len(colours)],
                label=label if j == 0 else None,
            )
    ax.axhline(0.0, color="k", lw=0.6, ls=":")
    ax.set_xlabel("settlement [mm]")
    ax.set_ylabel("natural frequency change [%]")
    ax.set_title(title)
    ax.legend(loc="upper left", fontsize=8, title=f"modes 1 to {len(f0)}: one colour each")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def plot_branches(
    branches: dict[str, list], path: Path, title: str, ylabel: str = "settlement [mm]"
) -> None:
    """Settlement (``ylabel``: its quantity and unit, by default [mm]) and contact normal force
    [kN] against time [s] of branches from one state: rows (time [s], settlement, normal force
    [N]) by label."""
    plt = _pyplot()
    fig, (ax, ax2) = plt.subplots(2, 1, figsize=(8, 5.5), sharex=True)
    for label, rows in branches.items():
        t, s, n = np.array(rows).T
        ax.plot(t, s, lw=1.2, label=label)
        ax2.plot(t, 1e-3 * n, lw=1.2)
    ax.axhline(0.0, color="k", lw=0.6, ls=":")
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.legend(loc="lower left", fontsize=8)
    ax2.set_xlabel("time [s]")
    ax2.set_ylabel("contact normal force [kN]")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


#: shading of the stages of an installation run, by role
ROLE_COLOURS = {
    "self-weight": "0.8",
    "lead-in": "tab:orange",
    "modal": "tab:green",
    "control": "tab:red",
    "sweep step": "tab:purple",
}


def plot_sequence(
    history: list[dict],
    stages: list[dict],
    roles: list[str],
    natural_hz: list[float],
    path: Path,
    title: str,
) -> None:
    """Left: settlement [mm] and excitation frequency [Hz] against time [s], the stages shaded
    by role; right: the settlement gained per vibration stage [um] against its frequency [Hz],
    the natural frequencies of the settled joint marked. ``history``/``stages``: rows as an
    installation run writes them (``time_s``, ``settlement_mm``, ``frequency_Hz``; ``start_s``,
    ``end_s``, ``frequency_Hz``, ``gained_mm``); ``roles``: each stage's role, a key of
    ``ROLE_COLOURS``."""
    plt = _pyplot()
    fig, (ax, ax_f) = plt.subplots(1, 2, figsize=(13, 4.5), gridspec_kw={"width_ratios": [3, 2]})
    t = np.array([r["time_s"] for r in history])
    ax.plot(t, [r["settlement_mm"] for r in history], "k-", lw=1)
    ax.set_xlabel("time [s]")
    ax.set_ylabel("settlement [mm]")
    twin = ax.twinx()
    twin.plot(t, [r["frequency_Hz"] for r in history], color="tab:blue", lw=0.8)
    twin.set_ylabel("excitation frequency [Hz]", color="tab:blue")
    seen = set()
    for s, role in zip(stages, roles):
        label = role if role not in seen else None
        ax.axvspan(s["start_s"], s["end_s"], color=ROLE_COLOURS[role], alpha=0.2, label=label)
        seen.add(role)
    ax.legend(loc="lower right", fontsize=8)
    ax.set_title(title)
    vibration = [(s, role) for s, role in zip(stages, roles) if s["frequency_Hz"] > 0]
    for s, role in vibration:
        ax_f.bar(s["frequency_Hz"], 1e3 * s["gained_mm"], width=4.0, color=ROLE_COLOURS[role])
        ax_f.annotate(
            f"{1e3 * s['gained_mm']:.0f}",
            (s["frequency_Hz"], 1e3 * s["gained_mm"]),
            ha="center",
            va="bottom",
            fontsize=8,
        )
    top = max([s["frequency_Hz"] for s, _ in vibration], default=100.0) * 1.1
    marked = [f for f in natural_hz if f <= top]
    for k, fn in enumerate(marked):
        label = "natural frequency (settled)" if k == 0 else None
        ax_f.axvline(fn, color="tab:blue", ls=":", lw=0.8, label=label)
    ax_f.set_yscale("log")
    low, high = ax_f.get_ylim()
    ax_f.set_ylim(low, 10 * high)  # room above the bars for their labels and the legend
    ax_f.set_xlabel("excitation frequency [Hz]")
    ax_f.set_ylabel("settlement gained in the stage [um]")
    if marked:
        ax_f.legend(loc="upper right", fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def plot_ramps(
    ramps: dict[str, tuple[np.ndarray, np.ndarray]],
    natural_hz: list[float],
    discrete_hz: float,
    path: Path,
    title: str,
) -> None:
    """Settlement gained [um] against the excitation frequency [Hz] of linear frequency ramps
    (frequency and gain arrays by label); the natural frequencies in the ramps' range marked,
    and ``discrete_hz``, the time-discrete natural frequency of the mode the ramps cross."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(8, 4))
    for label, (f, gained) in ramps.items():
        ax.plot(f, gained, lw=1.2, label=label)
    low = min(f.min() for f, _ in ramps.values())
    high = max(f.max() for f, _ in ramps.values())
    for k, fn in enumerate(f for f in natural_hz if low <= f <= high):
        ax.axvline(
            fn, color="tab:blue", ls=":", lw=0.8, label="natural frequency" if k == 0 else None
        )
    ax.axvline(discrete_hz, color="tab:blue", ls="--", lw=0.8, label="its time-discrete frequency")
    ax.set_xlabel("excitation frequency [Hz]")
    ax.set_ylabel("settlement gained in the ramp [um]")
    ax.set_title(title)
    ax.legend(loc="upper left", fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
