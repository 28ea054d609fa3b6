"""Velocity-dependent Coulomb friction law (docs/physics.md §4).

mu(v) = mu_d + (mu_s - mu_d) exp(-d_c |v|), with |v| the relative slip speed
in m/s and d_c in s/m. Works on numpy arrays and on UFL expressions.
"""

from dataclasses import dataclass

import numpy as np
import ufl


@dataclass(frozen=True)
class FrictionLaw:
    """Coulomb friction with exponential decay from static to dynamic coefficient."""

    mu_s: float = 0.5  #: static coefficient [-]
    mu_d: float = 0.4  #: dynamic coefficient [-]
    d_c: float = 100.0  #: decay coefficient [s/m]

    def __post_init__(self) -> None:
        if not (self.mu_s >= 0 and self.mu_d >= 0):
            raise ValueError(
                f"friction coefficients must be >= 0, got mu_s={self.mu_s}, mu_d={self.mu_d}"
            )
        if self.mu_d > self.mu_s:
            raise ValueError(f"mu_d ({self.mu_d}) must not exceed mu_s ({self.mu_s})")
        if self.d_c < 0:
            raise ValueError(f"decay coefficient d_c must be >= 0 s/m, got {self.d_c}")

    def coefficient(self, slip_speed):
        """Friction coefficient at slip speed |v| [m/s] (numpy array or UFL expression)."""
        if isinstance(slip_speed, ufl.core.expr.Expr):
            return self.mu_d + (self.mu_s - self.mu_d) * ufl.exp(-self.d_c * slip_speed)
        return self.mu_d + (self.mu_s - self.mu_d) * np.exp(-self.d_c * np.abs(slip_speed))

    def derivative(self, slip_speed):
        """d mu / d|v| [s/m] (numpy array or UFL expression)."""
        if isinstance(slip_speed, ufl.core.expr.Expr):
            return -self.d_c * (self.mu_s - self.mu_d) * ufl.exp(-self.d_c * slip_speed)
        return -self.d_c * (self.mu_s - self.mu_d) * np.exp(-self.d_c * np.abs(slip_speed))
