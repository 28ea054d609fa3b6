"""Command line shared by the installation-type demos (sweep, dismount, imperfections, parameter
study): a case file plus ``--set table.key=value`` overrides, named shorthands for the common
keys, ``--quick`` and ``--output``; bad options give ``error: ...`` and exit code 2 before any
computation, a time loop that gives up gives exit code 1 (as ``demos/install.py``).

Override order (later wins): the demo's defaults, ``--quick``, the named options, ``--set``.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

from mpi4py import MPI

from common.case import read_case
from solver.installation.runner import Installation
from solver.installation.case import InstallationCase

#: the very coarse joint (8 around, 0.25 m) with 10 mm axial elements in the contact zone
#: (the contact band is about 20 x the settlement high) and the contact settings with which
#: the frictional stages converge on it (docs/contact.md, docs/install.md: the default run of
#: demos/install.py)
COARSE_FRICTIONAL = [
    "mesh.n_circumferential=8",
    "mesh.axial_size=0.25",
    "mesh.contact_axial_size=0.01",
    "contact.theta=-1",
    "contact.gamma0=1.0",
    "contact.max_gap_change=1e-5",
    "contact.max_backtracks=4",
    "time.rho_inf=0.0",
    "self_weight.hold_s=0.0",
    "time.steps_per_period=16",
]

#: --quick: the tiny joint of the pipeline tests (12 around, 0.2 m) with the landing settings
#: of COARSE_FRICTIONAL (skew-symmetric Nitsche, gamma0 = 1, gap-limited Newton steps) and the
#: case's friction, a 12 ms self-weight ramp (the TP is still sliding at its end), short stages,
#: no ParaView files; a smoke run of the demo, not physics
QUICK = [
    "mesh.n_circumferential=12",
    "mesh.axial_size=0.2",
    "mesh.contact_axial_size=0.0",
    "contact.theta=-1",
    "contact.gamma0=1.0",
    "contact.max_gap_change=1e-5",
    "self_weight.ramp_time_s=0.012",
    "self_weight.hold_s=0.002",
    "self_weight.dt_s=0.002",
    "vibration.n_modes=4",
    "vibration.n_frequencies=1",
    "vibration.lead_in_hz=[]",
    "time.steps_per_period=4",
    "output.checkpoint_every=50",
    "output.paraview=false",
]

#: named options -> case keys
NAMED = {
    "mesh_size": ("mesh.axial_size", float, "axial element size [m]"),
    "n_circumferential": ("mesh.n_circumferential", int, "elements around (multiple of 4)"),
    "mu_s": ("friction.mu_s", float, "static friction coefficient"),
    "mu_d": ("friction.mu_d", float, "dynamic friction coefficient"),
    "d_c": ("friction.d_c", float, "friction decay coefficient [s/m]"),
    "damping": ("damping.model", str, "damping model: rayleigh | modal"),
    "forcing": ("vibration.forcing", str, "vibration force at: eccentric | face | shaker"),
    "direction": ("vibration.direction", str, "vibration force direction: axial | lateral | both"),
    "steps_per_period": ("time.steps_per_period", int, "time steps per excitation period"),
}


def parser(description: str, output: str) -> argparse.ArgumentParser:
    """The common options; a demo adds its own."""
    p = argparse.ArgumentParser(description=description)
    p.add_argument("--case", default="scaled", help="case file or preset name in cases/")
    p.add_argument("--set", action="append", default=[], metavar="TABLE.KEY=VALUE",
                   help="override a case entry, e.g. friction.mu_s=0.3 (repeatable)")
    for name, (_, kind, text) in NAMED.items():
        p.add_argument("--" + name.replace("_", "-"), type=kind, help=text)
    p.add_argument("--quick", action="store_true",
                   help="smoke run on the tiny joint with very short stages "
                   "(what CTest runs; not physics)")
    p.add_argument("--output", default=output, help="output folder")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    return p


def overrides(args: argparse.Namespace, defaults: list[str], quick: list[str]) -> list[str]:
    """Case overrides: defaults, then --quick's, then the named options, then --set."""
    items = list(defaults) + (list(quick) if args.quick else [])
    for name, (key, _, _) in NAMED.items():
        value = getattr(args, name)
        if value is not None:
            items.append(f"{key}={value!r}" if isinstance(value, str) else f"{key}={value}")
    return items + list(args.set)


def fail(comm: MPI.Comm, message: str) -> int:
    """Print ``error: message`` (rank 0) and return the exit code 2."""
    if comm.rank == 0:
        print(f"error: {message}", file=sys.stderr, flush=True)
    return 2


def load_case(
    args: argparse.Namespace,
    items: list[str],
    edit: Callable[[dict[str, Any]], None] | None = None,
) -> InstallationCase:
    """The checked case (ValueError on any problem); ``edit`` may change the case dict first
    (e.g. put in a generated [[schedule]])."""
    data = read_case(args.case, items)
    if edit is not None:
        edit(data)
    return InstallationCase.from_dict(data)


def run(comm: MPI.Comm, case: InstallationCase, output: str | Path, progress: bool = True,
        log: Callable[[str], None] | None = None) -> tuple[Installation, int]:
    """Run the installation pipeline of ``case``; returns the runner and the exit code
    (0 done, 1 stopped: the time loop gave up, or the modal stage found fewer ranked
    frequencies than the schedule asks for; results up to there are in ``output``)."""
    runner = Installation(comm, case, output, log=log, progress=progress)
    try:
        runner.run()
    except (RuntimeError, ValueError) as e:  # Newton failed at the minimum step; a 'ranked k'
        if comm.rank == 0:  # stage beyond the frequencies the modal stage found
            print(f"\nrun stopped: {e}\nresults up to this point are in {output}",
                  file=sys.stderr, flush=True)
        return runner, 1
    return runner, 0


def say(comm: MPI.Comm) -> Callable[[str], None]:
    """print on rank 0, flushed (progress messages)."""
    return lambda s: print(s, flush=True) if comm.rank == 0 else None
