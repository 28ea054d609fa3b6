"""Structured hexahedral gmsh meshes of the MP and TP walls, brought into DOLFINx.

Each part's (r, z) wall profile -- one quadrilateral per axial segment (straight
part, cone) -- is meshed as a structured quad grid (``n_layers`` through the
wall, ``axial_size`` along the axis) and revolved about the z axis in four
quarter turns with ``n_circumferential / 4`` recombined layers each, giving
hexahedra through the wall. ``geometry_order = 2`` gives hex27 cells whose
high-order nodes lie on the exact circles. Tags: :mod:`geometry.tags`.

gmsh runs on rank 0 only; :func:`dolfinx.io.gmsh.model_to_mesh` distributes.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path

import gmsh
import numpy as np
from mpi4py import MPI

import dolfinx
import dolfinx.io.gmsh

from geometry import tags
from geometry.contact_map import tp_placement
from geometry.imperfections import RadialDeviation, check_imperfections
from geometry.parameters import ConePart, JointGeometry, MeshOptions

__all__ = [
    "MeshOptions",
    "RadialDeviation",
    "add_joint_to_gmsh",
    "add_tube_to_gmsh",
    "create_joint_mesh",
    "create_tube_mesh",
    "write_paraview",
]


@dataclass(frozen=True)
class _PartEntities:
    """gmsh entity tags of one revolved part, by role."""

    volumes: list[int]
    bottom: list[int]  #: annulus at the lower end
    top: list[int]  #: annulus at the upper end
    outer: list[int]  #: outer lateral surfaces, per segment (bottom to top), concatenated
    inner: list[int]
    outer_contact: list[int]  #: outer cone surface (inside the contact zone if there is one)
    inner_contact: list[int]


def _add_part(
    part: ConePart, z0: float, options: MeshOptions, zone: tuple[float, float] | None = None
) -> _PartEntities:
    """Add one part, lower end at global height ``z0`` [m], to the current gmsh model (geo).

    Each wall layer is its own profile surface, so every node of the mesh lies on a
    geometric surface of revolution and second-order nodes land on exact circles
    also inside the wall (a single surface split into layers would leave the
    interior mid-edge nodes on chords). ``zone`` = (z_low, z_high) [m, global]: the
    part of the cone inside is meshed with ``options.contact_axial_size`` and is the
    contact surface (``outer_contact``, ``inner_contact``); without a zone, the whole cone.
    """
    geo = gmsh.model.geo
    heights = list(part.profile_heights())
    if zone is not None:
        for z in zone:
            h = z - z0
            if part.cone_bottom_z < h < part.cone_top_z and min(abs(h - x) for x in heights) > 1e-9:
                heights.append(h)
        heights.sort()
    n_layers = options.n_layers
    # points[j][h]: layer interface j (0 = inner surface, n_layers = outer) at height h
    points = [
        [
            geo.addPoint(float(part.inner_radius(h)) + j * part.thickness / n_layers, 0.0, z0 + h)
            for h in heights
        ]
        for j in range(n_layers + 1)
    ]
    radial = [
        [geo.addLine(points[j][k], points[j + 1][k]) for k in range(len(heights))]
        for j in range(n_layers)
    ]
    for line in (line for layer in radial for line in layer):
        geo.mesh.setTransfiniteCurve(line, 2)

    profile, is_contact, layer_of = [], [], []
    for k in range(len(heights) - 1):
        mid = 0.5 * (heights[k] + heights[k + 1])
        in_zone = (
            zone is not None
            and zone[0] <= z0 + mid <= zone[1]
            and part.cone_bottom_z <= mid <= part.cone_top_z
        )
        n = options.n_axial(heights[k + 1] - heights[k], in_zone) + 1
        axial = [geo.addLine(points[j][k], points[j][k + 1]) for j in range(n_layers + 1)]
        for line in axial:
            geo.mesh.setTransfiniteCurve(line, n)
        for j in range(n_layers):
            loop = geo.addCurveLoop([radial[j][k], axial[j + 1], -radial[j][k + 1], -axial[j]])
            surface = geo.addPlaneSurface([loop])
            geo.mesh.setTransfiniteSurface(surface)
            geo.mesh.setRecombine(2, surface)
            profile.append(surface)
            is_contact.append(
                in_zone if zone is not None else part.cone_bottom_z <= mid <= part.cone_top_z
            )
            layer_of.append((j, k))

    entities = _PartEntities([], [], [], [], [], [], [])
    sources = [(2, s) for s in profile]
    last_segment = len(heights) - 2
    for _ in range(4):
        out = geo.revolve(
            sources,
            0,
            0,
            0,
            0,
            0,
            1,
            math.pi / 2,
            numElements=[options.n_circumferential // 4],
            recombine=True,
        )
        # per source surface: [end surface, volume, laterals of radial_k, outer, radial_k+1, inner]
        sources = []
        for i, (j, k) in enumerate(layer_of):
            end, vol, lat_bottom, lat_outer, lat_top, lat_inner = out[6 * i : 6 * i + 6]
            sources.append(end)
            entities.volumes.append(vol[1])
            if j == n_layers - 1:
                entities.outer.append(lat_outer[1])
                if is_contact[i]:
                    entities.outer_contact.append(lat_outer[1])
            if j == 0:
                entities.inner.append(lat_inner[1])
                if is_contact[i]:
                    entities.inner_contact.append(lat_inner[1])
            if k == 0:
                entities.bottom.append(lat_bottom[1])
            if k == last_segment:
                entities.top.append(lat_top[1])
    return entities


def _close_revolutions() -> None:
    """Merge each part's last quarter with its first (coincident profile entities)."""
    gmsh.model.geo.removeAllDuplicates()
    gmsh.model.geo.synchronize()


def _apply_deviation(volumes: list[int], z0: float, deviation: RadialDeviation) -> None:
    """Move every node of the part's volumes radially by ``deviation(theta, z - z0)``."""
    node_tags, coords = [], []
    for v in volumes:
        t, x, _ = gmsh.model.mesh.getNodes(3, v, includeBoundary=True)
        node_tags.append(t)
        coords.append(np.reshape(x, (-1, 3)))
    node_tags_all, first = np.unique(np.concatenate(node_tags), return_index=True)
    x = np.concatenate(coords)[first]
    r = np.hypot(x[:, 0], x[:, 1])
    theta = np.arctan2(x[:, 1], x[:, 0])
    dr = np.asarray(deviation(theta, x[:, 2] - z0), dtype=np.float64)
    scale = (r + dr) / r
    x[:, 0] *= scale
    x[:, 1] *= scale
    for tag, xi in zip(node_tags_all, x):
        gmsh.model.mesh.setNode(int(tag), xi.tolist(), [])


def _generate(options: MeshOptions) -> None:
    gmsh.option.setNumber("Mesh.SecondOrderIncomplete", 0)
    gmsh.model.mesh.generate(3)
    if options.geometry_order > 1:
        gmsh.model.mesh.setOrder(options.geometry_order)


def add_joint_to_gmsh(
    joint: JointGeometry,
    options: MeshOptions,
    imperfections: Mapping[str, RadialDeviation] | None = None,
    tp_z: float | None = None,
) -> None:
    """Populate the current gmsh model with the meshed MP and TP (TP at first contact).

    ``imperfections`` maps ``"mp"`` and/or ``"tp"`` to a radial deviation
    ``f(theta [rad], part-local z [m]) -> dr [m]`` applied to all nodes of that
    part (the whole wall moves, the thickness is kept). The TP's lower end is put
    at ``tp_z`` [m], by default at the first contact of the (imperfect) surfaces,
    :func:`geometry.contact_map.tp_placement` (``joint.tp_offset`` if perfect).
    """
    imperfections = check_imperfections(imperfections)
    if tp_z is None:
        tp_z = tp_placement(joint, imperfections)
    zone = None
    if options.contact_axial_size > 0:
        zone = (tp_z - options.contact_zone_below, tp_z + options.contact_zone_above)
    mp = _add_part(joint.mp, 0.0, options, zone)
    tp = _add_part(joint.tp, tp_z, options, zone)
    _close_revolutions()
    groups = {
        tags.MP_VOLUME: (3, mp.volumes),
        tags.TP_VOLUME: (3, tp.volumes),
        tags.MP_CLAMPED: (2, mp.bottom),
        tags.TP_TOP: (2, tp.top),
        tags.MP_CONTACT: (2, mp.outer_contact),
        tags.TP_CONTACT: (2, tp.inner_contact),
    }
    for tag, (dim, entities) in groups.items():
        gmsh.model.addPhysicalGroup(dim, entities, tag, name=tags.JOINT_NAMES[tag])
    _generate(options)
    for name, part, z0 in (("mp", mp, 0.0), ("tp", tp, tp_z)):
        if name in imperfections:
            _apply_deviation(part.volumes, z0, imperfections[name])


def add_tube_to_gmsh(part: ConePart, options: MeshOptions) -> None:
    """Populate the current gmsh model with one meshed part, lower end at z = 0."""
    entities = _add_part(part, 0.0, options)
    _close_revolutions()
    groups = {
        tags.VOLUME: (3, entities.volumes),
        tags.BOTTOM: (2, entities.bottom),
        tags.TOP: (2, entities.top),
        tags.OUTER: (2, entities.outer),
        tags.INNER: (2, entities.inner),
    }
    for tag, (dim, ents) in groups.items():
        gmsh.model.addPhysicalGroup(dim, ents, tag, name=tags.TUBE_NAMES[tag])
    _generate(options)


def sector_partitioner(x: np.ndarray | None) -> Callable:
    """DOLFINx cell partitioner: cell -> rank by equal angular sectors about the z axis.

    ``x`` (num_nodes, 3) [m] are the input node coordinates on the rank that holds the
    cells (None elsewhere); the partitioner receives each cell's vertices as indices into
    ``x``. Every rank gets a sector of both parts, so the contact surfaces (and their
    quadrature work) are shared, and the cuts are two planes through the axis per rank.
    Cells are not ghosted (as DOLFINx's default partitioner with GhostMode.none).
    """

    def partition(comm: MPI.Comm, n_parts: int, cell_types, topology):
        vertices = [
            np.asarray(t).reshape(-1, dolfinx.cpp.mesh.cell_num_vertices(c))
            for c, t in zip(cell_types, topology)
        ]
        destination = []
        for v in vertices:
            centre = x[v].mean(axis=1) if len(v) else np.zeros((0, 3))
            angle = np.arctan2(centre[:, 1], centre[:, 0]) + np.pi  # [0, 2 pi]
            destination.append(
                np.minimum((angle * n_parts / (2 * np.pi)).astype(np.int32), n_parts - 1)
            )
        return dolfinx.cpp.graph.AdjacencyList_int32(np.concatenate(destination).reshape(-1, 1))

    return partition


def _to_dolfinx(
    comm: MPI.Comm, build: Callable[[], None], name: str, options: MeshOptions
) -> dolfinx.io.gmsh.MeshData:
    """Run ``build`` on rank 0 in a fresh gmsh model and distribute the mesh (``options.partition``)."""
    partition = options.partition
    if partition == "sectors" and comm.size > options.n_circumferential // 2:
        raise ValueError(
            f"{comm.size} ranks for {options.n_circumferential} elements around: sectors would be "
            'less than 2 elements wide; use [mesh] partition = "graph"'
        )
    rank = 0
    started = False
    x = None
    if comm.rank == rank:
        if not gmsh.isInitialized():
            gmsh.initialize()
            started = True
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add(name)
        try:
            build()
        except Exception:
            gmsh.model.remove()
            if started:
                gmsh.finalize()
            raise
        if partition == "sectors":
            x = dolfinx.io.gmsh.extract_geometry(gmsh.model)
    partitioner = sector_partitioner(x) if partition == "sectors" and comm.size > 1 else None
    mesh_data = dolfinx.io.gmsh.model_to_mesh(
        gmsh.model, comm, rank, gdim=3, partitioner=partitioner
    )
    if comm.rank == rank:
        gmsh.model.remove()
        if started:
            gmsh.finalize()
    mesh_data.mesh.name = name
    return mesh_data


def create_joint_mesh(
    comm: MPI.Comm,
    joint: JointGeometry,
    options: MeshOptions,
    imperfections: Mapping[str, RadialDeviation] | None = None,
) -> dolfinx.io.gmsh.MeshData:
    """DOLFINx mesh of MP and TP with cell and facet tags; the TP's lower end is at
    :func:`geometry.contact_map.tp_placement` (``joint.tp_offset`` for perfect parts)."""
    tp_z = tp_placement(joint, imperfections)  # on every rank: errors before gmsh starts
    return _to_dolfinx(
        comm, lambda: add_joint_to_gmsh(joint, options, imperfections, tp_z), "slipjoint", options
    )


def create_tube_mesh(
    comm: MPI.Comm, part: ConePart, options: MeshOptions
) -> dolfinx.io.gmsh.MeshData:
    """DOLFINx mesh of one part alone (lower end at z = 0), tags as in :mod:`geometry.tags`."""
    return _to_dolfinx(comm, lambda: add_tube_to_gmsh(part, options), "tube", options)


def write_paraview(mesh_data: dolfinx.io.gmsh.MeshData, path: str | Path) -> Path:
    """Write mesh, cell tags and facet tags to an XDMF file for ParaView; returns its path."""
    path = Path(path).with_suffix(".xdmf")
    mesh = mesh_data.mesh
    mesh.topology.create_connectivity(mesh.topology.dim - 1, mesh.topology.dim)
    with dolfinx.io.XDMFFile(mesh.comm, path, "w") as xdmf:
        xdmf.write_mesh(mesh)
        mesh_data.cell_tags.name = "cell_tags"
        mesh_data.facet_tags.name = "facet_tags"
        xdmf.write_meshtags(mesh_data.cell_tags, mesh.geometry)
        xdmf.write_meshtags(mesh_data.facet_tags, mesh.geometry)
    return path
