"""The time loop: integrate an ``Elastodynamics`` problem over an interval with step cutting.

On Newton failure the step is halved and retried, and grows back after a few accepted
steps where the time lies on the grid of the grown step (:func:`run`), so that the steps keep
to their grids and the interval's end. With ``EventSteps`` a step during which a measure of
the state (e.g. the settlement) moves faster than a given rate, or whose Newton fails, is
retaken in finer steps until it rests again: the events of a stick-slip staircase are
resolved while the steps between them stay long.
Observers add their values (keys carry units) to each step's row.
"""

from collections.abc import Callable, Sequence
from dataclasses import dataclass

from mpi4py import MPI

from solver.dynamics.elastodynamics import Elastodynamics

Observer = Callable[[Elastodynamics], dict[str, float]]


@dataclass(frozen=True)
class EventSteps:
    """Fine steps within events: a step longer than ``dt_s`` [s] during which ``measure`` moved
    faster than ``rate`` (its unit per s), or whose Newton failed, is retaken in steps of
    ``dt_s``; the nominal step resumes at the first time on its grid after ``calm_steps`` fine
    steps below the rate.

    The nominal step must be a whole multiple of ``dt_s``, so that both step sizes keep their
    operators (``Elastodynamics(operators_kept=2)`` refactorises nothing on a switch)."""

    dt_s: float
    rate: float
    measure: Callable[[Elastodynamics], float]
    calm_steps: int

    def __post_init__(self) -> None:
        if not (self.dt_s > 0 and self.rate > 0 and self.calm_steps >= 1):
            raise ValueError(
                f"need dt_s > 0, rate > 0 and calm_steps >= 1, "
                f"got {self.dt_s} s, {self.rate}, {self.calm_steps}"
            )


def check_event_step(dt: float, dt_s: float, dt_min: float) -> None:
    """Raise ValueError unless the step within events dt_s [s] divides the nominal step dt [s]
    and is at least the smallest cut step dt_min [s]."""
    ratio = dt / dt_s
    if ratio < 1 - 1e-9 or abs(ratio - round(ratio)) > 1e-9 * ratio:
        raise ValueError(f"the step within events ({dt_s} s) must divide the step dt = {dt} s")
    if dt_s < dt_min:
        raise ValueError(
            f"the step within events ({dt_s} s) lies below the smallest cut step "
            f"dt_min = {dt_min} s"
        )


def _saved_state(problem: Elastodynamics) -> dict:
    return {key: value.copy() for key, value in problem.state_arrays().items()}


def _on_grid(elapsed: float, step: float) -> bool:
    """Whether ``elapsed`` [s] is a whole number of steps ``step`` [s], to the round-off that a
    time summed step by step carries (1e-9 relative: within it for 10^7 steps)."""
    return abs(elapsed - round(elapsed / step) * step) <= 1e-9 * max(elapsed, step)


def run(
    problem: Elastodynamics,
    t_end: float,
    dt: float,
    dt_min: float | None = None,
    observers: Sequence[Observer] = (),
    on_row: Callable[[dict[str, float]], None] | None = None,
    progress: bool = True,
    growth_after: int = 4,
    events: EventSteps | None = None,
) -> list[dict[str, float]]:
    """Integrate from problem.t to t_end [s] with nominal step dt [s].

    On Newton failure the step is halved and retried (with ``events``, a step longer than
    ``events.dt_s`` is retaken in steps of it); after ``growth_after`` accepted steps it doubles
    again at the first time on the grid of the doubled step (up to dt, or up to ``events.dt_s``
    within an event), so that a step of size h starts on the grid t + k h of the start time t
    (but the last, shortened to reach t_end). Below dt_min
    (default dt/64) a RuntimeError names the time and step. Each accepted step records time_s,
    dt_s, newton_iterations and every observer's values (keys carry units, e.g.
    settlement_mm); each row is passed to ``on_row`` as it is produced (e.g.
    ``solver.post.csv.CsvWriter.write``). Returns the rows.
    """
    if not (t_end > problem.t and dt > 0):
        raise ValueError(
            f"need t_end > t = {problem.t} s and dt > 0, got t_end={t_end} s, dt={dt} s"
        )
    dt_min = dt / 64 if dt_min is None else dt_min
    if not 0 < dt_min <= dt:
        raise ValueError(f"need 0 < dt_min <= dt, got dt_min={dt_min} s, dt={dt} s")
    if events is not None:
        check_event_step(dt, events.dt_s, dt_min)
    comm = problem.V.mesh.comm
    bar = None
    if progress and comm.rank == 0:
        from tqdm import tqdm

        bar = tqdm(
            total=t_end - problem.t,
            unit="s",
            bar_format="{l_bar}{bar}| {n:.4g}/{total:.4g} s {postfix}",
        )
    t_start = problem.t  # every step of size h starts on the grid t_start + k h
    measured = events.measure(problem) if events is not None else 0.0
    rows, h, h_max, accepted, calm = [], dt, dt, 0, 0
    try:
        while problem.t < t_end - 1e-12 * t_end:
            remaining = t_end - problem.t
            # a last step within round-off of h is taken as h: a new step size would mean a new
            # effective operator A(dt) and its factorisation
            step = h if abs(remaining - h) <= 1e-9 * h else min(h, remaining)
            if events is not None:
                t_old, before = problem.t, _saved_state(problem)
            result = problem.step(step)
            if not result.converged:
                accepted = 0
                if events is not None and step > events.dt_s * (1 + 1e-9):
                    h = h_max = events.dt_s  # retaken as an event
                    calm = 0
                    continue
                h = step / 2
                if h < dt_min:
                    raise RuntimeError(
                        f"Newton did not converge at t = {problem.t:.6g} s even with dt = {step:.3g} s "
                        f"(minimum step {dt_min:.3g} s): {result.message or 'no message'}; "
                        f"last residual norms {result.residual_norms[-3:]} N"
                    )
                continue
            if events is not None:
                now = events.measure(problem)
                fast = comm.allreduce(abs(now - measured) > events.rate * step, op=MPI.LOR)
                if fast and step > events.dt_s * (1 + 1e-9):  # an event: retaken in fine steps
                    problem.restore_state(t_old, before)
                    h = h_max = events.dt_s
                    accepted = calm = 0
                    continue
                measured, calm = now, 0 if fast else calm + 1
                if h_max < dt and calm >= events.calm_steps and _on_grid(problem.t - t_start, dt):
                    h = h_max = dt
                    accepted = 0
            row = {"time_s": problem.t, "dt_s": step, "newton_iterations": result.iterations}
            for observe in observers:
                row.update(observe(problem))
            rows.append(row)
            if on_row is not None:
                on_row(row)
            if bar is not None:
                bar.update(step)
                bar.set_postfix(
                    {k: f"{v:.4g}" for k, v in row.items() if k != "time_s"}, refresh=False
                )
            accepted += 1
            if h < h_max and accepted >= growth_after and _on_grid(problem.t - t_start, 2 * h):
                h, accepted = min(2 * h, h_max), 0
    finally:
        if bar is not None:
            bar.close()
    return rows
