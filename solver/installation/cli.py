"""The command line shared by the demos.

Every demo reads a case: ``--case NAME`` (a preset in ``cases/`` or a TOML file; each demo has
its default case), with ``--set table.key=value`` overrides and, for the installation-type
demos, named shorthands for common keys (``--mu-s 0.6`` is ``--set friction.mu_s=0.6``).
``--quick`` is ``--case`` of the demo's quick preset (a smoke run, what CTest runs); giving
another ``--case`` with it is an error. Later wins: the case file (with the files it extends),
the named options, ``--set``. ``--output`` is the output folder.

Exit codes: bad options, a case that does not check, or an output folder that cannot be
created or written give ``error: ...`` on stderr and 2 before any computation; a time loop
that gives up gives 1 (results up to there are in the output folder).
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import Any

from mpi4py import MPI

from common.case import read_case, resolve_case_path
from solver.installation.case import InstallationCase
from solver.installation.runner import Installation

#: named options -> (case key, type, help)
NAMED = {
    "mesh_size": ("mesh.axial_size", float, "axial element size [m]"),
    "n_circumferential": ("mesh.n_circumferential", int, "elements around (multiple of 4)"),
    "degree": ("contact.degree", int, "Lagrange degree of the displacement"),
    "mu_s": ("friction.mu_s", float, "static friction coefficient"),
    "mu_d": ("friction.mu_d", float, "dynamic friction coefficient"),
    "d_c": ("friction.d_c", float, "friction decay coefficient [s/m]"),
    "damping": ("damping.model", str, "damping model: rayleigh | modal"),
    "zeta": ("damping.zeta", float, "damping ratio"),
    "forcing": ("vibration.forcing", str, "vibration force at: eccentric | face | shaker"),
    "direction": ("vibration.direction", str, "vibration force direction: axial | lateral | both"),
    "lateral_fraction": ("vibration.lateral_fraction", float, "lateral part with --direction both"),
    "amplitude": (
        "vibration.amplitude_N",
        float,
        "force amplitude of the modal/control stages [N]",
    ),
    "shaker_height": (
        "vibration.shaker_height_m",
        float,
        "shaker: height above the TP lower end [m]",
    ),
    "angle": ("vibration.angle_deg", float, "circumferential position of the point force [deg]"),
    "stage_duration": ("vibration.stage_duration_s", float, "duration of each vibration stage [s]"),
    "n_frequencies": (
        "vibration.n_frequencies",
        int,
        "number of ranked natural frequencies excited",
    ),
    "steps_per_period": ("time.steps_per_period", int, "time steps per excitation period"),
}
#: the named options of the installation-type demos that add options of their own
INSTALLATION_OPTIONS = (
    "mesh_size",
    "n_circumferential",
    "mu_s",
    "mu_d",
    "d_c",
    "damping",
    "forcing",
    "direction",
    "steps_per_period",
)


def case_parser(
    description: str, output: str, default_case: str, quick_case: str
) -> argparse.ArgumentParser:
    """``--case``, ``--set``, ``--quick`` and ``--output``: the options of every demo."""
    p = argparse.ArgumentParser(description=description, allow_abbrev=False)
    p.set_defaults(default_case=default_case, quick_case=quick_case, named=())
    p.add_argument(
        "--case", help=f"case: a preset name in cases/ or a TOML file (default: {default_case})"
    )
    p.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="TABLE.KEY=VALUE",
        help="override a case entry, e.g. friction.mu_s=0.6 (repeatable)",
    )
    p.add_argument(
        "--quick",
        action="store_true",
        help=f"smoke run: --case {quick_case} (what CTest runs; not physics)",
    )
    p.add_argument("--output", default=output, help=f"output folder (default: {output})")
    return p


def parser(
    description: str,
    output: str,
    default_case: str,
    quick_case: str,
    named: Iterable[str] = INSTALLATION_OPTIONS,
) -> argparse.ArgumentParser:
    """The options of the installation-type demos: ``case_parser``'s, the ``named`` shorthands
    and ``--no-progress``; a demo adds its own."""
    p = case_parser(description, output, default_case, quick_case)
    p.set_defaults(named=tuple(named))
    for name in named:
        _, kind, text = NAMED[name]
        p.add_argument("--" + name.replace("_", "-"), type=kind, help=text)
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    return p


def case_name(args: argparse.Namespace) -> str:
    """The case of the command line: ``--case``, the quick preset with ``--quick``, else the
    demo's default (ValueError for ``--quick`` with another ``--case``)."""
    if not args.quick:
        return args.case or args.default_case
    if (
        args.case is not None
        and resolve_case_path(args.case).resolve() != resolve_case_path(args.quick_case).resolve()
    ):
        raise ValueError(
            f"--quick is --case {args.quick_case}; it cannot be combined with --case {args.case}"
        )
    return args.quick_case


def overrides(
    args: argparse.Namespace, before: Iterable[str] = (), after: Iterable[str] = ()
) -> list[str]:
    """Case overrides: a demo's ``before`` the named options and --set (which win over them), then
    the named options, --set, and a demo's ``after`` them (which win over --set)."""
    items = list(before)
    for name in args.named:
        value = vars(args)[name]
        if value is not None:
            key = NAMED[name][0]
            items.append(f"{key}={value!r}" if isinstance(value, str) else f"{key}={value}")
    return items + list(args.set) + list(after)


def read(
    args: argparse.Namespace, before: Iterable[str] = (), after: Iterable[str] = ()
) -> dict[str, Any]:
    """The case dict of the command line (ValueError on any problem)."""
    return read_case(case_name(args), overrides(args, before, after))


def load_case(
    args: argparse.Namespace,
    before: Iterable[str] = (),
    after: Iterable[str] = (),
    edit: Callable[[dict[str, Any]], None] | None = None,
) -> InstallationCase:
    """The checked installation case (ValueError on any problem); ``edit`` may change the case
    dict first (e.g. put in a generated [[schedule]])."""
    data = read(args, before, after)
    if edit is not None:
        edit(data)
    return InstallationCase.from_dict(data)


def prepare_output(comm: MPI.Comm, folder: str | Path) -> Path:
    """Create the output folder and check that it takes files (collective); ValueError naming the
    folder if not."""
    folder = Path(folder)
    problem = None
    if comm.rank == 0:
        probe = folder / ".write-test"
        try:
            folder.mkdir(parents=True, exist_ok=True)
            probe.write_text("")
            probe.unlink()
        except OSError as e:
            problem = (
                f"output folder {str(folder)!r} cannot be created or written: {e.strerror or e}"
            )
    problem = comm.bcast(problem, root=0)
    if problem is not None:
        raise ValueError(problem)
    return folder


def fail(comm: MPI.Comm, message: str) -> int:
    """Print ``error: message`` (rank 0) and return the exit code 2."""
    if comm.rank == 0:
        print(f"error: {message}", file=sys.stderr, flush=True)
    return 2


def run(
    comm: MPI.Comm,
    case: InstallationCase,
    output: str | Path,
    progress: bool = True,
    log: Callable[[str], None] | None = None,
) -> tuple[Installation, int]:
    """Run the installation pipeline of ``case``; returns the runner and the exit code
    (0 done, 1 stopped: the time loop gave up, or the modal stage found fewer ranked
    frequencies than the schedule asks for; results up to there are in ``output``)."""
    runner = Installation(comm, case, output, log=log, progress=progress)
    try:
        runner.run()
    except (RuntimeError, ValueError) as e:  # Newton failed at the minimum step; a 'ranked k'
        if comm.rank == 0:  # stage beyond the frequencies the modal stage found
            print(
                f"\nrun stopped: {e}\nresults up to this point are in {output}",
                file=sys.stderr,
                flush=True,
            )
        return runner, 1
    return runner, 0


def amplitude(text: str) -> float | str:
    """A force amplitude given on the command line: "eccentric" (the motors' 0.3632 f^2 N) or
    a force [N]; ValueError otherwise."""
    if text == "eccentric":
        return text
    try:
        return float(text)
    except ValueError:
        raise ValueError(f"--amplitude must be 'eccentric' or a force in N, got {text!r}") from None


def say(comm: MPI.Comm) -> Callable[[str], None]:
    """print on rank 0, flushed (progress messages)."""
    return lambda s: print(s, flush=True) if comm.rank == 0 else None
