"""Linear elasticity in UFL: strain and stress (SI units, small strain).

Conventions: displacement u in m, stress in Pa; the material is ``common.material.Material``.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import ufl

if TYPE_CHECKING:
    import dolfinx

    from common.material import Material

__all__ = ["elastic_forms", "epsilon", "sigma"]


def epsilon(u: ufl.core.expr.Expr) -> ufl.core.expr.Expr:
    """Small-strain tensor sym(grad u) [-]."""
    return ufl.sym(ufl.grad(u))


def sigma(u: ufl.core.expr.Expr, material: Material) -> ufl.core.expr.Expr:
    """Cauchy stress of Hooke's law [Pa]."""
    eps = epsilon(u)
    return 2.0 * material.mu * eps + material.lmbda * ufl.tr(eps) * ufl.Identity(len(u))


def elastic_forms(V: dolfinx.fem.FunctionSpace, material: Material) -> tuple[ufl.Form, ufl.Form]:
    """The bilinear forms of stiffness, int sigma(u) : eps(v) dx [N/m], and mass,
    int rho u . v dx [kg], on the function space V."""
    u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    dx = ufl.dx(domain=V.mesh)
    return ufl.inner(sigma(u, material), epsilon(v)) * dx, material.rho * ufl.inner(u, v) * dx
