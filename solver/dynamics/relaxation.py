"""Aitken relaxation of the fixed point in the friction coefficients of Newton on the contact
points (``solver.dynamics.point_newton``) when mu is taken at the iterate's slip speed
(docs/contact.md, section 6a).
"""

import numpy as np
import numpy.typing as npt

__all__ = ["CoefficientRelaxation"]


class CoefficientRelaxation:
    """Aitken relaxation of the fixed point in the friction coefficients of the outer iteration
    (mu at the iterate's slip speed): the inner problem of iteration k takes

        mu_k = mu_{k-1} + omega_k r_k,   r_k = mu(u_k) - mu_{k-1},
        omega_k = -omega_{k-1} r_{k-1} . (r_k - r_{k-1}) / |r_k - r_{k-1}|^2   (omega_1 = 1),

    clipped to [``omega_min``, ``omega_max``] and the coefficients to the law's range [``low``,
    ``high``]. A linear fixed point of rate c then takes omega = 1 / (1 - c) after two
    iterations: velocity weakening feeds slip back into slip (c near 1 in a settling event).
    The cap ``omega_max`` = 20 bounds the gain at c > 0.95 (c = 0.99: 116 iterations to 1e-12
    instead of about 2,500); a repelling fixed point (c > 1) is not reached. With mu fixed
    (lagged), r = 0 and mu_k = mu(u_k) bit for bit. :meth:`reset` at other points.
    ``CoefficientRelaxation(low, high, omega_max=1.0)`` is the plain fixed point.

    Args:
        low, high: the law's range of mu [-] (mu_d and mu_s).
        omega_min, omega_max: bounds of the relaxation factor [-].
        still: |r| [-] below which the coefficients count as not moving.
    """

    def __init__(
        self,
        low: float,
        high: float,
        omega_min: float = 0.1,
        omega_max: float = 20.0,
        still: float = 1e-6,
    ) -> None:
        self.low, self.high = low, high
        self.omega_min, self.omega_max, self.still = omega_min, omega_max, still
        self.reset()

    def reset(self) -> None:
        """Forget the iterates (new points, or a new solve): the next call returns mu(u_k)."""
        self._mu: npt.NDArray | None = None
        self._r: npt.NDArray | None = None
        self.omega = 1.0  #: the last relaxation factor [-]
        #: whether the last call's coefficients at the iterate differed from the last ones
        #: returned by more than ``still`` at some point
        self.moving = False

    def __call__(self, mu: npt.NDArray) -> npt.NDArray:
        """The coefficients (np,) [-] for the inner problem, from those at the iterate, ``mu``
        (np,) [-]."""
        if self._mu is None or len(self._mu) != len(mu):
            self.reset()
            self._mu = mu.copy()
            return mu
        r = mu - self._mu
        self.moving = bool(np.abs(r).max(initial=0.0) > self.still)
        if self._r is not None:
            dr = r - self._r
            denominator = float(dr @ dr)
            if denominator > 0:
                omega = -self.omega * float(self._r @ dr) / denominator
                self.omega = min(max(omega, self.omega_min), self.omega_max)
        self._r = r
        self._mu = np.clip(self._mu + self.omega * r, self.low, self.high)
        return self._mu
