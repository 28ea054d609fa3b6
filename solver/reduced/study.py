"""The reduced model's study of the full-scale installation (docs/physics.md §7, demos/lumped.py):
the case's ``[lumped]`` table (:class:`LumpedStudy`)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from common.case import construct
from solver.contact import FrictionLaw

__all__ = ["LumpedStudy", "read_study"]


@dataclass(frozen=True)
class LumpedStudy:
    """``[lumped]``: friction and damping of the lumped model and the settlement map over
    frequency x amplitude (SI units; the defaults are docs/physics.md §7's study)."""

    mu_s: float = 0.5  #: static friction coefficient [-]
    mu_d: float = 0.3  #: dynamic friction coefficient of the base case [-]
    d_c: float = math.inf  #: decay of mu(v) [s/m] (inf: a step from mu_s to mu_d)
    damping_ratio: float = 0.01  #: fraction of critical damping per dof [-]
    settle_time_s: float = 1.0  #: self-weight alone before the harmonic load [s]
    duration_s: float = 90.0  #: harmonic loading of each map run [s]
    f_max_hz: float = 20.0  #: largest map frequency [Hz] (the map starts at 0)
    amplitude_max_N: float = 500e3  #: largest map amplitude [N] (the map starts at 0)
    n_frequencies: int = 41  #: map frequencies
    n_amplitudes: int = 11  #: map amplitudes
    bvp_tol: float = 1e-5  #: tolerance of the shell springs' collocation [-]

    def __post_init__(self) -> None:
        FrictionLaw(self.mu_s, self.mu_d, self.d_c)  # checks the coefficients
        if not (self.duration_s > 0 and self.f_max_hz > 0 and self.bvp_tol > 0):
            raise ValueError("duration_s, f_max_hz and bvp_tol must be positive")
        if not (self.settle_time_s >= 0 and self.amplitude_max_N >= 0):
            raise ValueError("settle_time_s and amplitude_max_N must be >= 0")
        if not self.damping_ratio >= 0:
            raise ValueError(f"damping_ratio must be >= 0, got {self.damping_ratio}")
        for name in ("n_frequencies", "n_amplitudes"):
            value = getattr(self, name)
            if not (isinstance(value, int) and value >= 2):
                raise ValueError(f"{name} must be an integer >= 2, got {value!r}")

    def friction(self, mu_d: float | None = None) -> FrictionLaw:
        """The friction law, with another dynamic coefficient where given [-]."""
        return FrictionLaw(self.mu_s, self.mu_d if mu_d is None else mu_d, self.d_c)


def read_study(case: dict[str, Any]) -> LumpedStudy:
    """The study of a case dict's ``[lumped]`` table (the defaults of :class:`LumpedStudy` where
    absent); ValueError naming the table on a bad entry."""
    return construct(LumpedStudy, dict(case.get("lumped", {})), "lumped")
