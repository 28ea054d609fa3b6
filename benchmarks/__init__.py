"""Timing and convergence scripts (run as ``python benchmarks/<name>.py``); ``phase_timer``
reports the time step's phases (recorded by ``common.timing``), ``atlas`` holds the scenario
atlas of ``scenarios.py``."""
