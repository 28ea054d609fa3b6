"""The inner problem of Newton on the contact points (``solver.dynamics.point_newton``): the
candidates' trial tractions y (3 per point) [Pa] solve

    Phi(y) = y - y_free + G lambda(y) = 0

with the dense compliance G and the multipliers lambda of the pointwise law
(``solver.contact.law``) at fixed normals and friction coefficients (docs/contact.md,
section 6a, "Inner problem").
"""

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
import numpy.typing as npt

from common.timing import timed
from solver.contact.law import Multipliers, derivative, multipliers
from solver.dynamics.traction_jacobian import TractionJacobian

__all__ = [
    "Evaluation",
    "TractionSolution",
    "pointwise_law",
    "solve_tractions",
    "stick_restart",
    "traction_residual",
]


@dataclass
class TractionSolution:
    """Outcome of :func:`solve_tractions`: the trial tractions y [Pa], the multipliers
    lambda(y) [Pa] (both 3 per point), the iterations and whether ||Phi|| met the tolerance."""

    y: npt.NDArray
    multipliers: npt.NDArray
    iterations: int
    converged: bool


def pointwise_law(
    y: npt.NDArray, normal: npt.NDArray, mu: npt.NDArray
) -> tuple[npt.NDArray, Multipliers]:
    """The pointwise law at trial tractions y (3 per point) [Pa], unit normals (np, 3) and
    coefficients mu (np,) [-]: the tangential trial tractions P_t (np, 3) [Pa] and the
    multipliers."""
    P = y.reshape(-1, 3)
    P_n = np.einsum("pi,pi->p", P, normal)
    P_t = P - P_n[:, None] * normal
    return P_t, multipliers(P_n, P_t, mu)


class Evaluation(NamedTuple):
    """The pointwise law and Phi at trial tractions y (:func:`traction_residual`)."""

    P_t: npt.NDArray  #: tangential trial tractions (np, 3) [Pa]
    law: Multipliers  #: the multipliers and each point's state
    lam: npt.NDArray  #: the multipliers as a vector, 3 per point [Pa]
    phi: npt.NDArray  #: Phi(y), 3 per point [Pa]


def traction_residual(
    jacobian: TractionJacobian,
    y: npt.NDArray,
    y_free: npt.NDArray,
    normal: npt.NDArray,
    mu: npt.NDArray,
) -> Evaluation:
    """Phi(y) = y - y_free + G lambda(y) [Pa] with the jacobian's G, and P_t and the multipliers
    at y (as ``pointwise_law``; lambda also as a vector, 3 per point)."""
    P_t, lam = pointwise_law(y, normal, mu)
    lam_y = lam.vector(normal).ravel()
    return Evaluation(
        P_t, lam, lam_y, y - y_free + jacobian.times(lam_y, np.flatnonzero(lam.active))
    )


def stick_restart(y: npt.NDArray, normal: npt.NDArray, mu: npt.NDArray) -> npt.NDArray:
    """The trial tractions y (3 per point) [Pa] with each slipping point's tangential part pulled
    just inside its friction disk (radius mu p, p = -P_n > 0): those points become stuck."""
    P = y.reshape(-1, 3)
    P_n = np.einsum("pi,pi->p", P, normal)
    P_t = P - P_n[:, None] * normal
    radius = np.linalg.norm(P_t, axis=1)
    limit = mu * np.maximum(-P_n, 0.0)
    slipping = (P_n < 0) & (radius > limit)
    scale = np.ones_like(radius)
    scale[slipping] = (1.0 - 1e-3) * limit[slipping] / radius[slipping]
    return (P_n[:, None] * normal + scale[:, None] * P_t).ravel()


@timed("tractions")
def solve_tractions(
    G: npt.NDArray,
    y_free: npt.NDArray,
    y0: npt.NDArray,
    normal: npt.NDArray,
    mu: npt.NDArray,
    rtol: float = 1e-12,
    max_iterations: int = 60,
    max_backtracks: int = 12,
    jacobian: TractionJacobian | None = None,
    restarts: int = 2,
    evaluated: Evaluation | None = None,
    area: npt.NDArray | None = None,
    force_tol: float = 0.0,
) -> TractionSolution:
    """Solve Phi(y) = y - y_free + G lambda(y) = 0 for the trial tractions y [Pa] of points with
    normals ``normal`` (np, 3) and friction coefficients ``mu`` (np,), from y0.

    Semismooth Newton: (I + G D) dy = -Phi with D = d lambda / d y (``solver.contact.law``), whose
    columns vanish at open points, so that only the active points' block is solved
    (``solver.dynamics.traction_jacobian``); the step is halved while ||Phi|| does not decrease.
    Where no step decreases ||Phi|| (the slip law's derivative does not see a point that should
    stick: Newton stalls with every point slipping), the iteration restarts from
    :func:`stick_restart` of its iterate, at most ``restarts`` times. Converged when
    ||Phi|| <= rtol max(||y_free||, ||y||) (infinity norms), or where ``area`` (np,) [m^2] is
    given, when Phi as forces on the points, ||area Phi|| (2-norm), is at most ``force_tol`` [N]
    (the accuracy an outer Newton iteration needs). ``jacobian``: kept by the caller
    between calls for the same points, so that its factors are reused. ``evaluated``:
    :func:`traction_residual` at y0 with this G, y_free, normal and mu, where the caller has
    it already.
    """
    if jacobian is None:
        jacobian = TractionJacobian()
    jacobian.set_compliance(G)

    def evaluate(y: npt.NDArray) -> Evaluation:
        return traction_residual(jacobian, y, y_free, normal, mu)

    y = y0.copy()
    P_t, lam, lam_y, phi = evaluate(y) if evaluated is None else evaluated
    norm = float(np.linalg.norm(phi))
    scale = max(np.abs(y_free).max(initial=0.0), np.abs(y).max(initial=0.0), 1.0)

    def converged() -> bool:
        if np.abs(phi).max(initial=0.0) <= rtol * scale:
            return True
        return area is not None and np.linalg.norm(area[:, None] * phi.reshape(-1, 3)) <= force_tol

    for iteration in range(max_iterations + 1):
        if converged():
            return TractionSolution(y, lam_y, iteration, True)
        if iteration == max_iterations:
            break
        active = np.flatnonzero(lam.active)
        dy = -phi
        if active.size:
            D = derivative(
                normal[active],
                P_t[active],
                mu[active],
                -lam.normal[active],
                lam.stick[active],
                lam.slip[active],
            )
            dy = jacobian.direction(active, D, phi)
        alpha, accepted = 1.0, False
        for _ in range(max_backtracks + 1):
            trial = y + alpha * dy
            P_t_trial, lam_trial, lam_trial_y, phi_trial = evaluate(trial)
            norm_trial = float(np.linalg.norm(phi_trial))
            if norm_trial < (1.0 - 1e-4 * alpha) * norm:
                accepted = True
                break
            alpha *= 0.5
        if not accepted:
            if restarts == 0:
                break
            restarts -= 1
            y = stick_restart(y, normal, mu)
            P_t, lam, lam_y, phi = evaluate(y)
            norm = float(np.linalg.norm(phi))
            continue
        y, P_t, lam, lam_y, phi, norm = (
            trial,
            P_t_trial,
            lam_trial,
            lam_trial_y,
            phi_trial,
            norm_trial,
        )
    return TractionSolution(y, lam_y, iteration, False)
