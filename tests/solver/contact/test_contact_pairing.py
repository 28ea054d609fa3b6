"""Closest-point pairing: flat and curved master surfaces, and independence of the distribution."""

from mpi4py import MPI

import numpy as np
import pytest

import dolfinx
from contact_cases import MASTER, SLAVE, two_blocks, two_rings
from solver.contact import MasterSurface, SlaveQuadrature, pair

pytestmark = pytest.mark.mpi


def _surfaces(mesh, facet_tags, degree=2):
    V = dolfinx.fem.functionspace(mesh, ("Lagrange", degree, (3,)))
    master = MasterSurface(V, facet_tags, MASTER)
    slave = SlaveQuadrature(V, facet_tags, SLAVE, 4)
    return V, master, slave


def test_flat_surface_under_rigid_motion():
    """Slave points lifted by 10 mm project vertically onto the moved plane z = 0.02 m."""
    mesh, _, tags = two_blocks(MPI.COMM_WORLD, order=2)
    V, master, slave = _surfaces(mesh, tags)
    u = dolfinx.fem.Function(V)
    u.interpolate(lambda x: np.vstack([0.1 * np.ones_like(x[0]), 0.05 + 0 * x[0], 0.02 + 0 * x[0]]))
    x = slave.points + np.array([0.0, 0.0, 0.03])
    p = pair(x, master, master.displacement(u))
    inside = (x[:, 0] > 0.1 + 1e-9) & (x[:, 1] > 0.05 + 1e-9)  # above the moved base
    assert np.allclose(p.gap[inside], 0.01, atol=1e-12)
    assert np.allclose(p.normal[inside], [0, 0, 1], atol=1e-12)
    assert np.allclose(p.y[inside, :2], x[inside, :2], atol=1e-12)
    # points beyond the moved base's edges have no partner
    assert np.array_equal(p.paired, inside)


def test_curved_surface_gap():
    """Points on the outer ring's inner cylinder (r = b) against the inner ring's outer
    cylinder (r = b + delta): gap = |x| - (b + delta) up to the O(h^3) geometry error."""
    radii, delta = (0.5, 0.75, 1.0), 1e-3
    mesh, _, tags = two_rings(MPI.COMM_WORLD, radii, delta, inner=(2, 12), outer=(2, 9))
    V, master, slave = _surfaces(mesh, tags)
    x = slave.points
    p = pair(x, master, master.displacement(dolfinx.fem.Function(V)))
    r = np.hypot(x[:, 0], x[:, 1])
    assert p.paired.all()
    assert np.allclose(p.gap, r - (radii[1] + delta), atol=5e-6)
    radial = np.column_stack([x[:, 0] / r, x[:, 1] / r, 0 * r])
    assert np.allclose(p.normal, radial, atol=1e-3)
    assert np.allclose(np.hypot(p.y[:, 0], p.y[:, 1]), radii[1] + delta, atol=5e-6)


def _sorted_pairs(comm):
    mesh, _, tags = two_rings(comm, (0.5, 0.75, 1.0), 1e-3, inner=(2, 12), outer=(2, 9))
    V, master, slave = _surfaces(mesh, tags)
    u = dolfinx.fem.Function(V)
    u.interpolate(lambda x: np.vstack([2e-3 * x[1], -1e-3 * x[0], 1e-4 * x[2]]))  # slide and twist
    p = pair(slave.points + slave.displacement(u), master, master.displacement(u))
    data = np.column_stack([slave.points, p.y, p.normal, p.gap])
    data = np.concatenate(mesh.comm.allgather(data))
    return data[np.lexsort(np.round(data[:, :3], 10).T)]


def test_pairs_independent_of_distribution():
    """The distributed pairing equals the pairing on an undistributed copy of the mesh."""
    distributed = _sorted_pairs(MPI.COMM_WORLD)
    serial = _sorted_pairs(MPI.COMM_SELF)
    assert distributed.shape == serial.shape
    assert np.allclose(distributed, serial, rtol=0, atol=1e-13)
