"""The atlas's scenarios, one module each: the runs a scenario needs, judged against its
criterion (docs/physics.md §5), as rows of its :class:`~benchmarks.atlas.outcome.Outcome`."""
