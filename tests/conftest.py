"""Shared pytest set-up: load the DOLFINx stack in the right order first."""

import os

os.environ.setdefault("PYVISTA_OFF_SCREEN", "true")
os.environ.setdefault("MPLBACKEND", "Agg")

from common import backend  # noqa: E402,F401
