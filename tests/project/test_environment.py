"""The DOLFINx stack loads in the right order and works on 1 and 2 ranks."""

import pytest
from mpi4py import MPI

import dolfinx
from petsc4py import PETSc

pytestmark = pytest.mark.mpi


def test_dolfinx_version_and_scalar():
    assert dolfinx.__version__.startswith("0.11")
    assert PETSc.ScalarType().dtype.kind == "f", "the code needs real-scalar PETSc"


def test_distributed_mesh_counts_cells():
    mesh = dolfinx.mesh.create_unit_cube(MPI.COMM_WORLD, 3, 3, 3, dolfinx.mesh.CellType.hexahedron)
    imap = mesh.topology.index_map(3)
    assert mesh.comm.allreduce(imap.size_local, op=MPI.SUM) == 27
