"""Newmark-family time integration: parameters, effective-system coefficients and updates.

One scheme covers three integrators (Chung & Hulbert 1993 convention): the balance

    M a_{n+1-alpha_m} + C v_{n+1-alpha_f} + K u_{n+1-alpha_f} + r_c = f_{n+1-alpha_f},
    x_{n+1-alpha} = (1 - alpha) x_{n+1} + alpha x_n,

with the Newmark relations

    u_{n+1} = u_n + dt v_n + dt^2 ((1/2 - beta) a_n + beta a_{n+1}),
    v_{n+1} = v_n + dt ((1 - gamma) a_n + gamma a_{n+1}).

* Newmark (alpha_m = alpha_f = 0): average acceleration beta = 1/4, gamma = 1/2 by
  default (unconditionally stable, second order, no numerical dissipation: the
  discrete energy of an undamped linear system is conserved exactly);
* generalised-alpha (``GeneralisedAlpha.from_spectral_radius(rho_inf)``): second
  order, unconditionally stable, dissipates the high-frequency content (rho_inf < 1
  is the spectral radius at dt -> infinity); recommended against contact chatter;
* quasi-static (``QuasiStatic``): no inertia and no damping, K u + r_c = f; the
  velocity is the backward difference (u_{n+1} - u_n)/dt (used by the friction law).

Dividing the balance by (1 - alpha_f) gives the effective system solved for u_{n+1}:

    A u_{n+1} + r_c(u_{n+1}) = b,   A = K + c_M M + c_C C,
    c_M = (1 - alpha_m) / ((1 - alpha_f) beta dt^2),   c_C = gamma / (beta dt),

see ``history`` for b. Units: dt in s, u in m, v in m/s, a in m/s^2.
"""

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class GeneralisedAlpha:
    """Parameters of the generalised-alpha / Newmark family (defaults: average acceleration)."""

    beta: float = 0.25  #: Newmark beta [-]
    gamma: float = 0.5  #: Newmark gamma [-]
    alpha_m: float = 0.0  #: weight of a_n in the inertia term [-]
    alpha_f: float = 0.0  #: weight of step n in the internal and external forces [-]

    def __post_init__(self) -> None:
        if not 0 < self.beta <= 1:
            raise ValueError(f"Newmark beta must lie in (0, 1], got {self.beta}")
        if not 0.5 <= self.gamma <= 1.5:
            raise ValueError(f"Newmark gamma must lie in [0.5, 1.5], got {self.gamma}")
        if not 0 <= self.alpha_f < 1 or not -1 <= self.alpha_m < 1:
            raise ValueError(
                f"need 0 <= alpha_f < 1 and -1 <= alpha_m < 1, got {self.alpha_f}, {self.alpha_m}"
            )

    @classmethod
    def from_spectral_radius(cls, rho_inf: float) -> "GeneralisedAlpha":
        """Chung-Hulbert generalised-alpha with high-frequency spectral radius rho_inf in [0, 1]."""
        if not 0 <= rho_inf <= 1:
            raise ValueError(f"spectral radius rho_inf must lie in [0, 1], got {rho_inf}")
        alpha_m = (2 * rho_inf - 1) / (rho_inf + 1)
        alpha_f = rho_inf / (rho_inf + 1)
        gamma = 0.5 - alpha_m + alpha_f
        return cls(
            beta=0.25 * (1 - alpha_m + alpha_f) ** 2, gamma=gamma, alpha_m=alpha_m, alpha_f=alpha_f
        )

    @property
    def dynamic(self) -> bool:
        return True

    def coefficients(self, dt: float) -> tuple[float, float]:
        """(c_M [1/s^2], c_C [1/s]) of the effective operator A = K + c_M M + c_C C."""
        if not dt > 0:
            raise ValueError(f"time step must be positive, got {dt} s")
        c_M = (1 - self.alpha_m) / ((1 - self.alpha_f) * self.beta * dt**2)
        return c_M, self.gamma / (self.beta * dt)

    def history(
        self, u: np.ndarray, v: np.ndarray, a: np.ndarray, dt: float
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Known parts (a_hat, v_hat, u_hat) of a_{n+1-alpha_m}, v_{n+1-alpha_f}, u_{n+1-alpha_f}.

        a_{n+1-alpha_m} = (1-alpha_f) c_M u_{n+1} + a_hat, v_{n+1-alpha_f} = (1-alpha_f) c_C u_{n+1}
        + v_hat, u_{n+1-alpha_f} = (1-alpha_f) u_{n+1} + u_hat, hence the effective load
        b = (f_{n+1-alpha_f} - alpha_f r_c,n - M a_hat - C v_hat - K u_hat) / (1 - alpha_f).
        """
        b, g, am, af = self.beta, self.gamma, self.alpha_m, self.alpha_f
        a_pred = -(u + dt * v) / (b * dt**2) - (0.5 / b - 1) * a  # a_{n+1} minus its u_{n+1} part
        v_pred = v + dt * (1 - g) * a + g * dt * a_pred  # v_{n+1} minus its u_{n+1} part
        return (1 - am) * a_pred + am * a, (1 - af) * v_pred + af * v, af * u

    def update(
        self, u_new: np.ndarray, u: np.ndarray, v: np.ndarray, a: np.ndarray, dt: float
    ) -> tuple[np.ndarray, np.ndarray]:
        """Newmark update: (v_{n+1}, a_{n+1}) from u_{n+1} and the state at step n."""
        a_new = (u_new - u - dt * v) / (self.beta * dt**2) - (0.5 / self.beta - 1) * a
        v_new = v + dt * ((1 - self.gamma) * a + self.gamma * a_new)
        return v_new, a_new


@dataclass(frozen=True)
class QuasiStatic:
    """No inertia or damping: K u + r_c(u) = f at each load step; v = (u_{n+1} - u_n)/dt, a = 0."""

    alpha_f: float = 0.0  #: no time weighting of the forces (field for a uniform interface)

    @property
    def dynamic(self) -> bool:
        return False

    def coefficients(self, dt: float) -> tuple[float, float]:
        if not dt > 0:
            raise ValueError(f"time step must be positive, got {dt} s")
        return 0.0, 0.0

    def history(
        self, u: np.ndarray, v: np.ndarray, a: np.ndarray, dt: float
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        zero = np.zeros_like(u)
        return zero, zero, zero

    def update(
        self, u_new: np.ndarray, u: np.ndarray, v: np.ndarray, a: np.ndarray, dt: float
    ) -> tuple[np.ndarray, np.ndarray]:
        return (u_new - u) / dt, np.zeros_like(a)


Scheme = GeneralisedAlpha | QuasiStatic


def scheme_from_name(name: str, rho_inf: float = 0.8) -> Scheme:
    """Scheme from a case-file name: 'newmark' (average acceleration), 'generalised-alpha', 'quasi-static'."""
    schemes = {
        "newmark": GeneralisedAlpha,
        "generalised-alpha": lambda: GeneralisedAlpha.from_spectral_radius(rho_inf),
        "quasi-static": QuasiStatic,
    }
    if name not in schemes:
        raise ValueError(f"unknown time scheme {name!r}; choose one of {sorted(schemes)}")
    return schemes[name]()
