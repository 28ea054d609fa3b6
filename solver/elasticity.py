"""Linear elasticity in UFL: strain and stress (SI units, small strain).

Conventions: displacement u in m, stress in Pa; the material is ``common.material.Material``.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import ufl

if TYPE_CHECKING:
    from common.material import Material

__all__ = ["epsilon", "sigma"]


def epsilon(u: ufl.core.expr.Expr) -> ufl.core.expr.Expr:
    """Small-strain tensor sym(grad u) [-]."""
    return ufl.sym(ufl.grad(u))


def sigma(u: ufl.core.expr.Expr, material: Material) -> ufl.core.expr.Expr:
    """Cauchy stress of Hooke's law [Pa]."""
    eps = epsilon(u)
    return 2.0 * material.mu * eps + material.lmbda * ufl.tr(eps) * ufl.Identity(len(u))
