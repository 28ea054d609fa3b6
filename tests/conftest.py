"""Shared pytest set-up: the DOLFINx stack loaded in the right order first; temporary folders
that every MPI rank shares; the test cases of ``cases/``; the demos' entry points."""

import importlib.util
import os
from pathlib import Path

os.environ.setdefault("PYVISTA_OFF_SCREEN", "true")
os.environ.setdefault("MPLBACKEND", "Agg")

from common import backend  # noqa: E402,F401

import pytest  # noqa: E402
from mpi4py import MPI  # noqa: E402

DEMOS = Path(__file__).resolve().parents[1] / "demos"


@pytest.fixture(scope="session")
def shared_dir(tmp_path_factory):
    """``shared_dir(name)``: a new temporary folder, the same path on every MPI rank (made by
    rank 0; collective)."""

    def make(name: str) -> Path:
        comm = MPI.COMM_WORLD
        return Path(comm.bcast(str(tmp_path_factory.mktemp(name)) if comm.rank == 0 else None, root=0))

    return make


@pytest.fixture
def shared_tmp(shared_dir) -> Path:
    """A new temporary folder for this test, the same path on every MPI rank."""
    return shared_dir("tmp")


def _case_factory(name: str):
    def make(*overrides: str):
        from common.case import read_case
        from solver.installation.case import InstallationCase

        return InstallationCase.from_dict(read_case(name, list(overrides)))

    make.__doc__ = f"The installation case cases/{name}.toml with ``table.key=value`` overrides."
    return make


@pytest.fixture(scope="session")
def tiny_case():
    """``tiny_case(*overrides)``: the tests' tiny frictionless joint (cases/tiny.toml)."""
    return _case_factory("tiny")


@pytest.fixture(scope="session")
def quick_case():
    """``quick_case(*overrides)``: the demos' smoke-run joint (cases/quick.toml)."""
    return _case_factory("quick")


@pytest.fixture(scope="session")
def coarse_case():
    """``coarse_case(*overrides)``: the coarse frictional joint (cases/coarse.toml)."""
    return _case_factory("coarse")


@pytest.fixture(scope="session")
def scenario_case():
    """``scenario_case(*overrides)``: the coarse joint under a 1 s ramp (cases/scenario.toml)."""
    return _case_factory("scenario")


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
