"""Time stepping of the atlas's branches from a saved state: the joint's time, settlement and
contact normal force recorded after every step, with or without a new excitation."""

from solver.dynamics.loads import Schedule
from solver.dynamics.time_loop import run
from solver.installation.model import JointModel, attach_vibration

__all__ = ["advance", "joint_state", "run_schedule"]


def joint_state(model: JointModel) -> tuple[float, float, float]:
    """Time [s], settlement [mm] and contact normal force [N] now (collective)."""
    problem = model.problem
    return problem.t, model.settlement(problem)["settlement_mm"], model.contact.forces()[0]


def advance(model: JointModel, t_end: float, dt: float, rows: list) -> None:
    """Integrate to ``t_end`` [s] with step ``dt`` [s] (cut on a Newton failure, down to the
    case's ``time.dt_min_fraction`` of it), appending ``joint_state`` after every step."""

    def observe(problem) -> dict:
        rows.append(joint_state(model))
        return {}

    dt_min = dt * model.case.time.dt_min_fraction
    run(model.problem, t_end, dt, dt_min=dt_min, observers=[observe], progress=False)


def run_schedule(model: JointModel, schedule: Schedule, dt: float) -> list:
    """Excite the joint with ``schedule`` (from now to its end) with step ``dt`` [s]; its
    ``joint_state`` rows, the first one now."""
    attach_vibration(model, schedule)
    rows = [joint_state(model)]
    advance(model, schedule.end_s, dt, rows)
    return rows
