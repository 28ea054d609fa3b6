"""Fixtures of the benchmarks' tests."""

import pytest
from mpi4py import MPI

from solver.installation.runner import Installation


@pytest.fixture(scope="session")
def installed(tiny_case, shared_dir):
    """The output folder of an installation run of the tiny joint, with its stage states."""
    out = shared_dir("installed")
    case = tiny_case("output.stage_states=true")
    Installation(MPI.COMM_WORLD, case, out, progress=False).run()
    return out
