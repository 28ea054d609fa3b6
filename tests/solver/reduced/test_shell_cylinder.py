"""Shell statics in the cylinder limit against Timoshenko's beam-on-elastic-foundation
solution, convergence of the collocation solution, and the cone -> cylinder limit."""

import math
from itertools import pairwise

import numpy as np
import pytest

from common.material import Material
from solver.reduced.shell import Meridian, Shell, ring_flexibility, solve_ring_load

MAT = Material(E=210e9, nu=0.3)
R, H, L = 0.3, 0.006, 1.4  # scaled TP: mid-surface radius, wall, length [m]


def cylinder() -> Shell:
    return Shell(Meridian((R, R), (0.0, L)), H, MAT)


def bef_constants(shell: Shell) -> tuple[float, float]:
    """lambda [1/m] and D [N m] of the long-cylinder solution."""
    lam = (3 * (1 - MAT.nu**2) / (R * H) ** 2) ** 0.25
    return lam, shell.bending_stiffness


def test_long_cylinder_edge_flexibility_matches_timoshenko():
    """Free lower edge, clamped top, lambda L = 42: edge ring shear Q0 and moment M0 give
    w = (Q0 + lambda M0) / (2 lambda^3 D) and slope (Q0 + 2 lambda M0) / (2 lambda^2 D)."""
    shell = cylinder()
    lam, D = bef_constants(shell)
    assert lam * L > 30  # the clamped end is "far": e^-30 effect
    F, _ = ring_flexibility(shell, 0.0, "top")
    # rows/cols: (u_r, u_z, beta) per (H, V, M); beta = -dw/ds, so at the lower edge
    # an outward shear gives positive beta (deflection decays upward)
    expected = {
        (0, 0): 1 / (2 * lam**3 * D),  # deflection per shear
        (2, 0): 1 / (2 * lam**2 * D),  # rotation per shear
        (0, 2): 1 / (2 * lam**2 * D),  # deflection per moment
        (2, 2): 1 / (lam * D),  # rotation per moment
    }
    for (i, j), value in expected.items():
        # acceptance asks for 0.5 %; lambda L = 42 and tol = 1e-8 make it agree to 1e-7
        assert F[i, j] == pytest.approx(value, rel=1e-7), (i, j)
    # membrane coupling: axial line load V (up at the lower edge, compressive) -> Poisson expansion
    assert F[0, 1] == pytest.approx(MAT.nu * R / (MAT.E * H), rel=1e-7)
    # axial: L / (E h), less a clamped-end Poisson effect of order nu^2 / (lambda L) = 0.2 %
    assert F[1, 1] == pytest.approx(L / (MAT.E * H), rel=5e-3)
    np.testing.assert_allclose(F, F.T, rtol=1e-8, atol=1e-12 * np.abs(F).max())  # Maxwell-Betti


def test_collocation_converges_to_the_closed_form_field():
    """Deflection field w(x) = e^-lx cos(lx) / (2 l^3 D) under unit edge shear: the error
    falls with the solver tolerance at >= 3rd order in the number of mesh nodes."""
    shell = cylinder()
    lam, D = bef_constants(shell)
    x = np.linspace(0.0, 5 / lam, 201)
    exact = np.exp(-lam * x) * np.cos(lam * x) / (2 * lam**3 * D)
    errors, nodes = [], []
    for tol in (1e-2, 1e-3, 1e-4, 1e-6):
        sol = solve_ring_load(shell, 0.0, (1.0, 0.0, 0.0), "top", tol=tol, nodes=5)
        w = sol.pieces[0](x / L)[0]
        errors.append(np.abs(w - exact).max() / exact.max())
        nodes.append(sol.pieces[0].interpolant.x.size)
    assert all(e2 < e1 for e1, e2 in pairwise(errors)), errors
    order = math.log(errors[0] / errors[-1]) / math.log(nodes[-1] / nodes[0])
    assert order > 3.0, (errors, nodes)
    assert errors[-1] < 1e-7


def test_cone_tends_to_cylinder_as_angle_vanishes():
    """Flexibility of a 1 deg-type cone -> the cylinder's, with an error linear in the angle."""
    F_cyl, _ = ring_flexibility(cylinder(), 0.0, "top")
    diffs = []
    for angle in (1e-2, 1e-3):
        cone = Shell(Meridian((R, R - L * math.tan(angle)), (0.0, L)), H, MAT)
        F, _ = ring_flexibility(cone, 0.0, "top")
        diffs.append(abs(F[0, 0] - F_cyl[0, 0]) / F_cyl[0, 0])
    assert diffs[1] < 1e-3
    assert diffs[0] / diffs[1] == pytest.approx(10.0, rel=0.2)


def test_bad_shell_input_raises():
    with pytest.raises(ValueError, match="increase strictly"):
        Meridian((R, R), (1.0, 0.0))
    with pytest.raises(ValueError, match="not thin"):
        Shell(Meridian((R, R), (0.0, L)), 0.1, MAT)
    with pytest.raises(ValueError, match="clamped"):
        solve_ring_load(cylinder(), 0.0, (1.0, 0.0, 0.0), "left")
    with pytest.raises(ValueError, match="outside"):
        solve_ring_load(cylinder(), 2.0, (1.0, 0.0, 0.0), "top")
