"""Thin cylinders meshed by geometry/: solid modal analysis against shell theory.

Reference: Rayleigh-Ritz with Sanders-Koiter shell energy and Legendre series
(solver/reduced/cylinder_shell.py), itself checked against the published clamped-clamped
benchmark (~1701 Hz).
"""

import numpy as np
import pytest
from mpi4py import MPI

from common.material import Material
from geometry import tags
from geometry.mesh import create_tube_mesh
from geometry.parameters import ConePart, MeshOptions
from solver.modal.classify import classify
from solver.modal.eigen import EigenOptions, clamp, modal_analysis
from solver.reduced.cylinder_shell import cylinder_frequencies

from dolfinx import fem

pytestmark = pytest.mark.mpi

STEEL = Material(E=210e9, nu=0.3, rho=7850.0)
BENCH = Material(E=200e9, nu=0.3, rho=7800.0)


def tube(R: float, h: float, L: float, options: MeshOptions, degree: int):
    """Straight tube of mid-surface radius R, wall h, length L [m] and its Lagrange space."""
    part = ConePart(
        half_angle_deg=0.0,
        bottom_outer_diameter=2 * (R + h / 2),
        cone_length=L,
        straight_length=0.0,
        thickness=h,
    )
    mesh_data = create_tube_mesh(MPI.COMM_WORLD, part, options)
    return mesh_data, fem.functionspace(mesh_data.mesh, ("Lagrange", degree, (3,)))


def test_ritz_reference_is_converged_and_matches_published_benchmark():
    f14 = cylinder_frequencies(0.297, 0.006, 1.4, STEEL, 3, n_terms=14)[:3]
    f20 = cylinder_frequencies(0.297, 0.006, 1.4, STEEL, 3, n_terms=20)[:3]
    np.testing.assert_allclose(f14, f20, rtol=1e-4)
    f_cc = cylinder_frequencies(0.1, 0.01, 0.4, BENCH, 2, ends=("clamped", "clamped"))[0]
    assert f_cc == pytest.approx(1701.0, rel=0.005)


def test_donnell_is_stiffer_at_low_m_and_joins_sanders_as_m_grows():
    """Donnell's curvatures drop the in-plane displacements' terms of Sanders-Koiter's, which
    matter at small m: the lowest frequency comes out higher, by an excess that falls off like
    1 / m^2 once the mode is dominated by the wall's bending (m >= 3)."""
    ms = (2, 3, 4, 6, 8, 12, 16)
    excess = np.array(
        [
            cylinder_frequencies(0.297, 0.006, 1.4, STEEL, m, theory="donnell")[0]
            / cylinder_frequencies(0.297, 0.006, 1.4, STEEL, m)[0]
            - 1
            for m in ms
        ]
    )
    print(
        "Donnell against Sanders, lowest frequency per m: "
        + ", ".join(f"m = {m}: {100 * e:+.2f} %" for m, e in zip(ms, excess))
    )
    assert np.all(excess > 0)
    assert np.all(np.diff(excess[1:]) < 0) and excess[-1] < 0.005


@pytest.fixture(scope="module")
def clamped_free():
    """R = 0.297 m, h = 6 mm, L = 1.4 m, clamped at z = 0: cubic, 24 around, 0.1 m axially."""
    R, h, L = 0.297, 0.006, 1.4
    mesh_data, V = tube(R, h, L, MeshOptions(n_circumferential=24, axial_size=0.1), degree=3)
    bc = clamp(V, mesh_data.facet_tags, [tags.BOTTOM])
    result = modal_analysis(V, STEEL, [bc], options=EigenOptions(n_modes=12))
    labels = [classify(u) for u in result.modes]
    return result.frequencies_hz, labels, (R, h, L)


@pytest.mark.parametrize("m", [2, 3, 4])
def test_clamped_free_lowest_frequency_per_m(clamped_free, m):
    freqs, labels, (R, h, L) = clamped_free
    fe = min(f for f, w in zip(freqs, labels) if w.m == m)
    ritz = cylinder_frequencies(R, h, L, STEEL, m)[0]
    print(
        f"clamped-free m = {m}: solid {fe:.3f} Hz, Sanders-Ritz {ritz:.3f} Hz, "
        f"rel. diff {fe / ritz - 1:+.2e}"
    )
    assert fe == pytest.approx(ritz, rel=0.03)


def test_clamped_free_every_mode_in_its_analytic_family(clamped_free):
    freqs, labels, (R, h, L) = clamped_free
    for f, w in zip(freqs, labels):
        family = cylinder_frequencies(R, h, L, STEEL, w.m)[w.n]
        assert f == pytest.approx(family, rel=0.03), f"{f:.2f} Hz labelled (m, n) = ({w.m}, {w.n})"
    # axisymmetric shells: modes m >= 1 come in degenerate pairs
    assert all(
        labels[i].m == labels[i + 1].m and labels[i].n == labels[i + 1].n for i in range(0, 12, 2)
    )


def test_clamped_clamped_benchmark():
    """R = 0.1 m, L = 0.4 m, t = 0.01 m: lowest mode (m, n) = (2, 0) at about 1701 Hz."""
    mesh_data, V = tube(
        0.1, 0.01, 0.4, MeshOptions(n_circumferential=24, axial_size=0.04), degree=3
    )
    bc = clamp(V, mesh_data.facet_tags, [tags.BOTTOM, tags.TOP])
    result = modal_analysis(V, BENCH, [bc], options=EigenOptions(n_modes=4))
    w = classify(result.modes[0])
    print(f"clamped-clamped: f1 = {result.frequencies_hz[0]:.1f} Hz, (m, n) = ({w.m}, {w.n})")
    assert (w.m, w.n) == (2, 0)
    assert result.frequencies_hz[0] == pytest.approx(1701.0, rel=0.02)
