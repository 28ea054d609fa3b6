"""Every LU package of ``[contact] lu_solver`` works with and without the condensed bulk.

The self-weight ramp of the tiny joint (cases/tiny.toml, 6 steps) runs for each combination of
``lu_solver`` ("auto", "mumps", "superlu_dist") and ``condense_bulk``: every step converges
without a cut, and the settlement equals that of MUMPS on the full system to the Newton
tolerance (the same discrete problem, solved by other factorisations). Serially and on 2 ranks
(SuperLU_DIST on 2 ranks with the condensed bulk once aborted the process).
"""

import pytest
from mpi4py import MPI
from petsc4py import PETSc

from solver.dynamics.time_loop import run
from solver.installation.model import set_up_joint_model

pytestmark = pytest.mark.mpi


def _self_weight_ramp(case) -> tuple[float, int, list[int]]:
    """Settlement [mm] after the self-weight ramp of ``case``, step cuts, Newton iterations."""
    model = set_up_joint_model(MPI.COMM_WORLD, case)
    problem, sw = model.problem, case.self_weight
    iterations = []
    run(
        problem,
        sw.ramp_time_s,
        sw.dt_s,
        observers=[lambda p: iterations.append(p.last_result.iterations) or {}],
        progress=False,
    )
    return model.settlement(problem)["settlement_mm"], problem.failed_steps, iterations


@pytest.fixture(scope="module")
def reference(tiny_case) -> float:
    settled, cuts, _ = _self_weight_ramp(
        tiny_case("contact.lu_solver=mumps", "contact.condense_bulk=false")
    )
    assert cuts == 0
    return settled


@pytest.mark.parametrize("condense", ["true", "false"])
@pytest.mark.parametrize("lu", ["auto", "mumps", "superlu_dist"])
def test_lu_choice_with_and_without_condensation(tiny_case, reference, lu, condense):
    if lu != "auto" and not PETSc.Sys.hasExternalPackage(lu):
        pytest.skip(f"this PETSc has no {lu}")
    settled, cuts, iterations = _self_weight_ramp(
        tiny_case(f"contact.lu_solver={lu}", f"contact.condense_bulk={condense}")
    )
    print(
        f"\nlu_solver={lu}, condense_bulk={condense}: settlement {settled:.9f} mm "
        f"(reference {reference:.9f} mm), Newton iterations {iterations}, {cuts} step cuts"
    )
    assert cuts == 0
    assert len(iterations) == 6
    assert reference > 0
    assert settled == pytest.approx(reference, rel=1e-6)
