"""Reduced-model springs of both case files against long-cylinder closed forms.

The TP and MP are 1 deg cones whose bending layers (1/lambda of a few cm / dm) are
short against their lengths, so the springs must be close (<1 %) to the values of a
long cylinder of the local radius: TP edge with the other edge displacements held
(diagonal of the inverted flexibility) 4 lambda^3 D and 2 lambda D, free edge
2 lambda^3 D; MP interior ring 8 lambda^3 D; MP tangential: membrane E h / L_c.
"""

import math

import pytest

from geometry.parameters import load_geometry
from solver.reduced.shell import joint_stiffness, mp_contact_shell, tp_edge_shell


def lam(shell, r: float) -> float:
    return (3 * (1 - shell.material.nu**2) / (r * shell.thickness) ** 2) ** 0.25


@pytest.mark.parametrize("case", ["cases/full_scale.toml", "cases/scaled.toml"])
def test_springs_match_long_cylinder_values(case):
    joint, material, _ = load_geometry(case)
    springs = joint_stiffness(joint, material, tol=1e-6)

    tp = tp_edge_shell(joint, material)
    r, D = tp.meridian.r[0], tp.bending_stiffness
    lt = lam(tp, r)
    ring = 2 * math.pi * r
    assert springs.K_r == pytest.approx(ring * 4 * lt**3 * D, rel=0.01)
    assert springs.K_rot == pytest.approx(ring * 2 * lt * D, rel=0.01)
    assert springs.K_r_free == pytest.approx(ring * 2 * lt**3 * D, rel=0.01)

    mp, z_c = mp_contact_shell(joint, material)
    r_c = mp.meridian.radius(z_c)
    lm = lam(mp, r_c)
    assert lm * (z_c - mp.meridian.z[0]) > 20 and lm * (mp.meridian.z[-1] - z_c) > 20
    ring = 2 * math.pi * r_c
    assert springs.K_N == pytest.approx(ring * 8 * lm**3 * mp.bending_stiffness, rel=0.01)
    membrane = ring * material.E * mp.thickness / (z_c - mp.meridian.z[0])
    assert springs.K_T == pytest.approx(membrane, rel=0.01)
    # the masses are positive and below the parts' masses
    assert 0 < springs.m_r < joint.tp.mass(material)
    assert 0 < springs.m_T < joint.mp.mass(material)


def test_mp_clamp_lies_twice_the_cone_length_below_its_top():
    joint, material, _ = load_geometry("cases/scaled.toml")
    mp, z_c = mp_contact_shell(joint, material)
    assert mp.meridian.z[-1] - mp.meridian.z[0] == pytest.approx(2 * joint.mp.cone_length)
    assert z_c == pytest.approx(joint.first_contact_height)
