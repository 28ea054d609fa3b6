"""Dismount of an installed joint (docs/physics.md §3, 5.5): a pulling axial force alone, then pulling plus
vibration at the ranked natural frequencies of the settled joint.

:func:`read_plan` takes the sequence from a case's ``[dismount]`` table (:class:`DismountPlan`),
:func:`dismount_case` writes it into the installation case (``solver.installation``):
after the self-weight stage, optionally ``n_install`` installation stages at the ranked
frequencies with the self-weight force held, then the static axial force is ramped from the
self-weight force (down) to the pull ``pull_N`` (up, > 0) over ``ramp_s`` and held
(``[static_force]``), the pull acts alone for ``hold_s``, and then ``n_frequencies`` stages
at 'ranked 1', 'ranked 2', ... with the pull held (``[[schedule]]``).

:func:`dismount_table` reads the run per stage: the TP's axial motion (settlement change,
negative = the TP moved up) and whether it separated: the contact normal force at the end of
the stage below ``SEPARATION_FRACTION`` of the normal force at the end of the self-weight
stage (0 when every contact point is open); ``dismount.csv`` has the columns
``DISMOUNT_COLUMNS``. SI units: N, s, mm in the tables as named.

:func:`pull_out_force` is the rigid Coulomb estimate of the pull that frees a TP held on the
cone half-angle alpha by the normal force N: P = N (mu cos(alpha) - sin(alpha)) (the wedge's
normal force pushes the TP up by N sin(alpha), friction holds it down by at most mu N cos(alpha)).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from common.case import construct
from solver.installation.settings import SelfWeightSettings, VibrationSettings

DISMOUNT_COLUMNS = [
    "stage",
    "role",
    "start_s",
    "end_s",
    "frequency_Hz",
    "static_force_end_N",
    "settlement_start_mm",
    "settlement_end_mm",
    "axial_motion_mm",
    "normal_force_end_N",
    "normal_force_min_N",
    "open_fraction_end",
    "separated",
]
#: a stage separated the joint where its contact normal force ends below this fraction of the
#: self-weight stage's (or every contact point is open)
SEPARATION_FRACTION = 0.01


@dataclass(frozen=True)
class DismountPlan:
    """``[dismount]``: the dismount sequence after the self-weight stage (SI units; the defaults
    are ``demos/dismount.py``'s)."""

    pull_N: float = 6e3  #: pulling (upward) static force [N] (docs/physics.md §3 rig: 10-40 kN)
    ramp_s: float = 0.05  #: ramp from the self-weight force to the pull [s]
    hold_s: float = 0.05  #: pull alone, held [s]
    n_install: int = 0  #: installation stages (ranked frequencies, self-weight held) before
    n_frequencies: int = 2  #: pull + vibration stages at 'ranked 1..n'
    stage_duration_s: float = 0.03  #: each vibration stage [s]
    amplitude_N: float = 3600.0  #: vibration force amplitude [N]

    def __post_init__(self) -> None:
        if not self.pull_N > 0:
            raise ValueError(f"the pull must be a positive (upward) force, got {self.pull_N} N")
        if not (self.ramp_s > 0 and self.hold_s > 0 and self.stage_duration_s > 0):
            raise ValueError(
                f"pull ramp, pull hold and stage durations must be positive, got "
                f"{self.ramp_s}, {self.hold_s}, {self.stage_duration_s} s"
            )
        for name in ("n_install", "n_frequencies"):
            value = getattr(self, name)
            if not (isinstance(value, int) and value >= 0):
                raise ValueError(f"{name} must be an integer >= 0, got {value!r}")
        if not self.amplitude_N > 0:
            raise ValueError(f"amplitude must be positive, got {self.amplitude_N} N")

    def roles(self) -> list[str]:
        """Role of each stage after the self-weight stage."""
        return (
            ["install"] * self.n_install
            + ["pull ramp", "pull alone"]
            + ["pull + vibration"] * self.n_frequencies
        )


def read_plan(case: dict[str, Any]) -> DismountPlan:
    """The plan of a case dict's ``[dismount]`` table (the defaults of :class:`DismountPlan`
    where absent); ValueError naming the table on a bad entry."""
    return construct(DismountPlan, dict(case.get("dismount", {})), "dismount")


def dismount_case(case: dict[str, Any], plan: DismountPlan) -> None:
    """Write ``plan`` into the case dict (``[static_force]``, ``[[schedule]]``), in place.

    The ranked frequencies come from the modal stage after self-weight, so
    ``vibration.n_frequencies`` is raised to the number of ranked stages if needed.
    """

    def ranked(k: int) -> dict[str, Any]:
        return {
            "duration_s": plan.stage_duration_s,
            "frequency_hz": f"ranked {k}",
            "amplitude_N": plan.amplitude_N,
        }

    def still(duration: float) -> dict[str, Any]:
        return {"duration_s": duration, "frequency_hz": 0.0, "amplitude_N": 0.0}

    install = [ranked(k + 1) for k in range(plan.n_install)]
    pull = [ranked(k + 1) for k in range(plan.n_frequencies)]
    case["schedule"] = install + [still(plan.ramp_s), still(plan.hold_s)] + pull
    t_pull = plan.n_install * plan.stage_duration_s
    force_sw = float(case.get("self_weight", {}).get("force_N", SelfWeightSettings.force_N))
    times, forces = [t_pull + plan.ramp_s], [plan.pull_N]
    if t_pull > 0:
        times, forces = [t_pull] + times, [force_sw] + forces
    case["static_force"] = {"times_s": times, "forces_N": forces}
    vibration = case.setdefault("vibration", {})
    needed = max(plan.n_install, plan.n_frequencies)
    default = VibrationSettings.n_frequencies
    vibration["n_frequencies"] = max(int(vibration.get("n_frequencies", default)), needed)


def pull_out_force(normal_N: float, mu: float, alpha_rad: float) -> float:
    """Upward pull [N] that overcomes friction mu on a cone of half-angle alpha [rad] pressed by
    the total normal force ``normal_N`` [N]: N (mu cos(alpha) - sin(alpha)) (rigid, Coulomb)."""
    return normal_N * (mu * math.cos(alpha_rad) - math.sin(alpha_rad))


def dismount_table(
    history: list[dict[str, float]],
    stages: list[dict[str, Any]],
    roles: list[str],
    static_force: Callable[[float], float],
) -> list[dict[str, Any]]:
    """Per stage after the self-weight stage: axial motion and separation (see module doc);
    ``static_force`` [N] against time [s] (``JointModel.static``)."""
    sw_rows = [r for r in history if r["stage"] == 0]
    reference = sw_rows[-1]["normal_force_N"] if sw_rows else 0.0
    table = []
    for summary, role in zip(stages[1:], roles):
        rows = [r for r in history if r["stage"] == summary["stage"]]
        if not rows:
            continue
        normal = np.array([r["normal_force_N"] for r in rows])
        open_end = 1.0 - rows[-1]["stick_fraction"] - rows[-1]["slip_fraction"]
        table.append(
            {
                "stage": summary["stage"],
                "role": role,
                "start_s": summary["start_s"],
                "end_s": summary["end_s"],
                "frequency_Hz": summary["frequency_Hz"],
                "static_force_end_N": float(static_force(summary["end_s"])),
                "settlement_start_mm": summary["settlement_start_mm"],
                "settlement_end_mm": summary["settlement_end_mm"],
                "axial_motion_mm": summary["settlement_start_mm"] - summary["settlement_end_mm"],
                "normal_force_end_N": float(normal[-1]),
                "normal_force_min_N": float(normal.min()),
                "open_fraction_end": open_end,
                "separated": bool(
                    open_end >= 1.0 or normal[-1] <= SEPARATION_FRACTION * abs(reference)
                ),
            }
        )
    return table
