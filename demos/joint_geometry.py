"""Geometry of the slip-joint: hexahedral mesh of MP and TP, summary and rigid contact map.

Builds the case's joint mesh (TP at first contact), prints the derived geometry
and mesh counts, and writes to --output: joint.xdmf/.h5 (mesh, cell and facet
tags, ParaView), contact_map.png (rigid overlay: onset map and contact fraction)
and contact_fraction.csv.

--quick is --case geometry_quick (24 around, 0.2 m along).

Usage: mpirun -n 2 python demos/joint_geometry.py [--case scaled] [--quick] [--output DIR]
       [--imperfection tp=scans.csv] [--tp-ovality-mm 0.5] [--set mesh.n_layers=2 ...]
"""

import sys

from common import backend  # noqa: F401  (before dolfinx)

import numpy as np
from mpi4py import MPI

import dolfinx
from common.material import Material
from geometry import tags
from geometry.contact_map import plot_contact_map, rigid_contact_map, tp_placement
from geometry.imperfections import ovality, read_imperfection
from geometry.mesh import create_joint_mesh, write_paraview
from geometry.parameters import JointGeometry, geometry_from_case
from solver.installation import cli

DEFAULT_CASE = "scaled"
QUICK_CASE = "geometry_quick"


def summary(joint: JointGeometry, material: Material) -> list[str]:
    """Derived geometry, in mm and kg."""
    lines = [
        f"{'':4}{'cone bottom/top outer D [mm]':>30}{'inner R bottom/top [mm]':>26}"
        f"{'length cone+straight [mm]':>28}{'mass [kg]':>11}"
    ]
    for name, p in (("MP", joint.mp), ("TP", joint.tp)):
        d_b, d_t = p.bottom_outer_diameter * 1e3, p.derived_top_outer_diameter * 1e3
        r_b, r_t = (float(p.inner_radius(z)) * 1e3 for z in (p.cone_bottom_z, p.cone_top_z))
        cone, straight = p.cone_length * 1e3, p.straight_length * 1e3
        lines.append(
            f"{name:4}{d_b:>19.2f} / {d_t:8.2f}{r_b:>15.2f} / {r_t:8.2f}"
            f"{cone:>17.1f} + {straight:7.1f}{p.mass(material):>11.1f}"
        )
    z_fc, overlap = joint.first_contact_height * 1e3, joint.overlap * 1e3
    slip, full = joint.required_slip * 1e3, joint.full_contact_overlap * 1e3
    lines += [
        f"first contact: TP lower edge at z = {z_fc:.2f} mm (MP bottom at 0), "
        f"overlap {overlap:.2f} mm",
        f"required slip to full contact (docs/physics.md §2.2): {slip:.2f} mm (overlap then {full:.2f} mm)",
    ]
    return lines


def main(argv: list[str] | None = None) -> int:
    parser = cli.case_parser(__doc__.splitlines()[0], "output/geometry", DEFAULT_CASE, QUICK_CASE)
    parser.add_argument(
        "--imperfection",
        action="append",
        default=[],
        metavar="PART=FILE",
        help="measured deviations of part mp or tp: processed map or raw ring scans (CSV)",
    )
    parser.add_argument(
        "--tp-ovality-mm",
        type=float,
        default=0.0,
        help="add a synthetic m = 2 ovality of this amplitude [mm] to the TP",
    )
    args = parser.parse_args(argv)
    comm = MPI.COMM_WORLD

    def log(message: str) -> None:
        if comm.rank == 0:
            print(message, flush=True)

    try:
        joint, material, options = geometry_from_case(cli.read(args))
        imperfections = {}
        for item in args.imperfection:
            name, sep, path = item.partition("=")
            if not sep or name not in ("mp", "tp"):
                raise ValueError(f"--imperfection {item!r}: expected mp=FILE or tp=FILE")
            imperfections[name] = read_imperfection(path, joint.mp if name == "mp" else joint.tp)
        if args.tp_ovality_mm:
            if "tp" in imperfections:
                raise ValueError("--tp-ovality-mm and --imperfection tp=... exclude each other")
            imperfections["tp"] = ovality(args.tp_ovality_mm * 1e-3)
        tp_placement(joint, imperfections)  # deviations the cones cannot hold: before any output
        out = cli.prepare_output(comm, args.output)
    except ValueError as e:
        return cli.fail(comm, str(e))

    log(
        f"slip-joint geometry of {cli.case_name(args)} ({comm.size} rank(s)); SI input, printed in mm / kg"
    )
    for line in summary(joint, material):
        log(line)

    mesh_data = create_joint_mesh(comm, joint, options, imperfections)
    mesh = mesh_data.mesh
    V = dolfinx.fem.functionspace(mesh, ("Lagrange", 2, (3,)))
    log(
        f"mesh: {options.n_circumferential} around, {options.axial_size * 1e3:.0f} mm along, "
        f"{options.n_layers} layer(s), geometry order {options.geometry_order} "
        f"(hex{(options.geometry_order + 1) ** 3})"
    )
    log(
        f"  cells {mesh.topology.index_map(3).size_global}, geometry nodes "
        f"{mesh.geometry.index_map().size_global}, P2 vector DOFs "
        f"{V.dofmap.index_map.size_global * V.dofmap.index_map_bs}"
    )
    n_facets = mesh.topology.index_map(2).size_local
    n_cells = mesh.topology.index_map(3).size_local
    for tag, name in tags.JOINT_NAMES.items():
        is_cell = tag in (tags.MP_VOLUME, tags.TP_VOLUME)
        meshtags, n_owned = (
            (mesh_data.cell_tags, n_cells) if is_cell else (mesh_data.facet_tags, n_facets)
        )
        count = comm.allreduce(int(np.sum(meshtags.find(tag) < n_owned)))
        log(f"  tag {tag:2d} {name:11s}: {count} {'cells' if is_cell else 'facets'}")

    log(f"  ParaView: {write_paraview(mesh_data, out / 'joint')}")

    if comm.rank == 0:  # rigid contact map: analytic surfaces, serial numpy
        cmap = rigid_contact_map(
            joint,
            imperfections,
            n_theta=180 if args.quick else 360,
            n_zeta=100 if args.quick else 400,
        )
        first, perfect = cmap.first_contact_overlap * 1e3, joint.overlap * 1e3
        print(
            f"rigid contact map: first contact at overlap {first:.2f} mm (perfect {perfect:.2f} mm)"
        )
        for target in (0.25, 0.5, 0.9):
            reached = cmap.overlaps[cmap.contact_fraction >= target]
            at = f"{reached[0] * 1e3:.1f} mm" if reached.size else "not within the sweep"
            print(f"  {target:.0%} of the TP contact surface in contact at overlap {at}")
        np.savetxt(
            out / "contact_fraction.csv",
            np.column_stack([cmap.overlaps * 1e3, cmap.contact_fraction * 100]),
            delimiter=",",
            header="overlap_mm,contact_fraction_percent",
            comments="",
            fmt="%.6f",
        )
        print(f"  plot: {plot_contact_map(cmap, out / 'contact_map')}")
        print(f"  table: {out / 'contact_fraction.csv'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
