"""Cone parameters, derived quantities and case files (no DOLFINx)."""

import math
from pathlib import Path

import pytest
from scipy.integrate import quad

from common.material import Material
from geometry.parameters import ConePart, JointGeometry, MeshOptions, load_geometry

CASES = Path(__file__).resolve().parents[2] / "cases"


@pytest.fixture
def scaled() -> JointGeometry:
    return load_geometry(CASES / "scaled.toml")[0]


@pytest.mark.parametrize("name", ["mp", "tp"])
def test_volume_and_areas_against_quadrature(scaled, name):
    """Closed-form volume and cone areas equal numerical integration of the profile."""
    part: ConePart = getattr(scaled, name)

    def ro(z):
        return float(part.outer_radius(z))

    def ri(z):
        return float(part.inner_radius(z))

    pts = part.profile_heights()
    volume = sum(
        quad(lambda z: math.pi * (ro(z) ** 2 - ri(z) ** 2), a, b)[0]
        for a, b in zip(pts[:-1], pts[1:])
    )
    slant = 1.0 / math.cos(part.half_angle)
    a, b = part.cone_bottom_z, part.cone_top_z
    outer = quad(lambda z: 2 * math.pi * ro(z) * slant, a, b)[0]
    inner = quad(lambda z: 2 * math.pi * ri(z) * slant, a, b)[0]
    assert part.volume == pytest.approx(volume, rel=1e-12)
    assert part.outer_cone_area == pytest.approx(outer, rel=1e-12)
    assert part.inner_cone_area == pytest.approx(inner, rel=1e-12)


def test_scaled_case_derived_values(scaled):
    """docs/physics.md §2.1: straight parts placed as stated, first contact at the TP lower edge."""
    mp, tp = scaled.mp, scaled.tp
    assert (mp.cone_bottom_z, mp.cone_top_z, mp.total_length) == pytest.approx((0.4, 1.4, 1.4))
    assert (tp.cone_bottom_z, tp.cone_top_z, tp.total_length) == pytest.approx((0.0, 1.0, 1.4))
    # top diameters follow from the angles: D_b - 2 L tan(angle)
    assert mp.derived_top_outer_diameter == pytest.approx(0.6 - 2 * math.tan(math.radians(1.05)))
    assert tp.derived_top_outer_diameter == pytest.approx(0.61 - 2 * math.tan(math.radians(1.0)))
    # at first contact the TP's inner radius at its lower edge equals the MP's outer radius there
    z = scaled.first_contact_height
    assert float(mp.outer_radius(z)) == pytest.approx(float(tp.inner_radius(0.0)), abs=1e-12)
    # and the gap is positive everywhere above the edge (beta < alpha)
    zs = [z + 0.01 * k for k in range(1, int((1.4 - z) / 0.01))]
    gaps = [float(tp.inner_radius(zz - z) - mp.outer_radius(zz)) for zz in zs]
    assert min(gaps) > 0
    assert scaled.overlap == pytest.approx(1.4 - z)
    # docs/physics.md §2.2 formula, L_overlap being the overlap at full contact
    l_full = scaled.overlap + scaled.required_slip
    ratio = math.sin(math.radians(1.0)) / math.sin(math.radians(1.05))
    assert scaled.required_slip == pytest.approx(l_full * (1 - ratio), rel=1e-12)


def test_full_scale_case():
    """docs/physics.md §2.2: 6 m MP, overlap ~1.5 D at full contact, TP mass 151 t, nu = 0.33."""
    joint, material, options = load_geometry(CASES / "full_scale.toml")
    assert material.nu == 0.33
    assert joint.tp.mass(material) == pytest.approx(151e3, rel=2e-3)
    assert joint.full_contact_overlap == pytest.approx(1.5 * 6.0, rel=2e-3)
    assert joint.mp.total_length == pytest.approx(2 * joint.mp.cone_length)
    assert options.axial_size == pytest.approx(0.8)


@pytest.mark.parametrize(("angle", "d_b", "d_top"), [(1.05, 0.600, 0.584), (1.00, 0.610, 0.594)])
def test_tabulated_top_diameters_rejected(angle, d_b, d_top):
    """docs/physics.md §2.1's tabulated top diameters imply ~0.46 deg and must be rejected."""
    with pytest.raises(ValueError, match=r"inconsistent.*imply a half-angle of 0\.46 deg"):
        ConePart(angle, d_b, 1.0, 0.4, 0.006, top_outer_diameter=d_top)


def test_consistent_top_diameter_accepted():
    exact = 0.6 - 2 * math.tan(math.radians(1.05))
    part = ConePart(1.05, 0.6, 1.0, 0.4, 0.006, top_outer_diameter=round(exact, 4))
    assert part.derived_top_outer_diameter == pytest.approx(exact)


def test_case_file_errors(tmp_path):
    base = (CASES / "scaled.toml").read_text()
    cases = {
        "typo": (
            base.replace("thickness = 0.006            #", "thicknes = 0.006 #"),
            r"geometry\.mp\] has unknown key\(s\) \['thicknes'\]",
        ),
        "tabulated": (
            base.replace(
                "cone_length = 1.0            #", "top_outer_diameter = 0.584\ncone_length = 1.0 #"
            ),
            r"geometry\.mp\].*0\.46 deg",
        ),
        "steeper MP": (
            base.replace("= 1.05        # alpha", "= 0.9 # alpha"),
            "must be smaller than the MP half-angle",
        ),
        "bad mesh": (
            base.replace("n_circumferential = 48", "n_circumferential = 30"),
            r"\[mesh\] n_circumferential must be an integer multiple of 4",
        ),
        "bad material": (base.replace("nu = 0.3", "nu = 0.7"), r"\[material\] Poisson"),
    }
    for name, (text, message) in cases.items():
        assert text != base, name
        path = tmp_path / "case.toml"
        path.write_text(text)
        with pytest.raises(ValueError, match=message):
            load_geometry(path)


def test_ignores_other_sections(tmp_path):
    path = tmp_path / "case.toml"
    path.write_text((CASES / "scaled.toml").read_text() + '\n[post_processing]\nformat = "vtx"\n')
    joint, material, options = load_geometry(path)
    assert material == Material(E=210e9, nu=0.3, rho=7850.0)
    assert options == MeshOptions(contact_axial_size=0.01, contact_zone_above=0.15)
    assert joint.mp.half_angle_deg == 1.05


def test_preset_name_and_overrides():
    joint, _, options = load_geometry(
        "full_scale", ["mesh.n_circumferential=24", "geometry.tp.straight_length=1.0"]
    )
    assert options.n_circumferential == 24
    assert joint.tp.straight_length == 1.0
    with pytest.raises(ValueError, match=r"full_scale\.toml: \[mesh\] n_circumferential"):
        load_geometry("full_scale", ["mesh.n_circumferential=10"])
