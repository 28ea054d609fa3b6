"""Phase times and counts of ``common.timing`` on a clock the test advances: exclusive times of
nested phases, nothing recorded outside ``recording``, phases closed when they raise, reset."""

import pytest

from common import timing
from common.timing import PhaseTimes, count, recording, timed


class Clock:
    """Wall and CPU clock that move only when told [s]."""

    def __init__(self):
        self.now = 0.0

    def __call__(self) -> float:
        return self.now


@pytest.fixture
def clock(monkeypatch) -> Clock:
    clock = Clock()
    monkeypatch.setattr(timing.time, "perf_counter", clock)
    monkeypatch.setattr(timing.time, "process_time", clock)
    return clock


def test_nested_phases_are_exclusive(clock):
    @timed("inner")
    def inner(seconds: float) -> None:
        clock.now += seconds
        count("events", 2)

    @timed("outer")
    def outer(before: float, inside: float, after: float) -> None:
        """Spends ``before``, calls ``inner``, spends ``after``."""
        clock.now += before
        inner(inside)
        clock.now += after

    times = PhaseTimes()
    with recording(times):
        outer(1.0, 10.0, 2.0)
        outer(0.5, 0.25, 0.0)
    assert times.totals == {"outer": 3.5, "inner": 10.25}
    assert times.cpu == times.totals
    assert times.calls == {"outer": 2, "inner": 2}
    assert times.counts == {"events": 4}
    assert outer.__doc__ == "Spends ``before``, calls ``inner``, spends ``after``."


def test_nothing_is_recorded_outside_recording(clock):
    @timed("phase")
    def phase() -> None:
        clock.now += 1.0
        count("events")

    times = PhaseTimes()
    phase()
    with recording(times):
        pass
    phase()
    assert not times.totals and not times.calls and not times.counts


def test_a_raising_phase_is_closed_and_one_recorder_at_a_time(clock):
    @timed("failing")
    def failing() -> None:
        clock.now += 1.0
        raise ValueError("wrong input")

    @timed("outer")
    def outer() -> None:
        with pytest.raises(ValueError, match="wrong input"):
            failing()
        clock.now += 2.0

    times = PhaseTimes()
    with recording(times):
        outer()
        with pytest.raises(RuntimeError, match="already recording"):
            with recording(PhaseTimes()):
                pass
    assert times.totals == {"failing": 1.0, "outer": 2.0}


def test_reset_restarts_the_open_phases(clock):
    times = PhaseTimes()

    @timed("outer")
    def outer() -> None:
        clock.now += 5.0
        times.reset()  # e.g. a new stage announced from inside a step
        clock.now += 1.0
        count("events")

    with recording(times):
        outer()
    assert times.totals == {"outer": 1.0}
    assert times.calls == {"outer": 1} and times.counts == {"events": 1}
