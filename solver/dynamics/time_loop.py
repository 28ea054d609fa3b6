"""The time loop: integrate an ``Elastodynamics`` problem over an interval with step cutting.

On Newton failure the step is halved and retried, and grows back after a few accepted
steps (:func:`run`); observers add their values (keys carry units) to each step's row.
"""

from collections.abc import Callable, Sequence

from solver.dynamics.elastodynamics import Elastodynamics

Observer = Callable[[Elastodynamics], dict[str, float]]


def run(
    problem: Elastodynamics,
    t_end: float,
    dt: float,
    dt_min: float | None = None,
    observers: Sequence[Observer] = (),
    on_row: Callable[[dict[str, float]], None] | None = None,
    progress: bool = True,
    growth_after: int = 4,
) -> list[dict[str, float]]:
    """Integrate from problem.t to t_end [s] with nominal step dt [s].

    On Newton failure the step is halved and retried; after ``growth_after`` accepted
    steps it doubles again (up to dt). Below dt_min (default dt/64) a RuntimeError
    names the time and step. Each accepted step records time_s, dt_s, newton_iterations
    and every observer's values (keys carry units, e.g. settlement_mm); each row is passed to
    ``on_row`` as it is produced (e.g. ``solver.post.csv.CsvWriter.write``). Returns the rows.
    """
    if not (t_end > problem.t and dt > 0):
        raise ValueError(
            f"need t_end > t = {problem.t} s and dt > 0, got t_end={t_end} s, dt={dt} s"
        )
    dt_min = dt / 64 if dt_min is None else dt_min
    if not 0 < dt_min <= dt:
        raise ValueError(f"need 0 < dt_min <= dt, got dt_min={dt_min} s, dt={dt} s")
    comm = problem.V.mesh.comm
    bar = None
    if progress and comm.rank == 0:
        from tqdm import tqdm

        bar = tqdm(
            total=t_end - problem.t,
            unit="s",
            bar_format="{l_bar}{bar}| {n:.4g}/{total:.4g} s {postfix}",
        )
    rows, h, accepted = [], dt, 0
    try:
        while problem.t < t_end - 1e-12 * t_end:
            remaining = t_end - problem.t
            # a last step within round-off of h is taken as h: a new step size would mean a new
            # effective operator A(dt) and its factorisation
            step = h if abs(remaining - h) <= 1e-9 * h else min(h, remaining)
            result = problem.step(step)
            if not result.converged:
                h = step / 2
                accepted = 0
                if h < dt_min:
                    raise RuntimeError(
                        f"Newton did not converge at t = {problem.t:.6g} s even with dt = {step:.3g} s "
                        f"(minimum step {dt_min:.3g} s): {result.message or 'no message'}; "
                        f"last residual norms {result.residual_norms[-3:]} N"
                    )
                continue
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
            if h < dt and accepted >= growth_after:
                h, accepted = min(2 * h, dt), 0
    finally:
        if bar is not None:
            bar.close()
    return rows
