"""Structural damping: Rayleigh C = a M + b K, and modal damping of the first N modes.

A single mode of circular frequency omega [rad/s] gets the damping ratio

    Rayleigh:  zeta(omega) = a / (2 omega) + b omega / 2,
    modal:     zeta_i for the given modes, zero for all others,

with a in 1/s and b in s. Modal damping uses M-orthonormal mode shapes phi_i
(phi_i^T M phi_j = delta_ij) and the low-rank operator
C = M Phi diag(2 zeta_i omega_i) Phi^T M, never assembled (it is dense).
"""

from dataclasses import dataclass
from collections.abc import Sequence

import numpy as np
from petsc4py import PETSc


@dataclass(frozen=True)
class RayleighDamping:
    """C = a M + b K with a [1/s] (mass-proportional) and b [s] (stiffness-proportional)."""

    a: float = 0.0
    b: float = 0.0

    def __post_init__(self) -> None:
        if self.a < 0 or self.b < 0:
            raise ValueError(
                f"Rayleigh coefficients must be >= 0, got a={self.a} 1/s, b={self.b} s"
            )

    @classmethod
    def from_two_frequencies(
        cls, zeta1: float, f1: float, zeta2: float, f2: float
    ) -> "RayleighDamping":
        """Coefficients giving damping ratios zeta1 at f1 [Hz] and zeta2 at f2 [Hz] exactly."""
        if not (f1 > 0 and f2 > 0) or f1 == f2:
            raise ValueError(f"need two distinct positive frequencies, got {f1} Hz and {f2} Hz")
        w1, w2 = 2 * np.pi * f1, 2 * np.pi * f2
        a, b = np.linalg.solve([[1 / (2 * w1), w1 / 2], [1 / (2 * w2), w2 / 2]], [zeta1, zeta2])
        return cls(a=float(a), b=float(b))

    @classmethod
    def at_frequency(cls, zeta: float, f: float) -> "RayleighDamping":
        """zeta at f [Hz], where zeta(omega) has its minimum (a/(2 omega) = b omega/2 = zeta/2)."""
        if not f > 0 or zeta < 0:
            raise ValueError(f"need f > 0 Hz and zeta >= 0, got f={f}, zeta={zeta}")
        w = 2 * np.pi * f
        return cls(a=zeta * w, b=zeta / w)

    def ratio(self, f: float | np.ndarray) -> float | np.ndarray:
        """Damping ratio [-] of a mode at frequency f [Hz]."""
        w = 2 * np.pi * np.asarray(f)
        return self.a / (2 * w) + self.b * w / 2


class ModalDamping:
    """C = M Phi diag(2 zeta_i omega_i) Phi^T M from M-orthonormal modes (low rank, matrix-free)."""

    def __init__(
        self,
        M: PETSc.Mat,
        modes: Sequence[PETSc.Vec],
        frequencies_hz: Sequence[float],
        zeta: float | Sequence[float] = 0.01,
    ):
        if len(modes) == 0 or len(modes) != len(frequencies_hz):
            raise ValueError(
                f"need one frequency per mode, got {len(modes)} modes, {len(frequencies_hz)} frequencies"
            )
        zeta = np.broadcast_to(np.asarray(zeta, dtype=float), (len(modes),))
        if np.any(zeta < 0) or np.any(np.asarray(frequencies_hz) <= 0):
            raise ValueError("modal damping needs zeta >= 0 and positive frequencies")
        self.coefficients = 2 * zeta * 2 * np.pi * np.asarray(frequencies_hz, dtype=float)  # [1/s]
        self.zeta = zeta
        self.frequencies_hz = np.asarray(frequencies_hz, dtype=float)
        self.M_modes = []  # u_i = M phi_i
        for phi in modes:
            y = M.createVecLeft()
            M.mult(phi, y)
            self.M_modes.append(y)

    def ratio(self, f: float) -> float:
        """Damping ratio [-] of a response at f [Hz]: that of the damped mode nearest in ratio
        (|ln(f / f_i)|), zero beyond 10 % above the highest damped mode (undamped there)."""
        if f > 1.1 * self.frequencies_hz.max():
            return 0.0
        return float(self.zeta[np.argmin(np.abs(np.log(f / self.frequencies_hz)))])

    def mult(self, v: PETSc.Vec, out: PETSc.Vec) -> None:
        """out += C v [N]."""
        for c, y in zip(self.coefficients, self.M_modes):
            out.axpy(c * y.dot(v), y)

    def check_step(self, dt: float) -> None:
        """The modal damping force is explicit in time: require 2 zeta omega dt <= 0.5 for every mode."""
        worst = float(np.max(self.coefficients)) * dt
        if worst > 0.5:
            raise ValueError(
                f"time step {dt} s too large for explicit modal damping (2 zeta omega dt = {worst:.3g} > 0.5)"
            )
