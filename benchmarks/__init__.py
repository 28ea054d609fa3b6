"""Timing and convergence scripts (run as ``python benchmarks/<name>.py``); ``phase_timer``
instruments the time step, ``branches`` holds the docs/physics.md §5 branch functions shared with
the tests, ``atlas`` the scenario atlas of ``scenarios.py``."""
