"""Rigid contact map against closed forms for perfect and oval cones."""

import math
from pathlib import Path

import numpy as np
import pytest

from geometry.contact_map import plot_contact_map, rigid_contact_map
from geometry.imperfections import ovality
from geometry.parameters import JointGeometry, load_geometry

CASES = Path(__file__).resolve().parents[2] / "cases"


@pytest.fixture(scope="module")
def scaled() -> JointGeometry:
    return load_geometry(CASES / "scaled.toml")[0]


def closed_form_fraction(joint: JointGeometry, overlap: np.ndarray) -> np.ndarray:
    """Perfect cones: contact for zeta <= (o - o_fc) tan(a) / (tan(a) - tan(b)) (and zeta <= o)."""
    ta, tb = math.tan(joint.mp.half_angle), math.tan(joint.tp.half_angle)
    length, r0 = joint.tp.cone_length, float(joint.tp.inner_radius(0.0))
    zeta = np.clip((overlap - joint.overlap) * ta / (ta - tb), 0.0, np.minimum(overlap, length))

    def area(s):  # integral of r(zeta) d zeta, per radian
        return r0 * s - 0.5 * tb * s**2

    return area(zeta) / area(length)


def test_perfect_cones(scaled, tmp_path):
    cmap = rigid_contact_map(scaled, n_zeta=400)
    assert cmap.first_contact_overlap == pytest.approx(scaled.overlap, abs=1e-9)
    expected = closed_form_fraction(scaled, cmap.overlaps)
    assert np.max(np.abs(cmap.contact_fraction - expected)) < 2.0 / 400
    assert cmap.contact_fraction[0] == 0 and cmap.contact_fraction[-1] == pytest.approx(1.0)
    # every point touches first where the closed form says (grid of the sweep)
    ta, tb = math.tan(scaled.mp.half_angle), math.tan(scaled.tp.half_angle)
    onset = scaled.overlap + cmap.zeta * (ta - tb) / ta
    onset = np.maximum(onset, cmap.zeta)  # not before the point is over the MP top
    assert np.nanmax(np.abs(cmap.onset_overlap - onset[:, None])) < 1e-6
    assert plot_contact_map(cmap, tmp_path / "map").stat().st_size > 0


@pytest.mark.parametrize(
    ("imperfections", "shift"),
    [
        ({"tp": ovality(0.5e-3)}, -1.0),  # TP narrowest at 90 deg: touches 0.5 mm / tan(a) earlier
        ({"mp": ovality(0.5e-3)}, -1.0),  # MP widest at 0 deg: same
        ({"mp": ovality(0.5e-3), "tp": ovality(0.5e-3, phase_deg=90.0)}, -2.0),  # both, crossed
        ({"mp": ovality(0.5e-3), "tp": ovality(0.5e-3)}, 0.0),  # identical ovality: fits
    ],
)
def test_ovality_shifts_first_contact(scaled, imperfections, shift):
    """An m = 2 ovality of amplitude A shifts the first-contact overlap by k A / tan(alpha)."""
    cmap = rigid_contact_map(scaled, imperfections)
    expected = shift * 0.5e-3 / math.tan(scaled.mp.half_angle)
    tolerance = 0.01 * 0.5e-3 / math.tan(scaled.mp.half_angle)  # 1 % of the single shift
    assert cmap.first_contact_overlap - scaled.overlap == pytest.approx(expected, abs=tolerance)


def test_bad_input(scaled):
    with pytest.raises(ValueError, match="increasing"):
        rigid_contact_map(scaled, overlaps=[1.0, 0.9])
    with pytest.raises(ValueError, match="already in contact"):
        rigid_contact_map(scaled, overlaps=[1.0, 1.1])
    with pytest.raises(ValueError, match="no contact"):
        rigid_contact_map(scaled, overlaps=[0.5, 0.6])
    with pytest.raises(ValueError, match="imperfections keys"):
        rigid_contact_map(scaled, {"TP": ovality(1e-4)})
