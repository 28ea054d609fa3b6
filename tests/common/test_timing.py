"""Phase times and counts of ``common.timing``: exclusive times of nested phases, nothing
recorded outside ``recording``, phases closed when they raise."""

import time

import pytest

from common.timing import PhaseTimes, count, recording, timed


@timed("inner")
def inner(seconds: float) -> None:
    time.sleep(seconds)
    count("events", 2)


@timed("outer")
def outer(seconds: float, inner_seconds: float) -> None:
    """Sleeps, then calls ``inner``."""
    time.sleep(seconds)
    inner(inner_seconds)


@timed("failing")
def failing() -> None:
    raise ValueError("wrong input")


def test_nested_phases_are_exclusive():
    times = PhaseTimes()
    with recording(times):
        start = time.perf_counter()
        outer(0.01, 0.2)
        wall = time.perf_counter() - start
        outer(0.01, 0.0)
    # inclusive, outer would hold both sleeps: at least 0.2 s
    assert times.totals["outer"] < 0.19
    assert times.totals["inner"] >= 0.2
    assert times.calls == {"outer": 2, "inner": 2}
    assert times.counts == {"events": 4}
    # the exclusive times of the first call partition its wall time
    assert times.totals["outer"] + times.totals["inner"] >= wall - 0.05
    assert outer.__doc__ == "Sleeps, then calls ``inner``."


def test_nothing_is_recorded_outside_recording():
    times = PhaseTimes()
    outer(0.0, 0.0)
    with recording(times):
        pass
    outer(0.0, 0.0)
    assert not times.totals and not times.calls and not times.counts


def test_a_raising_phase_is_closed_and_one_recorder_at_a_time():
    times = PhaseTimes()
    with recording(times):
        with pytest.raises(ValueError, match="wrong input"):
            failing()
        inner(0.0)
        with pytest.raises(RuntimeError, match="already recording"):
            with recording(PhaseTimes()):
                pass
    assert times.calls == {"failing": 1, "inner": 1}
    times.reset()
    assert not times.totals and not times.calls and not times.counts
