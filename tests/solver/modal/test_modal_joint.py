"""Coupling through the contact interface, and the joint's modal outputs."""

import csv

import gmsh
import numpy as np
import pytest
from mpi4py import MPI

import dolfinx.io.gmsh
from dolfinx import fem, mesh

from common.case import read_case
from common.material import Material
from geometry import tags
from solver.contact import Status
from solver.modal.eigen import EigenOptions, clamp, modal_analysis
from solver.modal.interface import ContactInterface, bonded_band
from solver.modal.joint import JointCase, joint_modes
from solver.modal.outputs import format_table, write_outputs
from solver.modal.ranking import JointParts, describe_modes

pytestmark = pytest.mark.mpi

STEEL = Material(E=210e9, nu=0.3, rho=7850.0)
A, H = 0.05, 0.5  # column width and height of each of the two blocks [m]


def stacked_columns(comm: MPI.Comm) -> dolfinx.io.gmsh.MeshData:
    """Two disjoint square columns on top of each other, non-matching at z = H
    (2 x 2 elements below, 3 x 3 above), tagged like the joint: lower = MP, upper = TP."""
    if comm.rank == 0:
        gmsh.initialize()
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.option.setNumber("Geometry.AutoCoherence", 0)  # keep the coincident faces apart
        gmsh.model.add("stack")
        geo = gmsh.model.geo
        bodies = []
        for z0, n in ((0.0, 2), (H, 3)):
            pts = [geo.addPoint(x, y, z0) for x, y in ((0, 0), (A, 0), (A, A), (0, A))]
            lines = [geo.addLine(pts[k], pts[(k + 1) % 4]) for k in range(4)]
            for line in lines:
                geo.mesh.setTransfiniteCurve(line, n + 1)
            base = geo.addPlaneSurface([geo.addCurveLoop(lines)])
            geo.mesh.setTransfiniteSurface(base)
            geo.mesh.setRecombine(2, base)
            top, vol = geo.extrude([(2, base)], 0, 0, H, numElements=[10], recombine=True)[:2]
            bodies.append((base, top[1], vol[1]))
        geo.synchronize()
        (mp_base, mp_top, mp_vol), (tp_base, tp_top, tp_vol) = bodies
        gmsh.model.addPhysicalGroup(3, [mp_vol], tags.MP_VOLUME)
        gmsh.model.addPhysicalGroup(3, [tp_vol], tags.TP_VOLUME)
        for tag, surface in (
            (tags.MP_CLAMPED, mp_base),
            (tags.MP_CONTACT, mp_top),
            (tags.TP_CONTACT, tp_base),
            (tags.TP_TOP, tp_top),
        ):
            gmsh.model.addPhysicalGroup(2, [surface], tag)
        gmsh.model.mesh.generate(3)
    mesh_data = dolfinx.io.gmsh.model_to_mesh(gmsh.model, comm, 0, gdim=3)
    if comm.rank == 0:
        gmsh.finalize()
    return mesh_data


@pytest.fixture(scope="module")
def stack():
    mesh_data = stacked_columns(MPI.COMM_WORLD)
    V = fem.functionspace(mesh_data.mesh, ("Lagrange", 2, (3,)))
    return mesh_data, V, clamp(V, mesh_data.facet_tags, [tags.MP_CLAMPED])


def test_bonded_interface_recovers_the_monolithic_column(stack):
    """Tied non-matching blocks vibrate like one cantilever of length 2H."""
    mesh_data, V, bc = stack
    tie = bonded_band(V, mesh_data.facet_tags, STEEL, height=1e-3)
    assert tie.tied_fraction() == 1.0  # a flat interface lies entirely in the band
    tied = modal_analysis(V, STEEL, [bc], [tie], EigenOptions(n_modes=4)).frequencies_hz

    box = mesh.create_box(
        MPI.COMM_WORLD, [[0, 0, 0], [A, A, 2 * H]], [3, 3, 20], mesh.CellType.hexahedron
    )
    W = fem.functionspace(box, ("Lagrange", 2, (3,)))
    base = mesh.locate_entities_boundary(box, 2, lambda x: np.isclose(x[2], 0.0))
    bc_box = fem.dirichletbc(np.zeros(3), fem.locate_dofs_topological(W, 2, base), W)
    single = modal_analysis(W, STEEL, [bc_box], options=EigenOptions(n_modes=4)).frequencies_hz

    f_eb = (
        1.8751040687119611**2
        / (2 * np.pi)
        * np.sqrt(STEEL.E * A**2 / 12 / (STEEL.rho * (2 * H) ** 4))
    )
    print(f"tied {tied[0]:.3f} Hz, monolithic {single[0]:.3f} Hz, Euler-Bernoulli {f_eb:.3f} Hz")
    np.testing.assert_allclose(tied, single, rtol=5e-3)
    assert tied[0] == pytest.approx(f_eb, rel=0.01)


def test_interface_states_order_the_frequencies(stack):
    """Open < slipping (normal tie only) < stuck: the tangent stiffens monotonically, and
    the open interface leaves the lower block alone (a cantilever of length H)."""
    mesh_data, V, bc = stack
    contact = bonded_band(V, mesh_data.facet_tags, STEEL, height=1e-3).contact
    freqs = {}
    for status in (Status.OPEN, Status.SLIP, Status.STICK):
        interface = ContactInterface(contact, status)
        freqs[status] = modal_analysis(
            V, STEEL, [bc], [interface], EigenOptions(n_modes=6)
        ).frequencies_hz
    # open: the upper block floats free (6 rigid modes near 0 Hz)
    assert np.all(freqs[Status.OPEN] < 1.0)
    assert np.all(freqs[Status.SLIP][:2] <= freqs[Status.STICK][:2] * (1 + 1e-10))
    K_stick = contact.interface_stiffness(Status.STICK)
    K_t = K_stick.copy()
    K_t.transpose()
    K_t.axpy(-1.0, K_stick)
    assert K_t.norm() <= 1e-10 * K_stick.norm()


def test_nitsche_parameter_barely_matters(stack):
    mesh_data, V, bc = stack
    f = [
        modal_analysis(
            V,
            STEEL,
            [bc],
            [bonded_band(V, mesh_data.facet_tags, STEEL, 1e-3, gamma0=g)],
            EigenOptions(n_modes=4),
        ).frequencies_hz
        for g in (100.0, 1000.0)
    ]
    np.testing.assert_allclose(f[0], f[1], rtol=2e-3)


@pytest.fixture(scope="module")
def quick_joint():
    case = JointCase.from_dict(read_case("modal_quick", ["modal.n_modes=6"]))
    return case, joint_modes(MPI.COMM_WORLD, case)


def test_joint_partition_independent(quick_joint):
    case, modes = quick_joint
    serial = joint_modes(MPI.COMM_SELF, case).result.frequencies_hz
    np.testing.assert_allclose(modes.result.frequencies_hz, serial, rtol=1e-8)


def test_joint_outputs(quick_joint, shared_tmp):
    case, modes = quick_joint
    comm = MPI.COMM_WORLD
    folder = shared_tmp
    parts = JointParts.for_joint(modes.result.V, modes.mesh_data, case.joint)
    records = describe_modes(modes.result, case.material, parts)
    table = format_table(records)
    paths = write_outputs(modes.result, records, folder)
    comm.barrier()
    assert paths["png"].stat().st_size > 10_000
    assert (paths["vtx"]).is_dir()
    with open(paths["csv"]) as f:
        rows = list(csv.DictReader(f))
    assert (
        len(rows) == len(records) == 6
        and "frequency_Hz" in rows[0]
        and "resonant_slip_axial_um" in rows[0]
    )
    assert len(table.splitlines()) == 7
    # axisymmetric joint: the first modes come in degenerate pairs with equal labels and rank
    for a, b in zip(records[0::2], records[1::2]):
        assert (a.m, a.n, a.rank) == (b.m, b.n, b.rank)
        assert a.frequency_Hz == pytest.approx(b.frequency_Hz, rel=1e-6)
    # a uniform top-face force cannot excite m >= 2 of a perfect axisymmetric joint
    for r in records:
        if r.m >= 2:
            assert (
                r.participation_axial_face_per_sqrtkg
                < 1e-6 * r.participation_axial_point_per_sqrtkg + 1e-12
            )


@pytest.mark.parametrize(
    "override",
    [
        "modal.band_height=-0.05",
        "modal.clamped=['MP_TOP']",
        "modal.n_modes=0",
        "modal.zeta=2.0",
        "modal.frequency=3",
        "modal.target_hz=-5.0",
    ],
)
def test_bad_modal_settings_raise_before_computing(override):
    with pytest.raises(ValueError, match="modal"):
        JointCase.from_dict(read_case("scaled", [override]))


def test_clamping_a_missing_tag_raises(stack):
    mesh_data, V, _ = stack
    with pytest.raises(ValueError, match="99"):
        clamp(V, mesh_data.facet_tags, [99])
