"""The scenarios of the atlas (docs/physics.md §5 observations), each a function of a
:class:`~benchmarks.atlas.context.Context` returning an :class:`~benchmarks.atlas.outcome.Outcome`
(one module each in :mod:`benchmarks.atlas.criteria`)."""

import time

from benchmarks.atlas.context import Context, Scenario
from benchmarks.atlas.criteria import (
    s1_self_weight,
    s2_sequence,
    s3_amplitude,
    s4_modes,
    s5_dismount,
    s6_friction,
    s7_sweeps,
    s8_stiffening,
)
from benchmarks.atlas.outcome import Outcome

__all__ = ["SCENARIOS", "Context", "Scenario", "run_scenario"]

SCENARIOS: dict[str, Scenario] = {
    m.SCENARIO.key: m.SCENARIO
    for m in (
        s1_self_weight,
        s2_sequence,
        s3_amplitude,
        s4_modes,
        s5_dismount,
        s6_friction,
        s7_sweeps,
        s8_stiffening,
    )
}


def run_scenario(ctx: Context, key: str) -> Outcome:
    """Run scenario ``key`` (collective); its outcome is saved in ``output/key``."""
    t0 = time.perf_counter()
    outcome = SCENARIOS[key].run(ctx)
    if ctx.comm.rank == 0:
        outcome.save(ctx.output / key / "outcome.json")
        print(f"{key}: {outcome.title} ({time.perf_counter() - t0:.0f} s)", flush=True)
    return outcome
