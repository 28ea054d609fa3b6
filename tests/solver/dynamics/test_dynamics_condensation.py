"""Static condensation of the linear bulk (solver.dynamics.condensation) against the uncondensed system.

The coarse joint of the installation tests (8 around, 0.25 m axially, 10 mm in the contact zone,
P2, one element through the wall; contact surfaces: the cone walls inside the zone).

1. Linear algebra. The zone (the cells with a contact facet) meets the rest of the cones at three
   rings (the MP below and above the zone, the TP above it), each 2 x 8 nodes around and 3
   through the wall, so the interface has 3 x 16 x 3 x 3 = 432 dofs. Solving the condensed
   system A_hat x = b_hat and recovering the bulk must give the direct solution of A x = b
   (A: the Newmark effective operator at 300 Hz / 30 steps, b random) to round-off.
2. Dynamics. The self-weight landing and stick-slip (10 kN over 0.2 s in 10 ms steps, then
   held, up to 0.3 s; the demo's contact settings) with and without ``condense_bulk``: both
   solve the same equations to the Newton tolerance (1e-7 relative), so the settlement
   histories must agree to 1e-6 of the settlement (a margin of 10 for the path of stick-slip
   decisions) and the contact statuses at the end must be the same.
"""

from mpi4py import MPI

import numpy as np
import pytest

from common import backend  # noqa: F401
from petsc4py import PETSc
from dolfinx import fem
from dolfinx.fem import petsc as fem_petsc

from common.case import read_case
from geometry import tags
from geometry.mesh import create_joint_mesh
from geometry.parameters import MeshOptions, geometry_from_case
from solver.contact import FrictionLaw, NitscheContact
from solver.dynamics.condensation import BulkCondensation
from solver.dynamics.damping import RayleighDamping
from solver.dynamics.elastodynamics import Elastodynamics, assemble_structure
from solver.dynamics.loads import RampedAxialForce, TopFaceLoad, TPLoading
from solver.dynamics.schemes import GeneralisedAlpha
from solver.dynamics.time_loop import run
from solver.installation.observers import Settlement
from solver.modal.eigen import clamp

pytestmark = pytest.mark.mpi

N_AROUND = 8


def coarse_joint():
    comm = MPI.COMM_WORLD
    joint, material, _ = geometry_from_case(read_case("scaled"))
    options = MeshOptions(n_circumferential=N_AROUND, axial_size=0.25, contact_axial_size=0.01)
    data = create_joint_mesh(comm, joint, options)
    V = fem.functionspace(data.mesh, ("Lagrange", 2, (3,)))
    bcs = [clamp(V, data.facet_tags, [tags.MP_CLAMPED])]
    M, K = assemble_structure(V, material, bcs)
    contact = NitscheContact(
        V,
        data.facet_tags,
        tags.TP_CONTACT,
        tags.MP_CONTACT,
        material,
        FrictionLaw(0.5, 0.4, d_c=100.0),
        gamma0=1.0,
        theta=-1,
        lagged_friction=True,
    )
    return joint, data, V, bcs, M, K, contact


def lu(A: PETSc.Mat) -> PETSc.KSP:
    ksp = PETSc.KSP().create(A.getComm())
    ksp.setType("preonly")
    ksp.getPC().setType("lu")
    ksp.getPC().setFactorSolverType("mumps")
    ksp.setOperators(A)
    return ksp


def test_condensed_solve_equals_direct_solve():
    _, _, V, bcs, M, K, contact = coarse_joint()
    scheme, dt = GeneralisedAlpha.from_spectral_radius(0.0), 1 / 9000
    c_M, _ = scheme.coefficients(dt)
    A = K.copy()
    A.axpy(c_M, M)
    condensation = BulkCondensation(A, V, contact.support_cells)
    N = A.getSize()[0]
    sizes = condensation.sizes
    assert sizes["zone"] + sizes["bulk"] == N
    assert sizes["interface"] == 3 * (2 * N_AROUND) * 3 * 3
    assert sizes["parts"] == 3  # the MP below and above the zone, the TP above it: one ring each

    b = A.createVecLeft()  # a load on every dof, the same for any number of ranks
    b.array_w[:] = np.sin(1.0 + np.arange(*b.getOwnershipRange()))
    fem_petsc.set_bc(b, bcs)
    direct = b.duplicate()
    lu(A).solve(b, direct)

    u = fem.Function(V)
    b_hat = b.duplicate()
    condensation.reduce_load(b, b_hat)
    condensation.hold_bulk(u, b_hat)
    lu(condensation.A_hat).solve(b_hat, u.x.petsc_vec)
    u.x.scatter_forward()
    condensation.recover(b, u)
    error = u.x.petsc_vec.copy()
    error.axpy(-1.0, direct)
    assert error.norm() <= 1e-10 * direct.norm()


def test_update_equals_a_new_condensation():
    """Condensing A(dt2) by updating the condensation of A(dt1) gives the condensation built anew."""
    _, _, V, bcs, M, K, contact = coarse_joint()
    scheme = GeneralisedAlpha.from_spectral_radius(0.0)
    operators = []
    for dt in (1 / 9000, 1 / 4000):
        A = K.copy()
        A.axpy(scheme.coefficients(dt)[0], M)
        operators.append(A)
    updated = BulkCondensation(operators[0], V, contact.support_cells)
    updated.update(operators[1])
    new = BulkCondensation(operators[1], V, contact.support_cells)
    difference = updated.A_hat.copy()
    difference.axpy(-1.0, new.A_hat)
    assert difference.norm() <= 1e-12 * new.A_hat.norm()


def settling_problem(
    condense_bulk: bool, max_iterations: int = 30, joint_model=None
) -> Elastodynamics:
    """The coarse joint under 10 kN ramped over 0.2 s (``joint_model``: coarse_joint()'s)."""
    joint, data, V, bcs, M, K, contact = joint_model or coarse_joint()
    loading = TPLoading(
        TopFaceLoad(V, data.facet_tags, tags.TP_TOP), static_axial=RampedAxialForce(-10e3, 0.2)
    )
    return Elastodynamics(
        V,
        M,
        K,
        bcs,
        load=loading,
        scheme=GeneralisedAlpha.from_spectral_radius(0.0),
        damping=RayleighDamping.at_frequency(0.01, 120.0),
        contact=contact,
        newton_options={
            "max_backtracks": 4,
            "max_gap_change": 1e-5,
            "max_iterations": max_iterations,
        },
        condense_bulk=condense_bulk,
    )


def settle(condense_bulk: bool):
    joint, data, V, bcs, M, K, contact = joint_model = coarse_joint()
    problem = settling_problem(condense_bulk, joint_model=joint_model)
    problem.initialise(0.0)
    rows = run(
        problem, 0.3, 0.01, observers=[Settlement(problem.u, joint, data.cell_tags)], progress=False
    )
    return np.array([r["settlement_mm"] for r in rows]), contact.state.status.copy()


def test_condensed_dynamics_matches_uncondensed():
    s_full, status_full = settle(condense_bulk=False)
    s_cond, status_cond = settle(condense_bulk=True)
    if MPI.COMM_WORLD.rank == 0:
        print(
            f"settlement {s_full[-1]:.9f} mm (uncondensed), {s_cond[-1]:.9f} mm (condensed), "
            f"largest difference {np.abs(s_full - s_cond).max():.3e} mm"
        )
    assert s_full[-1] > 0.5  # the TP landed and slid
    assert np.abs(s_full - s_cond).max() <= 1e-6 * np.abs(s_full).max()
    assert np.array_equal(status_full, status_cond)


def test_failed_step_leaves_the_state_unchanged():
    """A step whose Newton fails (one iteration allowed, while the TP slides) leaves every array
    the next step depends on as it was, the contact memory (the lagged friction coefficient's
    slip speed, the pairing) included: the retried step starts from u_n, not the last iterate."""
    joint_model = coarse_joint()
    problem = settling_problem(False, joint_model=joint_model)
    problem.initialise(0.0)
    run(problem, 0.15, 0.01, progress=False)
    saved = {key: value.copy() for key, value in problem.state_arrays().items()}
    assert MPI.COMM_WORLD.allreduce(np.abs(saved["slip_velocity"]).max(), op=MPI.MAX) > 0
    strict = settling_problem(False, max_iterations=1, joint_model=joint_model)
    strict.restore_state(problem.t, saved)
    result = strict.step(0.01)
    assert not result.converged and strict.t == problem.t
    after = strict.state_arrays()
    assert set(after) == set(saved)
    for key, value in saved.items():
        assert np.array_equal(after[key], value), key
