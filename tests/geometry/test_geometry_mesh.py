"""Hexahedral meshes of MP and TP in DOLFINx: volumes, areas, tags, placement.

Runs serially and under ``mpiexec -n 2`` (all quantities are reduced over ranks).
"""

import math
from pathlib import Path

import numpy as np
import pytest
import ufl
from mpi4py import MPI

import dolfinx
from geometry import tags
from geometry.contact_map import tp_placement
from geometry.imperfections import ovality
from geometry.mesh import create_joint_mesh, create_tube_mesh, write_paraview
from geometry.parameters import ConePart, JointGeometry, MeshOptions, load_geometry

pytestmark = pytest.mark.mpi

CASES = Path(__file__).resolve().parents[2] / "cases"
COMM = MPI.COMM_WORLD


@pytest.fixture(scope="module")
def scaled() -> JointGeometry:
    return load_geometry(CASES / "scaled.toml")[0]


def integrate(mesh_data, measure: str, tag: int) -> float:
    mesh = mesh_data.mesh
    data = mesh_data.cell_tags if measure == "dx" else mesh_data.facet_tags
    m = ufl.Measure(measure, domain=mesh, subdomain_data=data)
    one = dolfinx.fem.Constant(mesh, 1.0)
    return COMM.allreduce(dolfinx.fem.assemble_scalar(dolfinx.fem.form(one * m(tag))))


def owned_count(mesh_data, dim: int, tag: int) -> int:
    """Number of entities with ``tag`` owned by this rank, summed over ranks."""
    meshtags = mesh_data.cell_tags if dim == 3 else mesh_data.facet_tags
    n_owned = mesh_data.mesh.topology.index_map(dim).size_local
    return COMM.allreduce(int(np.sum(meshtags.find(tag) < n_owned)))


def structured_counts(joint: JointGeometry, o: MeshOptions) -> dict[int, int]:
    """Expected global entity counts of the structured meshes."""

    def n_along(part: ConePart) -> int:
        h = part.profile_heights()
        return sum(o.n_axial(b - a) for a, b in zip(h[:-1], h[1:]))

    ring = o.n_circumferential * o.n_layers
    return {
        tags.MP_VOLUME: ring * n_along(joint.mp),
        tags.TP_VOLUME: ring * n_along(joint.tp),
        tags.MP_CLAMPED: ring,
        tags.TP_TOP: ring,
        tags.MP_CONTACT: o.n_circumferential * o.n_axial(joint.mp.cone_length),
        tags.TP_CONTACT: o.n_circumferential * o.n_axial(joint.tp.cone_length),
    }


@pytest.mark.parametrize("n_layers", [1, 2])
@pytest.mark.parametrize("axial_size", [0.08, 0.04])
@pytest.mark.parametrize("n_circ", [24, 48])
def test_volumes_areas_and_tags(scaled, n_circ, axial_size, n_layers):
    """Volumes and contact areas within 0.5 % of exact; every tag complete over ranks."""
    options = MeshOptions(n_circumferential=n_circ, axial_size=axial_size, n_layers=n_layers)
    md = create_joint_mesh(COMM, scaled, options)
    assert md.mesh.topology.cell_type == dolfinx.mesh.CellType.hexahedron
    assert md.mesh.geometry.cmaps[0].degree == 2
    for tag, part in ((tags.MP_VOLUME, scaled.mp), (tags.TP_VOLUME, scaled.tp)):
        assert integrate(md, "dx", tag) == pytest.approx(part.volume, rel=5e-3)
    assert integrate(md, "ds", tags.MP_CONTACT) == pytest.approx(
        scaled.mp.outer_cone_area, rel=5e-3
    )
    assert integrate(md, "ds", tags.TP_CONTACT) == pytest.approx(
        scaled.tp.inner_cone_area, rel=5e-3
    )
    expected = structured_counts(scaled, options)
    for tag, count in expected.items():
        assert (
            owned_count(md, 3 if tag in (tags.MP_VOLUME, tags.TP_VOLUME) else 2, tag) == count > 0
        )
    # conforming closed walls: the only exterior facets are two annuli and two walls per part
    md.mesh.topology.create_connectivity(2, 3)
    exterior = dolfinx.mesh.exterior_facet_indices(md.mesh.topology)
    n_ext = COMM.allreduce(int(np.sum(exterior < md.mesh.topology.index_map(2).size_local)))
    lateral = 2 * (expected[tags.MP_VOLUME] + expected[tags.TP_VOLUME]) // n_layers
    assert n_ext == lateral + 4 * n_circ * n_layers


def test_curved_geometry_is_not_faceted(scaled):
    """Order 1 (straight edges) gives exactly the polygon's area, 24 around: -0.29 %;
    order 2 places the mid-edge nodes on the circles, error below 1e-5."""
    ratios = []
    for order in (1, 2):
        md = create_joint_mesh(
            COMM, scaled, MeshOptions(n_circumferential=24, geometry_order=order)
        )
        ratios.append(integrate(md, "ds", tags.MP_CONTACT) / scaled.mp.outer_cone_area)
    mp, n = scaled.mp, 24
    r1, r2 = mp.cone_bottom_outer_radius, mp.cone_top_outer_radius
    # n planar trapezoids: chords 2 r sin(pi/n), height between chord midpoints
    height = math.hypot(mp.cone_length, (r1 - r2) * math.cos(math.pi / n))
    polygon = n * math.sin(math.pi / n) * (r1 + r2) * height / mp.outer_cone_area
    assert ratios[0] == pytest.approx(polygon, rel=1e-9)
    assert abs(ratios[1] - 1) < 1e-5 < abs(polygon - 1)


def surface_nodes(md, tag: int) -> np.ndarray:
    """Coordinates of the geometry nodes of the facets tagged ``tag``, gathered on all ranks."""
    mesh = md.mesh
    facets = md.facet_tags.find(tag)
    nodes = dolfinx.mesh.entities_to_geometry(mesh, 2, facets)
    x = mesh.geometry.x[np.unique(nodes)]
    return np.unique(np.round(np.concatenate(COMM.allgather(x)), 12), axis=0)


def rigid_contact_on_mesh(
    md, n_circumferential: int
) -> tuple[float, float, np.ndarray, np.ndarray]:
    """Lower the meshed TP rigidly until a TP contact node touches the meshed MP surface.

    The MP surface along each generator is interpolated linearly in z between its nodes
    (exact for a cone). Returns (TP lower-edge z, measured first-contact z of that edge,
    gaps at placement, TP node heights)."""
    mp, tp = surface_nodes(md, tags.MP_CONTACT), surface_nodes(md, tags.TP_CONTACT)
    n_angles = 2 * n_circumferential  # vertices and mid-edge nodes (order 2)

    def angle_index(x):
        return (
            np.round(np.arctan2(x[:, 1], x[:, 0]) * n_angles / (2 * np.pi)).astype(int) % n_angles
        )

    mp_key, tp_key = angle_index(mp), angle_index(tp)
    assert set(tp_key) == set(mp_key) == set(range(n_angles))

    def gaps(shift: float) -> np.ndarray:
        """Radial gap of every TP contact node to the MP surface along the same generator
        (+inf where the node, lowered by ``shift``, is above or below the MP cone)."""
        g = np.full(len(tp), np.inf)
        z = tp[:, 2] - shift
        for k in range(n_angles):
            m = mp[mp_key == k]
            t = (tp_key == k) & (z >= m[:, 2].min()) & (z <= m[:, 2].max())
            order = np.argsort(m[:, 2])
            r_mp = np.interp(z[t], m[order, 2], np.hypot(m[order, 0], m[order, 1]))
            g[t] = np.hypot(tp[t, 0], tp[t, 1]) - r_mp
        return g

    lo, hi = -0.05, 0.05  # shift down (positive) closes the gap
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if gaps(mid).min() > 0 else (lo, mid)
    z_edge = tp[:, 2].min()
    return z_edge, z_edge - 0.5 * (lo + hi), gaps(0.0), tp[:, 2]


def test_first_contact_height_measured_on_mesh(scaled):
    """Rigidly lowering the meshed TP until its contact nodes touch the meshed MP surface
    gives the closed-form first-contact height within 0.1 mm; at placement the gap is ~0
    at the lower edge and positive above it."""
    md = create_joint_mesh(COMM, scaled, MeshOptions(n_circumferential=24, axial_size=0.04))
    z_edge, measured, g0, z = rigid_contact_on_mesh(md, 24)
    assert abs(g0.min()) < 1e-9
    assert np.all(g0[z > z_edge + 1e-6] > 0)
    assert measured == pytest.approx(scaled.first_contact_height, abs=1e-4)
    assert z_edge == pytest.approx(scaled.first_contact_height, abs=1e-12)


def test_tp_ovality_on_mesh(scaled):
    """An m = 2 TP ovality of amplitude A applied to the mesh nodes (whole wall, thickness
    kept) raises the first contact by A / tan(alpha) (closed form) within 1 %."""
    amplitude = 0.5e-3
    imperfections = {"tp": ovality(amplitude)}
    md = create_joint_mesh(
        COMM, scaled, MeshOptions(n_circumferential=24, axial_size=0.04), imperfections
    )
    # every TP node moved radially by A cos(2 theta); MP nodes untouched
    tp_z = tp_placement(scaled, imperfections)
    for tag, part, z0, amp in (
        (tags.TP_VOLUME, scaled.tp, tp_z, amplitude),
        (tags.MP_VOLUME, scaled.mp, 0.0, 0.0),
    ):
        nodes = np.unique(dolfinx.mesh.entities_to_geometry(md.mesh, 3, md.cell_tags.find(tag)))
        x = md.mesh.geometry.x[nodes]
        r, theta = np.hypot(x[:, 0], x[:, 1]), np.arctan2(x[:, 1], x[:, 0])
        # depth in the wall after removing the deviation: inner, mid-wall or outer node (hex27)
        depth = (r - amp * np.cos(2 * theta) - part.inner_radius(x[:, 2] - z0)) / part.thickness
        off = np.min(np.abs(depth[:, None] - np.array([0.0, 0.5, 1.0])), axis=1)
        assert COMM.allreduce(float(off.max(initial=0.0)), op=MPI.MAX) < 1e-6
    z_edge, measured, g0, _ = rigid_contact_on_mesh(md, 24)
    shift = amplitude / math.tan(scaled.mp.half_angle)
    assert measured - scaled.first_contact_height == pytest.approx(shift, rel=0.01)
    # the TP is placed at its (imperfect) first contact: touching, not penetrating
    assert z_edge == pytest.approx(measured, abs=1e-6)
    assert abs(g0.min()) < 1e-7


def test_tube_mesh():
    """Clamped-free cylinder for the modal analysis: mid-surface radius 0.297 m, h = 6 mm."""
    part = ConePart(0.0, 0.600, 1.4, 0.0, 0.006)
    options = MeshOptions(n_circumferential=24, axial_size=0.1, n_layers=2)
    md = create_tube_mesh(COMM, part, options)
    assert integrate(md, "dx", tags.VOLUME) == pytest.approx(part.volume, rel=1e-4)
    annulus = math.pi * (0.3**2 - 0.294**2)
    assert integrate(md, "ds", tags.BOTTOM) == pytest.approx(annulus, rel=1e-4)
    assert integrate(md, "ds", tags.TOP) == pytest.approx(annulus, rel=1e-4)
    assert integrate(md, "ds", tags.OUTER) == pytest.approx(2 * math.pi * 0.3 * 1.4, rel=1e-4)
    assert integrate(md, "ds", tags.INNER) == pytest.approx(2 * math.pi * 0.294 * 1.4, rel=1e-4)
    assert owned_count(md, 3, tags.VOLUME) == 24 * 14 * 2


@pytest.mark.parametrize("n_layers", [1, 2, 3])
def test_nodes_on_exact_circles(n_layers):
    """Every geometry node of a perfect tube (also inside the wall) lies on one of the
    exact radii of the layer interfaces or their midpoints (hex27: no chord nodes)."""
    part = ConePart(0.0, 0.600, 0.4, 0.0, 0.006)
    md = create_tube_mesh(
        COMM, part, MeshOptions(n_circumferential=24, axial_size=0.1, n_layers=n_layers)
    )
    r = np.hypot(*md.mesh.geometry.x[:, :2].T)
    exact = 0.294 + 0.006 * np.arange(2 * n_layers + 1) / (2 * n_layers)
    distance = np.abs(r[:, None] - exact[None, :]).min(axis=1)
    assert COMM.allreduce(float(distance.max(initial=0.0)), op=MPI.MAX) < 1e-12


def test_paraview_export(scaled, shared_tmp):
    out = shared_tmp
    md = create_joint_mesh(COMM, scaled, MeshOptions(n_circumferential=24))
    path = write_paraview(md, out / "joint")
    COMM.barrier()
    assert path.exists() and path.with_suffix(".h5").exists()
    with dolfinx.io.XDMFFile(COMM, path, "r") as xdmf:
        mesh = xdmf.read_mesh(name="slipjoint")
        cell_tags = xdmf.read_meshtags(mesh, name="cell_tags")
    n_owned = mesh.topology.index_map(3).size_local
    counts = [COMM.allreduce(int(np.sum(cell_tags.find(t) < n_owned))) for t in (1, 2)]
    assert counts == [owned_count(md, 3, 1), owned_count(md, 3, 2)]


def test_bad_imperfection_key(scaled):
    with pytest.raises(ValueError, match="imperfections keys"):
        create_joint_mesh(COMM, scaled, MeshOptions(), imperfections={"TP": lambda t, z: 0 * t})


def test_full_scale_mesh():
    """The 6 m joint meshes too: volumes, contact areas and placement (coarse mesh)."""
    joint = load_geometry(CASES / "full_scale.toml")[0]
    options = MeshOptions(n_circumferential=24, axial_size=1.5)
    md = create_joint_mesh(COMM, joint, options)
    for tag, part in ((tags.MP_VOLUME, joint.mp), (tags.TP_VOLUME, joint.tp)):
        assert integrate(md, "dx", tag) == pytest.approx(part.volume, rel=5e-3)
    assert integrate(md, "ds", tags.TP_CONTACT) == pytest.approx(joint.tp.inner_cone_area, rel=5e-3)
    z_tp = surface_nodes(md, tags.TP_CONTACT)[:, 2].min()  # gathered over ranks
    assert z_tp == pytest.approx(joint.first_contact_height, abs=1e-9)
    for tag, count in structured_counts(joint, options).items():
        assert owned_count(md, 3 if tag in (tags.MP_VOLUME, tags.TP_VOLUME) else 2, tag) == count


def test_contact_zone_refinement(scaled):
    """contact_axial_size: the cone walls within the zone around the TP's lower edge get
    elements of at most that axial size (both parts) and are the contact surfaces; the walls
    outside keep axial_size. The generators are straight, so the volumes equal the unrefined
    mesh's (to the quadrature error of the curved cells, 4e-8) and the contact areas the exact
    frustum areas of the zone (curved cells, 8 around)."""
    size, below, above = 0.01, 0.03, 0.15
    options = MeshOptions(
        n_circumferential=8,
        axial_size=0.25,
        contact_axial_size=size,
        contact_zone_below=below,
        contact_zone_above=above,
    )
    md = create_joint_mesh(COMM, scaled, options)
    coarse = create_joint_mesh(COMM, scaled, MeshOptions(n_circumferential=8, axial_size=0.25))
    for tag in (tags.MP_VOLUME, tags.TP_VOLUME):
        assert integrate(md, "dx", tag) == pytest.approx(integrate(coarse, "dx", tag), rel=1e-6)
    z_edge = scaled.tp_offset

    def frustum(r1: float, r2: float, length: float) -> float:
        return math.pi * (r1 + r2) * math.hypot(length, r2 - r1)

    mp, tp = scaled.mp, scaled.tp
    areas = {
        tags.MP_CONTACT: frustum(
            mp.outer_radius(z_edge - below), mp.outer_radius(z_edge + above), below + above
        ),
        tags.TP_CONTACT: frustum(tp.inner_radius(0.0), tp.inner_radius(above), above),
    }
    for tag, area in areas.items():
        assert integrate(md, "ds", tag) == pytest.approx(area, rel=1e-3)
    mesh = md.mesh

    def extents(dim: int, entities):
        """Axial height and mid-height of owned entities [m] (their corner nodes)."""
        entities = entities[entities < mesh.topology.index_map(dim).size_local]
        z = mesh.geometry.x[dolfinx.mesh.entities_to_geometry(mesh, dim, entities)[:, : 2**dim]][
            :, :, 2
        ]
        return z.max(axis=1) - z.min(axis=1), 0.5 * (z.max(axis=1) + z.min(axis=1))

    for tag, low in ((tags.MP_CONTACT, z_edge - below), (tags.TP_CONTACT, z_edge)):
        height, mid = extents(2, md.facet_tags.find(tag))
        assert np.all((mid > low) & (mid < z_edge + above))
        assert np.all(height <= size * (1 + 1e-9))
        assert COMM.allreduce(len(mid)) == 8 * round((z_edge + above - low) / size)
    height, mid = extents(3, md.cell_tags.find(tags.TP_VOLUME))
    assert np.all(height[mid > z_edge + above] > size)
    assert owned_count(md, 3, tags.TP_VOLUME) > owned_count(coarse, 3, tags.TP_VOLUME) + 8 * 10


def test_contact_zone_options_are_checked():
    with pytest.raises(ValueError, match="contact_axial_size"):
        MeshOptions(contact_axial_size=-0.01)
    with pytest.raises(ValueError, match="contact zone"):
        MeshOptions(contact_axial_size=0.01, contact_zone_above=0.0)


@pytest.mark.parametrize("partition", ["sectors", "graph"])
def test_partition(scaled, partition):
    """Both partitions give the same mesh (cell and contact facet counts, volumes). With
    "sectors", each rank owns the cells of its angular sector (centres within
    [2 pi r / p - pi, 2 pi (r + 1) / p - pi]), so every rank holds a share of both contact
    surfaces of 1/p of the whole (+-1 layer of elements); serially nothing changes."""
    options = MeshOptions(
        n_circumferential=8, axial_size=0.25, contact_axial_size=0.02, partition=partition
    )
    md = create_joint_mesh(COMM, scaled, options)
    expected = structured_counts(scaled, MeshOptions(n_circumferential=8, axial_size=0.25))
    assert owned_count(md, 3, tags.TP_VOLUME) + owned_count(md, 3, tags.MP_VOLUME) > 0
    reference = create_joint_mesh(
        COMM,
        scaled,
        MeshOptions(
            n_circumferential=8, axial_size=0.25, contact_axial_size=0.02, partition="graph"
        ),
    )
    for dim, tag in (
        (3, tags.TP_VOLUME),
        (3, tags.MP_VOLUME),
        (2, tags.TP_CONTACT),
        (2, tags.MP_CONTACT),
    ):
        assert owned_count(md, dim, tag) == owned_count(reference, dim, tag)
    assert integrate(md, "dx", tags.TP_VOLUME) == pytest.approx(
        integrate(reference, "dx", tags.TP_VOLUME), rel=1e-12
    )
    assert owned_count(md, 2, tags.MP_CLAMPED) == expected[tags.MP_CLAMPED]
    if partition != "sectors":
        return
    mesh = md.mesh
    n_owned = mesh.topology.index_map(3).size_local
    centres = dolfinx.mesh.compute_midpoints(mesh, 3, np.arange(n_owned, dtype=np.int32))
    angle = np.arctan2(centres[:, 1], centres[:, 0]) + np.pi
    sector = 2 * np.pi / COMM.size
    assert np.all((angle >= COMM.rank * sector - 1e-9) & (angle <= (COMM.rank + 1) * sector + 1e-9))
    for dim, tag in ((2, tags.TP_CONTACT), (2, tags.MP_CONTACT)):
        meshtags = md.facet_tags
        mine = int(np.sum(meshtags.find(tag) < mesh.topology.index_map(dim).size_local))
        total = COMM.allreduce(mine)
        assert abs(mine - total / COMM.size) <= total / options.n_circumferential


def test_partition_option_is_checked():
    with pytest.raises(ValueError, match="partition"):
        MeshOptions(partition="metis")
