"""Reference natural frequencies of thin circular cylindrical shells (Rayleigh-Ritz).

An independent check of the 3D solid modal analysis: Sanders-Koiter (or Donnell)
thin-shell strain energy of a cylinder of mid-surface radius R, wall h, length L
[m], with displacements (axial u, circumferential v, radial w)

    u = U(x) cos(m theta),  v = V(x) sin(m theta),  w = W(x) cos(m theta),

and U, V, W expanded in Legendre polynomials times factors that enforce the end
conditions exactly (clamped end: u = v = w = dw/dx = 0; free end: nothing). The
Ritz frequencies converge from above to the shell-theory values as the number of
terms grows. Rotary inertia is neglected. SI units; frequencies in Hz.
"""

from typing import Literal

import numpy as np
from numpy.polynomial import Polynomial, legendre
from scipy.linalg import eigh

from common.material import Material

EndCondition = Literal["clamped", "free"]


def _bases(L: float, ends: tuple[EndCondition, EndCondition], n_terms: int) -> tuple[list, list]:
    """Polynomials for (U, V) and for W on [0, L] satisfying the end conditions."""
    for end in ends:
        if end not in ("clamped", "free"):
            raise ValueError(f"end condition must be 'clamped' or 'free', got {end!r}")
    x = Polynomial([0.0, 1.0])
    # clamped at x = 0 and/or x = L: u, v, w vanish (factor x), dw/dx too (factor x^2)
    f_uv, f_w = Polynomial([1.0]), Polynomial([1.0])
    if ends[0] == "clamped":
        f_uv, f_w = f_uv * x, f_w * x**2
    if ends[1] == "clamped":
        f_uv, f_w = f_uv * (L - x), f_w * (L - x) ** 2
    # Legendre polynomials on [0, L]
    legs = [
        legendre.Legendre.basis(k, domain=[0.0, L]).convert(kind=Polynomial) for k in range(n_terms)
    ]
    return [f_uv * p for p in legs], [f_w * p for p in legs]


def cylinder_frequencies(
    R: float,
    h: float,
    L: float,
    material: Material,
    m: int,
    ends: tuple[EndCondition, EndCondition] = ("clamped", "free"),
    n_terms: int = 14,
    theory: Literal["sanders", "donnell"] = "sanders",
) -> np.ndarray:
    """Ascending natural frequencies [Hz] of circumferential wave number m >= 1.

    The lowest one belongs to the lowest axial shape (n = 0 in docs/physics.md §5's convention),
    the next bending-dominated ones to n = 1, 2, ...
    """
    if not (R > 0 and h > 0 and L > 0):
        raise ValueError(f"R, h, L must be positive, got {R}, {h}, {L} m")
    if m < 1:
        raise ValueError(f"m must be >= 1 (m = 0 has uncoupled torsion), got {m}")
    if theory not in ("sanders", "donnell"):
        raise ValueError(f"theory must be 'sanders' or 'donnell', got {theory!r}")
    E, nu, rho = material.E, material.nu, material.rho
    C = E * h / (1 - nu**2)  # membrane stiffness [N/m]
    D = E * h**3 / (12 * (1 - nu**2))  # bending stiffness [N m]
    uv, ww = _bases(L, ends, n_terms)
    nb = n_terms
    xq, wq = np.polynomial.legendre.leggauss(2 * n_terms + 12)
    xq, wq = 0.5 * L * (xq + 1), 0.5 * L * wq

    def tab(polys, d):
        return np.array([p.deriv(d)(xq) if d else p(xq) for p in polys])  # (nb, nq)

    zero = np.zeros((nb, len(xq)))
    U, dU = tab(uv, 0), tab(uv, 1)
    V, dV = tab(uv, 0), tab(uv, 1)
    W, dW, ddW = tab(ww, 0), tab(ww, 1), tab(ww, 2)

    def block(u=zero, v=zero, w=zero):
        """Strain measure as a linear map of the coefficient vector (3 nb, nq)."""
        return np.concatenate([u, v, w])

    # membrane strains (cos, cos, sin in theta)
    e_x = block(u=dU)
    e_t = block(v=m * V / R, w=W / R)
    g_xt = block(u=-m * U / R, v=dV)
    # curvature changes
    k_x = block(w=-ddW)
    if theory == "sanders":
        k_t = block(v=m * V / R**2, w=m**2 * W / R**2)
        tau = block(u=m * U / (4 * R**2), v=0.75 * dV / R, w=m * dW / R)
    else:
        k_t = block(w=m**2 * W / R**2)
        tau = block(w=m * dW / R)

    def gram(a, b):
        return (a * wq) @ b.T

    # theta integral of cos^2 and sin^2 is pi; factor R for the area element
    K = (
        np.pi
        * R
        * (
            C
            * (
                gram(e_x, e_x)
                + gram(e_t, e_t)
                + nu * (gram(e_x, e_t) + gram(e_t, e_x))
                + 0.5 * (1 - nu) * gram(g_xt, g_xt)
            )
            + D
            * (
                gram(k_x, k_x)
                + gram(k_t, k_t)
                + nu * (gram(k_x, k_t) + gram(k_t, k_x))
                + 2 * (1 - nu) * gram(tau, tau)
            )
        )
    )
    disp = [block(u=U), block(v=V), block(w=W)]
    M = np.pi * R * rho * h * sum(gram(d, d) for d in disp)
    omega2 = eigh(K, M, eigvals_only=True)
    return np.sqrt(np.maximum(omega2, 0.0)) / (2 * np.pi)
