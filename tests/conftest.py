"""Shared pytest set-up: the DOLFINx stack loaded in the right order first; the ``--slow``
option and the serial run's skip of the ``parallel_only`` tests; garbage collection and PETSc
clean-up after every test; temporary folders that every MPI rank shares; the test cases of
``cases/``; the demos' entry points."""

import gc
import importlib.util
import os
from pathlib import Path

os.environ.setdefault("PYVISTA_OFF_SCREEN", "true")
os.environ.setdefault("MPLBACKEND", "Agg")

from common import backend  # noqa: E402,F401

import pytest  # noqa: E402
from mpi4py import MPI  # noqa: E402
from petsc4py import PETSc  # noqa: E402

from solver.installation.model import free_dropped_joints  # noqa: E402

DEMOS = Path(__file__).resolve().parents[1] / "demos"


def pytest_addoption(parser):
    parser.addoption(
        "--slow",
        action="store_true",
        help="also run the tests marked slow (minutes to an hour each)",
    )


def pytest_collection_modifyitems(config, items):
    slow = pytest.mark.skip(reason="marked slow: runs with pytest --slow")
    serial = pytest.mark.skip(
        reason="marked parallel_only: runs with mpiexec -n 2 python -m mpi4py -m pytest -m mpi"
    )
    for item in items:
        if item.get_closest_marker("slow") and not config.getoption("--slow"):
            item.add_marker(slow)
        if item.get_closest_marker("parallel_only"):
            if not item.get_closest_marker("mpi"):
                raise pytest.UsageError(f"{item.nodeid}: parallel_only needs the mark mpi too")
            if MPI.COMM_WORLD.size == 1:
                item.add_marker(serial)


@pytest.fixture(autouse=True)
def collect_garbage():
    """After each test: free the Python objects it left and the PETSc objects whose collective
    destruction they deferred (the same on every rank), those of the joints it set up included."""
    yield
    gc.collect()
    PETSc.garbage_cleanup(MPI.COMM_WORLD)
    free_dropped_joints()


@pytest.fixture(scope="session")
def shared_dir(tmp_path_factory):
    """``shared_dir(name)``: a new temporary folder, the same path on every MPI rank (made by
    rank 0; collective)."""

    def make(name: str) -> Path:
        comm = MPI.COMM_WORLD
        return Path(
            comm.bcast(str(tmp_path_factory.mktemp(name)) if comm.rank == 0 else None, root=0)
        )

    return make


@pytest.fixture
def shared_tmp(shared_dir) -> Path:
    """A new temporary folder for this test, the same path on every MPI rank."""
    return shared_dir("tmp")


def _case_fixture(name: str, what: str):
    """A session fixture ``<name>_case(*overrides)``: the installation case cases/<name>.toml
    with ``table.key=value`` overrides."""

    @pytest.fixture(scope="session")
    def fixture():
        from common.case import read_case
        from solver.installation.case import InstallationCase

        return lambda *overrides: InstallationCase.from_dict(read_case(name, list(overrides)))

    fixture.__doc__ = f"``{name}_case(*overrides)``: {what} (cases/{name}.toml)."
    return fixture


tiny_case = _case_fixture("tiny", "the tests' tiny frictionless joint")
quick_case = _case_fixture("quick", "the demos' smoke-run joint")
coarse_case = _case_fixture("coarse", "the coarse frictional joint")


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
