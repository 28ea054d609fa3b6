"""Frequency sweeps of the installed joint (docs/physics.md §3, 5.7): the case's ``[sweep]``
table (:class:`SweepPlan`) and the [[schedule]] it stands for (:func:`sweep_case`), which
``demos/sweep.py`` writes into the installation case in place of any other."""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any

from common.case import construct
from solver.dynamics.loads import Stage, frequency_ramp, frequency_steps

__all__ = ["SweepPlan", "read_sweep", "sweep_case"]

#: [vibration] keys -> the [[schedule]] keys the sweep's stages take them to
_DIRECTION_KEYS = {
    "direction": "direction",
    "lateral_fraction": "lateral_fraction",
    "angle_deg": "lateral_angle_deg",
}


@dataclass(frozen=True)
class SweepPlan:
    """``[sweep]``: a step-wise frequency increase (kind "steps": f_start_hz, f_start_hz +
    f_step_hz, ... up to f_stop_hz, each held dwell_s) or a linear frequency ramp (kind "ramp":
    f_start_hz to f_stop_hz over duration_s), at the force amplitude amplitude_N: "eccentric"
    (the motors' 0.3632 f^2 N) or a force [N]. SI units; the defaults are demos/sweep.py's."""

    kind: str = "steps"
    f_start_hz: float = 10.0
    f_stop_hz: float = 130.0
    f_step_hz: float = 10.0  #: "steps" only
    dwell_s: float = 0.03  #: "steps" only (docs/physics.md §3: 0.5 s)
    duration_s: float = 1.0  #: "ramp" only (docs/physics.md §3: 13-200 s)
    amplitude_N: float | str = "eccentric"

    def __post_init__(self) -> None:
        if self.kind not in ("steps", "ramp"):
            raise ValueError(f"kind must be 'steps' or 'ramp', got {self.kind!r}")
        force = self.amplitude_N
        if (
            isinstance(force, str)
            and force != "eccentric"
            or (not isinstance(force, str) and not force > 0)
        ):
            raise ValueError(f"amplitude_N must be 'eccentric' or a force > 0 N, got {force!r}")

    def stages(self, **stage_options: Any) -> list[Stage]:
        """The sweep's stages (``stage_options``: direction, lateral_fraction, ...)."""
        if self.kind == "steps":
            return frequency_steps(
                self.f_start_hz,
                self.f_stop_hz,
                self.f_step_hz,
                self.dwell_s,
                self.amplitude_N,
                **stage_options,
            )
        return frequency_ramp(
            self.f_start_hz, self.f_stop_hz, self.duration_s, self.amplitude_N, **stage_options
        )


def read_sweep(case: dict[str, Any]) -> SweepPlan:
    """The plan of a case dict's ``[sweep]`` table (the defaults of :class:`SweepPlan` where
    absent); ValueError naming the table on a bad entry."""
    return construct(SweepPlan, dict(case.get("sweep", {})), "sweep")


def sweep_case(case: dict[str, Any], plan: SweepPlan) -> None:
    """Replace a case dict's [[schedule]] by the sweep's stages, each with the case's
    [vibration] direction settings (direction, lateral_fraction, angle_deg)."""
    vibration = case.get("vibration", {})
    options = {key: vibration[name] for name, key in _DIRECTION_KEYS.items() if name in vibration}
    case["schedule"] = [
        {k: v for k, v in asdict(stage).items() if v is not None}
        for stage in plan.stages(**options)
    ]
