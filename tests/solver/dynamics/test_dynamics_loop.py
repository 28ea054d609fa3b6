"""Time loop: step cutting and recovery, the minimum-step error, CSV history; settlement definition."""

import csv
import types

import numpy as np
import pytest
import ufl
from mpi4py import MPI

from dolfinx import fem

from common.case import resolve_case_path
from geometry import tags
from geometry.mesh import create_joint_mesh
from geometry.parameters import MeshOptions, load_geometry
from solver.dynamics.elastodynamics import StepResult
from solver.dynamics.time_loop import EventSteps, run
from solver.installation.observers import Settlement
from solver.post.csv import CsvWriter

pytestmark = pytest.mark.mpi


class FlakyProblem:
    """Stand-in for Elastodynamics whose Newton fails for steps longer than max_ok [s] near t_hard."""

    def __init__(self, t_hard: float, max_ok: float):
        self.t, self.t_hard, self.max_ok = 0.0, t_hard, max_ok
        self.V = types.SimpleNamespace(mesh=types.SimpleNamespace(comm=MPI.COMM_WORLD))
        self.attempts = []

    def step(self, dt: float) -> StepResult:
        self.attempts.append(dt)
        if self.t <= self.t_hard < self.t + dt and dt > self.max_ok:
            return StepResult(False, 30, [1.0, 2.0], "no convergence (test)")
        self.t += dt
        return StepResult(True, 2, [1.0, 1e-12])


def test_step_is_cut_and_regrown(shared_tmp):
    problem = FlakyProblem(t_hard=0.35, max_ok=0.03)
    comm = MPI.COMM_WORLD
    path = shared_tmp / "history.csv"  # written by rank 0
    with CsvWriter(path, comm=comm) as writer:
        rows = run(
            problem,
            1.0,
            0.1,
            observers=[lambda p: {"settlement_mm": 10 * p.t}],
            on_row=writer.write,
            progress=False,
        )
    steps = [r["dt_s"] for r in rows]
    assert sum(steps) == pytest.approx(1.0)
    assert min(steps) == pytest.approx(0.025)  # 0.1 -> 0.05 -> 0.025 <= 0.03
    assert max(steps[-3:]) == pytest.approx(0.1)  # grown back to dt
    if comm.rank > 0:
        return
    with open(path) as f:
        table = list(csv.reader(f))
    assert table[0] == ["time_s", "dt_s", "newton_iterations", "settlement_mm"]
    assert len(table) == len(rows) + 1 and float(table[-1][0]) == pytest.approx(1.0)


def test_minimum_step_gives_a_clear_error():
    problem = FlakyProblem(t_hard=0.35, max_ok=1e-9)
    with pytest.raises(
        RuntimeError,
        match=r"t = 0.3375 s even with dt = 0.0125 s \(minimum step 0.01 s\): no convergence \(test\)",
    ):
        run(problem, 1.0, 0.1, dt_min=0.01, progress=False)


class EventfulProblem(FlakyProblem):
    """A FlakyProblem whose measure (position(t) [m]) moves at 1 m/s for 0.3 s <= t <= 0.5 s and
    rests otherwise; its state is t alone."""

    def position(self) -> float:
        return min(max(self.t - 0.3, 0.0), 0.2)

    def state_arrays(self) -> dict:
        return {}

    def restore_state(self, t: float, arrays: dict) -> None:
        self.t = t


def test_cut_steps_within_an_event_keep_to_the_grids():
    """Steps of 0.1 s, events at 0.01 s (rate 0.3 m/s); within the event Newton fails at
    0.407 s for steps above 0.004 s: 0.01 s is cut to 0.005 s, which passes once (to 0.405 s)
    and is cut again. The cut steps grow back only where the time lies on the grid of the grown
    step (0.005 s at 0.415 s, 0.01 s at 0.44 s, not at 0.435 s), so that 5 calm steps after
    the event (at 0.55 s) the nominal step resumes on its grid (0.6 s) and the interval ends
    with a nominal step."""
    problem = EventfulProblem(t_hard=0.407, max_ok=0.004)
    events = EventSteps(0.01, 0.3, EventfulProblem.position, calm_steps=5)
    rows = run(problem, 1.0, 0.1, events=events, progress=False)
    times, steps = np.array([r["time_s"] for r in rows]), np.array([r["dt_s"] for r in rows])
    assert steps.sum() == pytest.approx(1.0) and times[-1] == pytest.approx(1.0)
    assert steps[(times > 0.3 + 1e-9) & (times < 0.5)].max() <= 0.01 + 1e-12  # event resolved
    assert np.allclose(np.unique(np.round(steps, 9)), [0.0025, 0.005, 0.01, 0.1])
    for step in (0.0025, 0.005, 0.01, 0.1):  # each step ends on its own grid
        ends = times[np.isclose(steps, step)]
        assert np.allclose(ends / step, np.round(ends / step))
    grown = times[np.flatnonzero(np.diff(steps) > 0)]  # the ends of the steps before a growth
    assert np.allclose(grown, [0.415, 0.44, 0.6])
    nominal = np.flatnonzero(np.isclose(steps, 0.1) & (times > 0.5))
    assert np.allclose(times[nominal], [0.7, 0.8, 0.9, 1.0])


def test_failed_nominal_step_is_retaken_in_event_steps():
    """With events at 0.01 s, a nominal step of 0.1 s whose Newton fails (at 0.15 s, for steps
    above 0.02 s) is retaken in steps of 0.01 s, not halved to 0.05 and 0.025 s; the nominal
    step resumes on its grid after 5 calm steps."""
    problem = EventfulProblem(t_hard=0.15, max_ok=0.02)
    events = EventSteps(0.01, 0.3, EventfulProblem.position, calm_steps=5)
    rows = run(problem, 0.3, 0.1, events=events, progress=False)
    times, steps = np.array([r["time_s"] for r in rows]), np.array([r["dt_s"] for r in rows])
    assert np.allclose(problem.attempts[:3], [0.1, 0.1, 0.01])  # the second 0.1 s step failed
    assert np.allclose(steps, [0.1] + [0.01] * 10 + [0.1])
    assert times[-1] == pytest.approx(0.3)


@pytest.mark.parametrize(
    "kwargs",
    [
        dict(t_end=-1.0, dt=0.1),
        dict(t_end=1.0, dt=0.0),
        dict(t_end=1.0, dt=0.1, dt_min=0.2),
        dict(t_end=1.0, dt=0.1, events=EventSteps(0.03, 1.0, lambda problem: 0.0, 5)),
        dict(t_end=1.0, dt=0.1, events=EventSteps(0.001, 1.0, lambda problem: 0.0, 5)),
    ],
)
def test_bad_run_arguments_raise(kwargs):
    with pytest.raises(ValueError):
        run(FlakyProblem(2.0, 1.0), progress=False, **kwargs)


@pytest.mark.parametrize(
    "args",
    [(0.0, 1.0, lambda p: 0.0, 5), (0.01, 0.0, lambda p: 0.0, 5), (0.01, 1.0, lambda p: 0.0, 0)],
)
def test_bad_event_steps_raise(args):
    with pytest.raises(ValueError, match="need dt_s > 0, rate > 0 and calm_steps >= 1"):
        EventSteps(*args)


@pytest.fixture(scope="module")
def joint_space():
    joint, _, _ = load_geometry(resolve_case_path("scaled"))
    data = create_joint_mesh(
        MPI.COMM_WORLD, joint, MeshOptions(n_circumferential=8, axial_size=0.5)
    )
    V = fem.functionspace(data.mesh, ("Lagrange", 2, (3,)))
    return joint, V, data.cell_tags


def test_settlement_definition(joint_space):
    joint, V, cell_tags = joint_space
    u = fem.Function(V)
    settlement = Settlement(u, joint, cell_tags)
    u.interpolate(
        lambda x: np.vstack([0.001 * x[1], -0.002 + 0 * x[0], 0.003 + 0 * x[0]])
    )  # rigid-ish motion
    assert settlement()["settlement_mm"] == pytest.approx(0.0, abs=1e-12)
    mesh = V.mesh
    chi = fem.Function(fem.functionspace(mesh, ("DG", 0)))  # 1 on the TP
    tp_cells = cell_tags.find(tags.TP_VOLUME)
    chi.x.array[tp_cells[tp_cells < mesh.topology.index_map(3).size_local]] = 1.0
    chi.x.scatter_forward()
    u.interpolate(
        fem.Expression(ufl.as_vector([0.0, 0.0, -0.004 * chi]), V.element.interpolation_points)
    )
    assert settlement()["settlement_mm"] == pytest.approx(4.0, rel=1e-12)
    # MP compressed axially by 1 mm at the TP edge height: the TP edge moves with it -> no settlement
    z_e = joint.tp_offset
    u.interpolate(lambda x: np.vstack([0 * x[0], 0 * x[0], -0.001 * x[2] / z_e]))
    assert settlement()["settlement_mm"] == pytest.approx(0.0, abs=1e-9)
