"""Timing and convergence scripts (run as ``python benchmarks/<name>.py``); ``phase_timer``
instruments the time step, ``atlas`` holds the scenario atlas of ``scenarios.py``."""
