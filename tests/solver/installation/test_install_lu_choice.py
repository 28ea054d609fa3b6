"""Every LU package of ``[contact] lu_solver`` works with and without the condensed bulk.

The self-weight ramp of the tiny joint (cases/tiny.toml, 6 steps) runs for each combination of
``lu_solver`` ("auto", "mumps", "superlu_dist") and ``condense_bulk``: every step converges
without a cut, and the settlement equals that of MUMPS on the full system to the Newton
tolerance (the same discrete problem, solved by other factorisations). The tiny joint's whole
run (self-weight, modal and vibration stages) with SuperLU_DIST equals the one with MUMPS.
"auto" takes SuperLU_DIST on several ranks only where the self-weight stage has no event steps
(with them SuperLU_DIST crashed in the first vibration stage; such cases are refused,
test_install_errors.py). Serially and on 2 ranks (SuperLU_DIST on 2 ranks with the condensed
bulk once aborted the process).
"""

import pytest
from mpi4py import MPI
from petsc4py import PETSc

from solver.dynamics.time_loop import run
from solver.installation.model import set_up_joint_model
from solver.installation.runner import Installation

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


def test_whole_run_with_superlu_dist(tiny_case, shared_dir):
    if not PETSc.Sys.hasExternalPackage("superlu_dist"):
        pytest.skip("this PETSc has no superlu_dist")
    settled = {}
    for lu in ("mumps", "superlu_dist"):
        case = tiny_case(f"contact.lu_solver={lu}")
        runner = Installation(MPI.COMM_WORLD, case, shared_dir(f"whole_{lu}"), progress=False)
        summary = runner.run()
        assert sum(row["step_cuts"] for row in runner.history) == 0
        assert runner.stages[-1]["stage"] > 0  # through the vibration stages
        settled[lu] = summary["total_settlement_mm"]
    print(f"\nwhole run: settlement {settled} mm")
    assert settled["mumps"] > 0
    assert settled["superlu_dist"] == pytest.approx(settled["mumps"], rel=1e-6)


@pytest.mark.parametrize("event_dt_s", ["0", "0.001"])
def test_auto_takes_superlu_dist_only_without_event_steps(tiny_case, event_dt_s):
    model = set_up_joint_model(
        MPI.COMM_WORLD, tiny_case("contact.lu_solver=auto", f"self_weight.event_dt_s={event_dt_s}")
    )
    several = MPI.COMM_WORLD.size > 1 and PETSc.Sys.hasExternalPackage("superlu_dist")
    expected = "superlu_dist" if several and event_dt_s == "0" else "mumps"
    assert model.problem.newton_options["lu_solver"] == expected
