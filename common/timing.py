"""Wall and CPU time per phase of a computation, and event counts, for profiling.

Solver functions name their phase with the decorator :func:`timed` and report counts (inner
iterations, factorisations) with :func:`count`. Both do nothing unless a :class:`PhaseTimes`
is recording (:func:`recording`), so the solver pays one test per call. Times are
*exclusive*: a phase called inside another is not counted in the outer one. Times are the
calling rank's; nothing here communicates. One recorder at a time, for the process (not per
thread).

    times = PhaseTimes()
    with recording(times):
        run()
    times.totals["pairing"], times.calls["pairing"], times.counts["gmres"]
"""

import functools
import time
from collections import defaultdict
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import ParamSpec, TypeVar

__all__ = ["PhaseTimes", "count", "recording", "timed"]

P = ParamSpec("P")
R = TypeVar("R")


class PhaseTimes:
    """Exclusive wall and process CPU time [s] and number of calls per phase, and counts per
    event name, accumulated while recording."""

    def __init__(self) -> None:
        self.totals: dict[str, float] = defaultdict(float)  #: wall time per phase [s]
        self.cpu: dict[str, float] = defaultdict(float)  #: process CPU time per phase [s]
        self.calls: dict[str, int] = defaultdict(int)
        self.counts: dict[str, int] = defaultdict(int)
        # open phases: [phase, wall start, CPU start, wall and CPU time of nested phases]
        self._open: list[list] = []

    def enter(self, phase: str) -> None:
        """Open ``phase`` (inside the phase open now, if any)."""
        self._open.append([phase, time.perf_counter(), time.process_time(), 0.0, 0.0])

    def exit(self) -> None:
        """Close the phase opened last: add its time without its nested phases."""
        phase, start, cpu_start, nested, nested_cpu = self._open.pop()
        elapsed, cpu = time.perf_counter() - start, time.process_time() - cpu_start
        self.totals[phase] += elapsed - nested
        self.cpu[phase] += cpu - nested_cpu
        self.calls[phase] += 1
        if self._open:
            self._open[-1][3] += elapsed
            self._open[-1][4] += cpu

    def reset(self) -> None:
        """Zero the times, calls and counts; phases open now count from here."""
        for table in (self.totals, self.cpu, self.calls, self.counts):
            table.clear()
        now, cpu_now = time.perf_counter(), time.process_time()
        for record in self._open:
            record[1:] = [now, cpu_now, 0.0, 0.0]


_active: PhaseTimes | None = None


@contextmanager
def recording(times: PhaseTimes) -> Iterator[PhaseTimes]:
    """Record into ``times`` inside the ``with`` block (one recorder at a time)."""
    global _active
    if _active is not None:
        raise RuntimeError("a PhaseTimes is already recording")
    _active = times
    try:
        yield times
    finally:
        _active = None


def timed(phase: str) -> Callable[[Callable[P, R]], Callable[P, R]]:
    """Decorator: calls of the function count as ``phase`` while a recorder is active."""

    def decorate(function: Callable[P, R]) -> Callable[P, R]:
        @functools.wraps(function)
        def wrapper(*args: P.args, **kwargs: P.kwargs) -> R:
            times = _active
            if times is None:
                return function(*args, **kwargs)
            times.enter(phase)
            try:
                return function(*args, **kwargs)
            finally:
                times.exit()

        return wrapper

    return decorate


def count(event: str, n: int = 1) -> None:
    """Add ``n`` to the count of ``event`` while a recorder is active."""
    if _active is not None:
        _active.counts[event] += n
