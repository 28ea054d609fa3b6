"""The pointwise contact law of the Nitsche terms: multipliers from trial tractions, and their
generalized derivative (docs/contact.md).

At a slave point with unit contact normal n (out of the slave), friction coefficient mu and trial
traction P = P_n n + P_t [Pa] (P_n = sigma_n + gamma g, P_t = sigma_t - gamma ds, P_t . n = 0):

    lambda_n = min(P_n, 0),   p = -lambda_n [Pa],
    lambda_t = P_t                    if |P_t| <= mu p   (stick),
               mu p P_t / |P_t|       otherwise          (slip),

and lambda = lambda_n n + lambda_t. The kink P_n = 0 counts as active (in contact) for the
derivative. With mu held fixed, d lambda / d P is, per point (3 x 3):

    open   0,
    stick  I,
    slip   n n^T - mu q n^T + mu p / |P_t| (I - n n^T - q q^T),   q = P_t / |P_t|.
"""

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

__all__ = ["Multipliers", "derivative", "multipliers"]


@dataclass
class Multipliers:
    """The multipliers of ``multipliers`` and the points' state (arrays over points)."""

    normal: npt.NDArray  #: lambda_n [Pa] (<= 0)
    tangential: npt.NDArray  #: lambda_t (np, 3) [Pa]
    active: npt.NDArray  #: P_n <= 0
    stick: npt.NDArray  #: active and inside the friction disk
    slip: npt.NDArray  #: active and outside it

    def vector(self, n: npt.NDArray) -> npt.NDArray:
        """lambda = lambda_n n + lambda_t (np, 3) [Pa]."""
        return self.normal[:, None] * n + self.tangential


def multipliers(P_n: npt.NDArray, P_t: npt.NDArray, mu: npt.NDArray) -> Multipliers:
    """The multipliers of trial tractions P_n (np,) and P_t (np, 3) [Pa] with coefficients mu."""
    active = P_n <= 0
    lam_n = np.where(active, P_n, 0.0)
    radius = -mu * lam_n
    norm = np.linalg.norm(P_t, axis=1)
    stick = active & (norm <= radius)
    slip = active & ~stick
    scale = np.where(slip, radius / np.where(norm > 0, norm, 1.0), 1.0)
    lam_t = np.where(active[:, None], P_t * scale[:, None], 0.0)
    return Multipliers(lam_n, lam_t, active, stick, slip)


def derivative(
    n: npt.NDArray,
    P_t: npt.NDArray,
    mu: npt.NDArray,
    pressure: npt.NDArray,
    stick: npt.NDArray,
    slip: npt.NDArray,
) -> npt.NDArray:
    """d lambda / d P (np, 3, 3) at points tied in the normal direction: the stick points also
    tangentially, the ``slip`` points by the derivative of the projection onto the friction disk
    (mu fixed); points in neither set are tied normally only (n n^T)."""
    D = n[:, :, None] * n[:, None, :]
    D[stick] = np.eye(3)
    if slip.any():
        s = np.flatnonzero(slip)
        norm = np.linalg.norm(P_t[s], axis=1)
        q = P_t[s] / norm[:, None]
        ns = n[s]
        tangent = np.eye(3) - ns[:, :, None] * ns[:, None, :] - q[:, :, None] * q[:, None, :]
        D[s] += (mu[s] * pressure[s] / norm)[:, None, None] * tangent
        D[s] -= mu[s][:, None, None] * q[:, :, None] * ns[:, None, :]
    return D
