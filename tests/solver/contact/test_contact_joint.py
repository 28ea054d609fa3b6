"""Generalized Newton on the scaled joint's first contact (the cycling of docs/contact.md).

A very coarse joint (8 around, 0.25 m axial, P2) is loaded on the TP top by the self-weight ramp
(10 kN over 2 s), in implicit steps of 20 ms up to 0.16 s (generalised-alpha): the TP first falls freely
(it starts a few micrometres above the MP), then lands on the MP cone. With the
symmetric variant and gamma0 = 10 and full Newton steps, Newton cycled between "all
open" and "deeply penetrated" at the landing step. With the skew-symmetric variant,
gamma0 = 1 and the gap-limited Newton step, every step must converge within
``MAX_ITERATIONS`` without cutting the step, and the TP must touch
the MP within these steps (it rebounds and lands again: the landing is nearly elastic).
"""

from mpi4py import MPI

import numpy as np
import pytest

from common import backend  # noqa: F401
from dolfinx import fem

from common.case import read_case
from geometry import tags
from geometry.mesh import create_joint_mesh
from geometry.parameters import MeshOptions, geometry_from_case
from solver.contact import FrictionLaw, NitscheContact, Status
from solver.dynamics.damping import RayleighDamping
from solver.dynamics.elastodynamics import Elastodynamics, assemble_structure
from solver.dynamics.loads import RampedAxialForce, TopFaceLoad, TPLoading
from solver.dynamics.schemes import GeneralisedAlpha
from solver.dynamics.time_loop import run
from solver.installation.observers import Settlement
from solver.modal.eigen import clamp

pytestmark = pytest.mark.mpi

MAX_ITERATIONS = 25


def landing(theta: int, gamma0: float, max_gap_change: float | None):
    """Steps of 20 ms of the self-weight ramp up to 0.16 s; returns (rows, contact).

    Raises RuntimeError at the first step that does not converge in MAX_ITERATIONS."""
    comm = MPI.COMM_WORLD
    joint, material, _ = geometry_from_case(read_case("scaled"))
    data = create_joint_mesh(comm, joint, MeshOptions(n_circumferential=8, axial_size=0.25))
    V = fem.functionspace(data.mesh, ("Lagrange", 2, (3,)))
    bcs = [clamp(V, data.facet_tags, [tags.MP_CLAMPED])]
    M, K = assemble_structure(V, material, bcs)
    contact = NitscheContact(
        V,
        data.facet_tags,
        tags.TP_CONTACT,
        tags.MP_CONTACT,
        material,
        FrictionLaw(),
        gamma0=gamma0,
        theta=theta,
    )
    loading = TPLoading(
        TopFaceLoad(V, data.facet_tags, tags.TP_TOP), static_axial=RampedAxialForce(-10e3, 2.0)
    )
    problem = Elastodynamics(
        V,
        M,
        K,
        bcs,
        load=loading,
        scheme=GeneralisedAlpha.from_spectral_radius(0.8),
        damping=RayleighDamping.at_frequency(0.01, 120.0),
        contact=contact,
        newton_options={
            "max_iterations": MAX_ITERATIONS,
            "refactor_after": 0,
            "max_gap_change": max_gap_change,
        },
    )
    problem.initialise(0.0)
    settlement = Settlement(problem.u, joint, data.cell_tags)

    def in_contact(problem) -> dict:
        points = comm.allreduce(int(np.sum(contact.state.status != Status.OPEN)), op=MPI.SUM)
        return {"contact_points": points}

    # dt_min = dt: a step that does not converge within MAX_ITERATIONS raises at once
    rows = run(problem, 0.16, 0.02, dt_min=0.02, observers=[settlement, in_contact], progress=False)
    return rows, contact


def test_self_weight_landing_converges():
    rows, contact = landing(theta=-1, gamma0=1.0, max_gap_change=1e-6)
    its = [r["newton_iterations"] for r in rows]
    points = [r["contact_points"] for r in rows]
    if MPI.COMM_WORLD.rank == 0:
        print(
            f"iterations {its}, settlement {[round(r['settlement_mm'], 4) for r in rows]} mm, "
            f"points in contact {points}"
        )
    assert len(rows) == 8 and max(its) <= MAX_ITERATIONS
    assert max(points) > 0  # the TP landed on the MP within these steps
