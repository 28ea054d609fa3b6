"""Shared pytest set-up: load the DOLFINx stack in the right order first; the demos' entry
points (``demo_main``)."""

import importlib.util
import os
from pathlib import Path

os.environ.setdefault("PYVISTA_OFF_SCREEN", "true")
os.environ.setdefault("MPLBACKEND", "Agg")

from common import backend  # noqa: E402,F401

import pytest  # noqa: E402

DEMOS = Path(__file__).resolve().parents[1] / "demos"


@pytest.fixture(scope="session")
def demo_main():
    """``demo_main(name)``: the ``main(argv)`` of ``demos/<name>.py`` (loaded from its file;
    the demos are scripts, not a package)."""
    loaded = {}

    def load(name: str):
        if name not in loaded:
            spec = importlib.util.spec_from_file_location(f"demo_{name}", DEMOS / f"{name}.py")
            module = importlib.util.module_from_spec(spec)
            spec.loader.exec_module(module)
            loaded[name] = module.main
        return loaded[name]

    return load
