"""Runs of the atlas kept as ``run.json`` in their folders: a later call with the same request
reads the kept run (or what it has so far) instead of running it again."""

import json
from pathlib import Path
from typing import Any

from mpi4py import MPI

__all__ = ["keep_run", "kept_run"]


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
