"""One-at-a-time parameter study of the installation run (SPEC 4, 5.6).

A *variant* is a name, the parameter it varies, and the case overrides that vary it from the
base case. :data:`VARIANTS` holds the SPEC values: friction mu_s/mu_d 0.5/0.4 (reference) vs
0.0625/0.05, friction decay d_c 100 (reference) vs 1 s/m, damping Rayleigh (reference) vs
modal, and the axial mesh size halved. Each variant runs the installation pipeline into its
own sub-folder; :func:`summary_rows` collects the settlement per stage and variant and
:func:`plot_summary` draws it. Settlement in mm, positive down (``solver.dynamics.elastodynamics.Settlement``).
"""

from __future__ import annotations

import os
import textwrap
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from mpi4py import MPI


@dataclass(frozen=True)
class Variant:
    """A case varied in one parameter from the base case."""

    name: str  #: sub-folder name
    parameter: str  #: what is varied (``base`` for the base case)
    value: str  #: the value, as printed
    overrides: tuple[str, ...] = ()  #: ``table.key=value`` applied on top of the base case


def variants(base_axial_size: float) -> list[Variant]:
    """The SPEC variants, each varied alone from the base case (reference friction 0.5/0.4,
    d_c = 100 s/m, Rayleigh damping, axial element size ``base_axial_size`` [m])."""
    return [
        Variant("base", "base", "mu 0.5/0.4, d_c 100 s/m, rayleigh, "
                f"{1e3 * base_axial_size:.0f} mm"),
        Variant("low_friction", "friction", "mu_s/mu_d 0.0625/0.05",
                ("friction.mu_s=0.0625", "friction.mu_d=0.05")),
        Variant("slow_decay", "d_c", "d_c 1 s/m", ("friction.d_c=1.0",)),
        Variant("modal_damping", "damping", "modal", ("damping.model='modal'",)),
        Variant("fine_mesh", "mesh size", f"{0.5e3 * base_axial_size:.0f} mm axially",
                (f"mesh.axial_size={0.5 * base_axial_size}",)),
    ]


def select(all_variants: list[Variant], names: list[str]) -> list[Variant]:
    """The variants named (base first); ValueError naming unknown names."""
    known = {v.name: v for v in all_variants}
    unknown = [n for n in names if n not in known]
    if unknown:
        raise ValueError(f"unknown variant(s) {unknown}; known: {list(known)}")
    return [v for v in all_variants if v.name in names or v.name == "base"]


SUMMARY_COLUMNS = [
    "variant",
    "parameter",
    "value",
    "stage",
    "name",
    "frequency_Hz",
    "amplitude_N",
    "role",
    "settlement_start_mm",
    "settlement_end_mm",
    "gained_mm",
    "stick_slip_events",
    "steps",
    "wall_s",
    "status",
]


def summary_rows(variant: Variant, stages: list[dict[str, Any]], excitations, status: str
                 ) -> list[dict[str, Any]]:
    """One row per stage of a variant's run (``Installation.stages``), with the role of each
    vibration stage (modal / control / ...) from ``Installation.excitations``."""
    roles = ["self-weight"] + [e.role for e in excitations]
    return [
        {
            "variant": variant.name,
            "parameter": variant.parameter,
            "value": variant.value,
            "stage": s["stage"],
            "name": s["name"],
            "frequency_Hz": s["frequency_Hz"],
            "amplitude_N": s["amplitude_N"],
            "role": roles[s["stage"]] if s["stage"] < len(roles) else "",
            "settlement_start_mm": s["settlement_start_mm"],
            "settlement_end_mm": s["settlement_end_mm"],
            "gained_mm": s["gained_mm"],
            "stick_slip_events": s["stick_slip_events"],
            "steps": s["steps"],
            "wall_s": s["wall_s"],
            "status": status,
        }
        for s in stages
    ]


def plot_summary(rows: list[dict[str, Any]], path: Path, comm: MPI.Comm) -> None:
    """Settlement gained per stage (grouped bars) for each variant (rank 0)."""
    if comm.rank != 0 or not rows:
        return
    os.environ.setdefault("MPLBACKEND", "Agg")
    import matplotlib.pyplot as plt

    names = list(dict.fromkeys(r["variant"] for r in rows))
    n_stages = 1 + max(r["stage"] for r in rows)
    width = 0.8 / n_stages
    fig, ax = plt.subplots(figsize=(max(6, 1.8 * len(names)), 4.5))
    x = np.arange(len(names))
    for k in range(n_stages):
        gain = [next((r["gained_mm"] for r in rows if r["variant"] == n and r["stage"] == k),
                     np.nan) for n in names]
        label = next((f"{r['role'] or r['name']}" + (f" ({r['frequency_Hz']:.0f} Hz)"
                                                      if r["frequency_Hz"] else "")
                      for r in rows if r["stage"] == k and r["variant"] == names[0]), f"stage {k}")
        ax.bar(x + (k - 0.5 * (n_stages - 1)) * width, gain, width, label=label)
    labels = [next(f"{r['variant']}\n{textwrap.fill(r['value'], 20)}"
                   + ("" if r["status"] == "done" else f"\n[{r['status']}]")
                   for r in rows if r["variant"] == n) for n in names]
    ax.set_xticks(x, labels, fontsize=7)
    ax.set_ylabel("settlement gained in the stage [mm]")
    ax.set_title("one-at-a-time parameter study (legend: stages of the base case)")
    ax.axhline(0.0, color="k", lw=0.5)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
