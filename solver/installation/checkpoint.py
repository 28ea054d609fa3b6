"""Checkpoint and resume of a time integration with frictional contact (per-rank files).

A checkpoint is a folder with

* ``rank<r>.npz`` on every rank: ``Elastodynamics.state_arrays()``, the rank's local arrays
  (owned and ghost entries) of u, v, a [m, m/s, m/s^2], the contact residual at u_n (needed by generalised-alpha)
  [N], and the contact memory of the slave points on this rank (slip velocity of
  the last step [m/s], the paired master facet, which the pairing keeps while it
  is as close as any other, the point's coordinates on that facet, from which the
  next projection starts, and its contact status at the end of the last step, which
  chooses the next step's Newton start);
* ``manifest.json`` (rank 0): rank count, time [s], and whatever progress record the
  caller passes (stage index, history rows, ...).

The arrays are only meaningful for the same mesh partition, so a resume must use the
same rank count and the same mesh/discretisation options; the rank count and the
array sizes are checked. A checkpoint is written to a temporary folder and renamed,
so a run killed while writing leaves the previous checkpoint intact.
"""

import json
import shutil
from pathlib import Path
from typing import Any

import numpy as np
from mpi4py import MPI

from solver.dynamics.elastodynamics import Elastodynamics

MANIFEST = "manifest.json"


def _plain(value: Any) -> Any:
    """numpy scalars -> Python numbers for JSON."""
    if isinstance(value, np.generic):
        return value.item()
    raise TypeError(f"cannot write {type(value).__name__} to a checkpoint manifest")


def _rank_file(folder: Path, rank: int) -> Path:
    return folder / f"rank{rank}.npz"


def save(folder: str | Path, problem: Elastodynamics, record: dict[str, Any]) -> None:
    """Write the state of ``problem`` (``Elastodynamics.state_arrays``) and ``record``."""
    comm: MPI.Comm = problem.V.mesh.comm
    folder = Path(folder)
    tmp = folder.with_name(folder.name + ".tmp")
    if comm.rank == 0:
        shutil.rmtree(tmp, ignore_errors=True)
        tmp.mkdir(parents=True)
    comm.barrier()
    np.savez(_rank_file(tmp, comm.rank), **problem.state_arrays())
    if comm.rank == 0:
        manifest = {"ranks": comm.size, "time_s": problem.t, **record}
        (tmp / MANIFEST).write_text(json.dumps(manifest, indent=1, default=_plain))
    comm.barrier()
    if comm.rank == 0:
        shutil.rmtree(folder, ignore_errors=True)
        tmp.rename(folder)
    comm.barrier()


def exists(folder: str | Path, comm: MPI.Comm) -> bool:
    """Whether a complete checkpoint is present (same answer on all ranks)."""
    return comm.bcast((Path(folder) / MANIFEST).is_file() if comm.rank == 0 else None, root=0)


def read_manifest(folder: str | Path, comm: MPI.Comm) -> dict[str, Any]:
    """The manifest of a checkpoint; ValueError if missing or written by another rank count."""
    folder = Path(folder)
    manifest = None
    if comm.rank == 0:
        path = folder / MANIFEST
        manifest = json.loads(path.read_text()) if path.is_file() else None
    manifest = comm.bcast(manifest, root=0)
    if manifest is None:
        raise ValueError(f"no checkpoint in {folder} (nothing to resume)")
    if manifest["ranks"] != comm.size:
        raise ValueError(
            f"checkpoint {folder} was written by {manifest['ranks']} rank(s); "
            f"resume with the same count (mpirun -n {manifest['ranks']}), not {comm.size}"
        )
    return manifest


def restore(folder: str | Path, problem: Elastodynamics) -> dict[str, Any]:
    """Load the state into ``problem`` (built exactly as when saving) and return the manifest."""
    comm: MPI.Comm = problem.V.mesh.comm
    manifest = read_manifest(folder, comm)
    data = np.load(_rank_file(Path(folder), comm.rank))
    expected = problem.state_arrays()
    required = [key for key in expected if key != "contact_status"]
    missing = [key for key in required if key not in data.files]
    if comm.allreduce(bool(missing), op=MPI.LOR):
        raise ValueError(
            f"checkpoint {folder} lacks {', '.join(missing) or 'arrays on another rank'} (written by "
            "an older version of the code?): rerun without --resume"
        )
    arrays = {key: data[key] for key in data.files}
    ok = all(arrays[key].shape == expected[key].shape for key in required)
    if comm.allreduce(not ok, op=MPI.LOR):
        raise ValueError(
            f"checkpoint {folder} does not match this discretisation "
            "(different mesh, contact surfaces or degree than when it was written)"
        )
    problem.restore_state(float(manifest["time_s"]), arrays)
    return manifest
