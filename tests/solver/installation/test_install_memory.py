"""A process that sets up joint after joint holds one joint's PETSc objects at a time.

petsc4py defers the destruction of a parallel PETSc object that Python drops to a collective
clean-up on the object's communicator; a joint's objects live on its mesh's own communicator.
Set up, used for a modal analysis and dropped five times, the joint of cases/quick.toml must
not grow the process: after ``free_dropped_joints`` the resident memory of the last three
rounds grows by less than 5 MB per joint (one joint's matrices, factorisations and eigensolver
take about 27 MB per rank on 2 ranks, which a clean-up on COMM_WORLD alone keeps). Serially and
on 2 ranks.
"""

from pathlib import Path

import pytest
from mpi4py import MPI

from solver.installation.model import free_dropped_joints, set_up_joint_model, settled_modes

pytestmark = pytest.mark.mpi

ROUNDS = 5
GROWTH_PER_JOINT_MB = 5.0


def _resident_mb() -> float:
    """This process's resident memory [MB] (Linux /proc)."""
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return float(line.split()[1]) / 1024.0
    raise RuntimeError("no VmRSS in /proc/self/status")


@pytest.mark.skipif(not Path("/proc/self/status").exists(), reason="needs Linux /proc")
def test_dropped_joints_are_freed(quick_case):
    comm = MPI.COMM_WORLD
    case = quick_case()
    resident = []
    for _ in range(ROUNDS):
        model = set_up_joint_model(comm, case)
        settled_modes(model, 6)
        del model
        free_dropped_joints()
        resident.append(comm.allreduce(_resident_mb(), op=MPI.MAX))
    growth = (resident[-1] - resident[1]) / (ROUNDS - 2)
    if comm.rank == 0:
        print(f"resident memory after each joint: {', '.join(f'{r:.1f}' for r in resident)} MB")
    assert growth < GROWTH_PER_JOINT_MB, f"{growth:.1f} MB per joint"
