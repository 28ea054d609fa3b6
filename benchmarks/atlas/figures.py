"""Figures of the atlas (PNG, matplotlib without a display; call on rank 0)."""

import os
from pathlib import Path

import numpy as np

__all__ = ["plot_branches", "plot_frequencies", "plot_settlement"]


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
    ax.legend(loc="upper left")
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
    for (label, f), marker in zip(series.items(), "os^dv<>"):
        ax.plot(np.arange(1, len(f) + 1), f, marker, ms=6, mfc="none", label=label)
    ax.set_xlabel("mode number")
    ax.set_ylabel("natural frequency [Hz]")
    ax.set_title(title)
    ax.legend(loc="upper left")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def plot_branches(branches: dict[str, list], path: Path, title: str) -> None:
    """Settlement [mm] and contact normal force [kN] against time [s] of branches from one
    state: rows (time [s], settlement [mm], normal force [N]) by label."""
    plt = _pyplot()
    fig, (ax, ax2) = plt.subplots(2, 1, figsize=(8, 5.5), sharex=True)
    for label, rows in branches.items():
        t, s, n = np.array(rows).T
        ax.plot(t, s, lw=1.2, label=label)
        ax2.plot(t, 1e-3 * n, lw=1.2)
    ax.axhline(0.0, color="k", lw=0.6, ls=":")
    ax.set_ylabel("settlement [mm]")
    ax.set_title(title)
    ax.legend(loc="lower left", fontsize=8)
    ax2.set_xlabel("time [s]")
    ax2.set_ylabel("contact normal force [kN]")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
