"""Generalized Newton on a sliding step: the Jacobian against finite differences of the
residual, and the convergence rate it gives.

The Jacobian drops the variation of the master normal and of the projection point with u
(docs/contact.md). With the base undeformed (its surface a fixed plane) these terms vanish
for perturbations of the sliding block, so there the Jacobian must match finite
differences to truncation error in the block's rows, including slip and the d mu / d|v|
term of the velocity law (the base's rows carry the dropped shift of the master basis
functions with the projection point). At the real sliding state, with the base deformed and perturbed too, the
dropped terms appear, with a relative size of the order of the interface strain p / E.
"""

from mpi4py import MPI

import numpy as np
import pytest

import dolfinx
from contact_cases import sliding_block
from solver.contact import Status
from solver.friction import FrictionLaw

pytestmark = pytest.mark.mpi


def _jacobian_error(contact, u, w, eps, rows=None):
    """|| (r(u + eps w) - r(u - eps w)) / (2 eps) - J w || / || J w || (on the owned ``rows``
    of the local arrays if given)."""
    u0 = u.x.array.copy()
    contact.update(u)
    J = contact.jacobian()
    Jw = J.createVecLeft()
    J.mult(w.x.petsc_vec, Jw)
    residuals = []
    for sign in (1.0, -1.0):
        u.x.array[:] = u0 + sign * eps * w.x.array
        contact.update(u)
        residuals.append(contact.residual())
    u.x.array[:] = u0
    contact.update(u)
    fd = residuals[0]
    fd.axpy(-1.0, residuals[1])
    fd.scale(0.5 / eps)
    fd.axpy(-1.0, Jw)
    if rows is None:
        return fd.norm() / Jw.norm()
    comm = u.function_space.mesh.comm
    error = comm.allreduce(np.sum(fd.array[rows] ** 2), op=MPI.SUM)
    reference = comm.allreduce(np.sum(Jw.array[rows] ** 2), op=MPI.SUM)
    return np.sqrt(error / reference)


@pytest.fixture()
def sliding_state():
    friction = FrictionLaw(mu_s=0.5, mu_d=0.4, d_c=5000.0)
    history, contact, results, u = sliding_block(MPI.COMM_WORLD, friction, steps=6, slide_per_step=2e-4, dt=1.0)
    assert all(r.converged for r in results)
    return contact, u, results


def _direction(contact, u, slave_only: bool):
    rng = np.random.default_rng(1 + u.function_space.mesh.comm.rank)
    w = dolfinx.fem.Function(u.function_space)
    w.x.array[:] = rng.uniform(-1.0, 1.0, w.x.array.size)
    if slave_only:
        mask = np.zeros(w.x.array.size // 3, dtype=bool)
        mask[contact.slave.dofs.ravel()] = True
        w.x.array.reshape(-1, 3)[~mask] = 0.0
    w.x.scatter_forward()
    return w


def test_jacobian_is_consistent_for_slave_motion(sliding_state):
    contact, u, _ = sliding_state
    V = u.function_space
    mesh = V.mesh
    # keep the block's displacement, reset the base to its undeformed (flat) shape, now and
    # at the step's start (the block then was 0.2 mm further back)
    cells = np.arange(mesh.topology.index_map(3).size_local + mesh.topology.index_map(3).num_ghosts, dtype=np.int32)
    block = cells[dolfinx.mesh.compute_midpoints(mesh, 3, cells)[:, 2] > 0]
    on_block = np.zeros(u.x.array.size // 3, dtype=bool)
    on_block[V.dofmap.list[block].ravel()] = True
    state = u.copy()
    state.x.array.reshape(-1, 3)[~on_block] = 0.0
    reference = state.copy()
    reference.x.array.reshape(-1, 3)[on_block, 0] -= 2e-4
    contact.set_reference(reference, 1.0)
    contact.update(state)
    status = np.concatenate(MPI.COMM_WORLD.allgather(contact.state.status))
    assert np.any(status == Status.SLIP)
    w = _direction(contact, u, slave_only=True)
    n_owned = V.dofmap.index_map.size_local
    block_rows = np.flatnonzero(np.repeat(on_block[:n_owned], 3))
    error = _jacobian_error(contact, state, w, eps=1e-11, rows=block_rows)
    assert error < 1e-6


def test_dropped_terms_are_of_order_strain(sliding_state):
    contact, u, _ = sliding_state
    w = _direction(contact, u, slave_only=False)
    error = _jacobian_error(contact, u, w, eps=1e-11)
    strain = 1e6 / contact.material.E  # q / E
    assert error < 10 * strain


def test_convergence_rate(sliding_state):
    """Once the stick/slip/open sets settle, each iteration cuts ||F|| by a factor of order p / E."""
    _, _, results = sliding_state
    norms = np.array(results[-1].residual_norms)
    assert results[-1].converged and results[-1].iterations <= 12
    rates = norms[-2:] / norms[-3:-1]
    assert np.all(rates < 1e-2), rates
