"""Runs of the atlas kept as ``run.json`` in their folders: a later call with the same request
reads the kept run (or what it has so far) instead of running it again."""

import functools
import json
from collections.abc import Callable
from pathlib import Path
from typing import Any, ParamSpec, TypeVar

from mpi4py import MPI

from solver.installation.model import free_dropped_joints

__all__ = ["frees_joints", "keep_run", "kept_run"]

P = ParamSpec("P")
R = TypeVar("R")


def frees_joints(run: Callable[P, R]) -> Callable[P, R]:
    """``run`` (an atlas run, collective), then the PETSc objects of the joints it set up freed
    (``free_dropped_joints``): a process that makes one run after another holds one joint at a
    time."""

    @functools.wraps(run)
    def run_and_free(*args: P.args, **kwargs: P.kwargs) -> R:
        result = run(*args, **kwargs)
        free_dropped_joints()
        return result

    return run_and_free


def kept_run(folder: Path, request: dict[str, Any]) -> dict[str, Any] | None:
    """The run kept in ``folder``/run.json if it was made for ``request``, else None."""
    path = folder / "run.json"
    if path.exists():
        kept = json.loads(path.read_text())
        if kept["request"] == request:
            return kept
    return None


def keep_run(comm: MPI.Comm, folder: Path, result: dict[str, Any]) -> None:
    """Write ``result`` (with its ``request``) to ``folder``/run.json (rank 0)."""
    if comm.rank == 0:
        folder.mkdir(parents=True, exist_ok=True)
        (folder / "run.json").write_text(json.dumps(result))
