"""Radial edge stiffness of the scaled TP: axisymmetric shell ODE vs a 3D solid FE model.

The FE model is the TP tube (hex27 mesh of geometry.mesh, vector Lagrange degree 2),
clamped at its top annulus, with a uniform radial traction q / h on its lower
annulus (a ring load of q per unit mid-surface circumference). The mean radial
displacement of the lower annulus is compared with the shell's free-edge radial
flexibility F_rr (ring shear H, with V = M = 0).
"""

import math

import numpy as np
import pytest
import ufl
from mpi4py import MPI

from common import backend  # noqa: F401  (before dolfinx)
import dolfinx.fem.petsc  # noqa: E402
from dolfinx import fem  # noqa: E402

from geometry import tags  # noqa: E402
from geometry.mesh import create_tube_mesh  # noqa: E402
from geometry.parameters import MeshOptions, load_geometry  # noqa: E402
from solver.elasticity import epsilon, sigma  # noqa: E402
from solver.modal.eigen import clamp  # noqa: E402
from solver.reduced.shell import ring_flexibility, tp_edge_shell  # noqa: E402

pytestmark = pytest.mark.mpi


def fe_edge_radial_flexibility(comm, part, material, options, q: float) -> float:
    """Mean radial displacement of the lower annulus per unit ring load [m^2/N]."""
    mesh_data = create_tube_mesh(comm, part, options)
    mesh, facets = mesh_data.mesh, mesh_data.facet_tags
    V = fem.functionspace(mesh, ("Lagrange", 2, (3,)))
    u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    x = ufl.SpatialCoordinate(mesh)
    e_r = ufl.as_vector((x[0], x[1], 0.0)) / ufl.sqrt(x[0] ** 2 + x[1] ** 2)
    ds = ufl.Measure("ds", domain=mesh, subdomain_data=facets)
    traction = (q / part.thickness) * e_r
    a = ufl.inner(sigma(u, material), epsilon(v)) * ufl.dx
    L = ufl.inner(traction, v) * ds(tags.BOTTOM)
    problem = dolfinx.fem.petsc.LinearProblem(
        a,
        L,
        bcs=[clamp(V, facets, [tags.TOP])],
        petsc_options_prefix="shell_fe_",
        petsc_options={
            "ksp_type": "preonly",
            "pc_type": "lu",
            "pc_factor_mat_solver_type": "mumps",
        },
    )
    uh = problem.solve()
    mean = fem.assemble_scalar(fem.form(ufl.inner(uh, e_r) * ds(tags.BOTTOM)))
    area = fem.assemble_scalar(fem.form(1.0 * ds(tags.BOTTOM)))
    return comm.allreduce(mean, op=MPI.SUM) / comm.allreduce(area, op=MPI.SUM) / q


def test_scaled_tp_radial_edge_stiffness_matches_3d_fe():
    joint, material, _ = load_geometry("cases/scaled.toml")
    F_shell, _ = ring_flexibility(tp_edge_shell(joint, material), 0.0, "top")
    # 24 elements around suffice for this axisymmetric (m = 0) load; 2 cm along the
    # axis resolve the edge bending layer (1 / lambda = 3.2 cm)
    options = MeshOptions(n_circumferential=24, axial_size=0.02, n_layers=1, geometry_order=2)
    f_fe = fe_edge_radial_flexibility(MPI.COMM_WORLD, joint.tp, material, options, q=1.0e5)
    r_mid = tp_edge_shell(joint, material).meridian.r[0]
    K_shell, K_fe = 2 * math.pi * r_mid / F_shell[0, 0], 2 * math.pi * r_mid / f_fe
    if MPI.COMM_WORLD.rank == 0:
        print(
            f"\nscaled TP radial edge stiffness: shell {K_shell:.5e} N/m, 3D FE {K_fe:.5e} N/m, "
            f"ratio {K_fe / K_shell:.4f}"
        )
    assert np.isfinite(K_fe)
    assert K_fe == pytest.approx(K_shell, rel=0.05)
