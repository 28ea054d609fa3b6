"""One-at-a-time parameter study of the installation run (docs/physics.md §4, 5.6).

A *variant* is a name, the parameter it varies, and the case overrides that vary it from the
base case. :data:`VARIANTS` holds the parameter-study values of docs/physics.md §4: friction
mu_s/mu_d 0.5/0.4 (reference) vs 0.0625/0.05, friction decay d_c 100 (reference) vs 1 s/m, damping Rayleigh
(reference) vs modal, and the axial mesh size halved. Each variant runs the installation pipeline into its
own sub-folder; :func:`summary_rows` collects the settlement per stage and variant and
``solver.post.plots.plot_parameter_study`` draws it. Settlement in mm, positive down
(``solver.installation.observers.Settlement``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from solver.installation.case import InstallationCase
from solver.post.report import sustained_rate_mm_s


@dataclass(frozen=True)
class Variant:
    """A case varied in one parameter from the base case."""

    name: str  #: sub-folder name
    parameter: str  #: what is varied (``base`` for the base case)
    value: str  #: the value, as printed
    overrides: tuple[str, ...] = ()  #: ``table.key=value`` applied on top of the base case


def variants(base: InstallationCase) -> list[Variant]:
    """The parameter-study variants of docs/physics.md §4, each varied alone from the ``base``
    case (its label: the base case's friction, damping model and axial element size)."""
    friction, base_axial_size = base.friction, base.mesh.axial_size
    return [
        Variant(
            "base",
            "base",
            f"mu {friction.mu_s:g}/{friction.mu_d:g}, d_c {friction.d_c:g} s/m, "
            f"{base.damping.model}, {1e3 * base_axial_size:.0f} mm",
        ),
        Variant(
            "low_friction",
            "friction",
            "mu_s/mu_d 0.0625/0.05",
            ("friction.mu_s=0.0625", "friction.mu_d=0.05"),
        ),
        Variant("slow_decay", "d_c", "d_c 1 s/m", ("friction.d_c=1.0",)),
        Variant("modal_damping", "damping", "modal", ("damping.model='modal'",)),
        Variant(
            "fine_mesh",
            "mesh size",
            f"{0.5e3 * base_axial_size:.0f} mm axially",
            (f"mesh.axial_size={0.5 * base_axial_size}",),
        ),
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
    "gained_second_half_mm",
    "sustained_rate_mm_s",
    "stick_slip_events",
    "steps",
    "wall_s",
    "status",
]


def summary_rows(
    variant: Variant, stages: list[dict[str, Any]], excitations, status: str
) -> list[dict[str, Any]]:
    """One row per stage of a variant's run (``Installation.stages``), with the role of each
    vibration stage (modal / control / ...) from ``Installation.excitations`` and its sustained
    rate (``solver.post.report.sustained_rate_mm_s``; a stage's whole gain also holds the event
    in which the joint settles to the depth that holds the new excitation, and the first
    vibration stage's also the joint's first settling under vibration)."""
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
            "gained_second_half_mm": s["gained_second_half_mm"],
            "sustained_rate_mm_s": sustained_rate_mm_s(s),
            "stick_slip_events": s["stick_slip_events"],
            "steps": s["steps"],
            "wall_s": s["wall_s"],
            "status": status,
        }
        for s in stages
    ]
