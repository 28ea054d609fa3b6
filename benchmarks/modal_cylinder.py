"""Convergence of the solid modal analysis of a thin clamped-free cylinder against shell theory.

    python benchmarks/modal_cylinder.py

Cylinder: mid-surface radius 0.297 m, wall 6 mm, length 1.4 m, steel (E = 210 GPa,
nu = 0.3, rho = 7850 kg/m^3), clamped at z = 0, meshed by geometry/. For each
discretisation (elements around, axial size, layers through the wall, degree) the
lowest frequency of m = 2, 3, 4 is compared with the Sanders-Koiter Rayleigh-Ritz
value (solver/reduced/cylinder_shell.py, 14 Legendre terms). Prints a markdown table.
"""

import sys
import time

from common import backend  # noqa: F401  (before dolfinx)

from dolfinx import fem
from mpi4py import MPI

from common.material import Material
from geometry import tags
from geometry.mesh import create_tube_mesh
from geometry.parameters import ConePart, MeshOptions
from solver.modal.classify import classify
from solver.modal.eigen import EigenOptions, clamp, modal_analysis
from solver.reduced.cylinder_shell import cylinder_frequencies

R, H, L = 0.297, 0.006, 1.4
STEEL = Material(E=210e9, nu=0.3, rho=7850.0)
CASES = [  # (n_circumferential, axial_size [m], n_layers, degree)
    (24, 0.08, 1, 2),
    (48, 0.08, 1, 2),
    (96, 0.08, 1, 2),
    (48, 0.04, 1, 2),
    (48, 0.08, 2, 2),
    (24, 0.1, 1, 3),
    (32, 0.1, 1, 3),
    (48, 0.08, 1, 3),
]


def main() -> int:
    comm = MPI.COMM_WORLD
    part = ConePart(
        half_angle_deg=0.0,
        bottom_outer_diameter=2 * (R + H / 2),
        cone_length=L,
        straight_length=0.0,
        thickness=H,
    )
    ritz = {m: cylinder_frequencies(R, H, L, STEEL, m)[0] for m in (2, 3, 4)}
    lines = [
        "| around | axial [m] | layers | degree | dofs | "
        + " | ".join(f"m={m} [Hz] (error)" for m in ritz)
        + " | time [s] |",
        "|---|---|---|---|---|" + "---|" * len(ritz) + "---|",
        "| Sanders-Ritz | | | | | " + " | ".join(f"{f:.2f}" for f in ritz.values()) + " | |",
    ]
    for n_c, axial, layers, degree in CASES:
        t0 = time.perf_counter()
        options = MeshOptions(n_circumferential=n_c, axial_size=axial, n_layers=layers)
        mesh_data = create_tube_mesh(comm, part, options)
        V = fem.functionspace(mesh_data.mesh, ("Lagrange", degree, (3,)))
        bc = clamp(V, mesh_data.facet_tags, [tags.BOTTOM])
        result = modal_analysis(V, STEEL, [bc], options=EigenOptions(n_modes=12))
        lowest = {}
        for f, u in zip(result.frequencies_hz, result.modes):
            lowest.setdefault(classify(u).m, f)
        cells = [
            f"{lowest[m]:.2f} ({100 * (lowest[m] / ritz[m] - 1):+.2f} %)" if m in lowest else "-"
            for m in ritz
        ]
        lines.append(
            f"| {n_c} | {axial} | {layers} | {degree} | {V.dofmap.index_map.size_global * 3} | "
            + " | ".join(cells)
            + f" | {time.perf_counter() - t0:.1f} |"
        )
        if comm.rank == 0:
            print(lines[-1], flush=True)
    if comm.rank == 0:
        print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main())
