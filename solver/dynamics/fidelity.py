"""Resonance fidelity of the Newmark-family schemes: algorithmic damping, period error and the
excitation frequency that makes up for the period error.

A time scheme applied to the modal oscillator q'' + 2 zeta omega q' + omega^2 q = 0 advances
x_n = (q_n, dt q'_n, dt^2 q''_n) by the amplification matrix, x_{n+1} = G(omega dt) x_n. Its
principal pair of eigenvalues lambda = exp(dt (-xi_h +- i) omega_h) defines the discrete
oscillator: its natural frequency omega_h and damping ratio xi_h. For zeta = 0:

    algorithmic damping ratio   xi_h = -ln|lambda| / arg(lambda)                 [-]
    period error                T_h / T - 1 = omega dt / arg(lambda) - 1          [-]

(Hilber and Hughes 1978, Chung and Hulbert 1993.) The time-discrete model of a mode at
omega therefore resonates at omega_h < omega; exciting it at omega would sit
(T_h / T - 1) / (2 zeta) half-power bandwidths away from its resonance. The compensated
excitation frequency f_c is the one at which, with dt = 1 / (f_c steps_per_period), the
discrete natural frequency equals f_c.
"""

from dataclasses import dataclass

import numpy as np
import scipy.optimize

from solver.dynamics.schemes import GeneralisedAlpha, QuasiStatic, Scheme

__all__ = [
    "SchemeAccuracy",
    "accuracy",
    "amplification_matrix",
    "compensated_frequency",
    "discrete_frequency",
]


def amplification_matrix(
    scheme: GeneralisedAlpha, omega_dt: float, zeta: float = 0.0
) -> np.ndarray:
    """G with x_{n+1} = G x_n, x = (q, dt q', dt^2 q'') for q'' + 2 zeta omega q' + omega^2 q = 0.

    Rows of the balance (1 - alpha_m) a_{n+1} + alpha_m a_n + 2 zeta omega v_{n+1-alpha_f} +
    omega^2 q_{n+1-alpha_f} = 0 and the two Newmark relations, in dimensionless form.
    """
    b, g, am, af = scheme.beta, scheme.gamma, scheme.alpha_m, scheme.alpha_f
    w, c = omega_dt, 2.0 * zeta * omega_dt
    lhs = np.array([[w**2 * (1 - af), c * (1 - af), 1 - am], [1.0, 0.0, -b], [0.0, 1.0, -g]])
    rhs = np.array([[-(w**2) * af, -c * af, -am], [1.0, 1.0, 0.5 - b], [0.0, 1.0, 1.0 - g]])
    return np.linalg.solve(lhs, rhs)


def _principal(scheme: GeneralisedAlpha, omega_dt: float) -> complex:
    """The principal (oscillating) eigenvalue of G(omega dt), upper half plane."""
    eigenvalues = np.linalg.eigvals(amplification_matrix(scheme, omega_dt))
    principal = eigenvalues[np.argmax(eigenvalues.imag)]
    if not principal.imag > 0:
        raise ValueError(
            f"omega dt = {omega_dt:.3g} is beyond the scheme's oscillation limit (too few steps per period)"
        )
    return complex(principal)


@dataclass(frozen=True)
class SchemeAccuracy:
    """Dispersion of a scheme at a number of steps per (physical) period."""

    steps_per_period: float
    damping_ratio: float  #: algorithmic damping ratio xi_h [-]
    period_error: float  #: relative period elongation T_h / T - 1 [-]


def accuracy(scheme: Scheme, steps_per_period: float) -> SchemeAccuracy:
    """Algorithmic damping ratio and period error of ``scheme`` for an undamped mode sampled with
    ``steps_per_period`` steps per period (omega dt = 2 pi / steps_per_period)."""
    if isinstance(scheme, QuasiStatic):
        raise ValueError("the quasi-static scheme has no inertia: it cannot represent a resonance")
    omega_dt = 2 * np.pi / steps_per_period
    lam = _principal(scheme, omega_dt)
    phase = np.angle(lam)
    return SchemeAccuracy(steps_per_period, -np.log(abs(lam)) / phase, omega_dt / phase - 1.0)


def discrete_frequency(scheme: GeneralisedAlpha, frequency_hz: float, dt: float) -> float:
    """Natural frequency [Hz] of the time-discrete model of an undamped mode at ``frequency_hz``."""
    return np.angle(_principal(scheme, 2 * np.pi * frequency_hz * dt)) / (2 * np.pi * dt)


def compensated_frequency(
    scheme: GeneralisedAlpha, frequency_hz: float, steps_per_period: int
) -> float:
    """Excitation frequency f_c [Hz] at which the time-discrete model of the mode at ``frequency_hz``
    resonates when stepped with dt = 1 / (f_c steps_per_period): arg lambda(omega dt) = 2 pi / N."""
    target = 2 * np.pi / steps_per_period
    x = scipy.optimize.brentq(
        lambda x: np.angle(_principal(scheme, x)) - target,
        0.5 * target,
        2.0 * target,
        xtol=1e-15,
        rtol=1e-15,
    )
    return frequency_hz * target / x
