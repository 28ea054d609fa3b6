"""Timing and convergence scripts (run as ``python benchmarks/<name>.py``); ``phase_timer``
instruments the time step, ``scenarios`` holds the docs/physics.md §5 scenario functions shared with
the tests."""
