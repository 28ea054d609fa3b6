"""Where the atlas's scenarios run (:class:`Context`: case, overrides, output folder, the
installation run they read) and what a scenario is (:class:`Scenario`)."""

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from mpi4py import MPI

from benchmarks.atlas.outcome import Outcome, Row
from benchmarks.atlas.self_weight import self_weight_run
from common.case import read_case
from solver.installation.case import InstallationCase

__all__ = ["Context", "Scenario", "events_text"]


@dataclass
class Context:
    """Where and on what the scenarios run: the case (preset name or file) with its overrides,
    the output folder (one sub-folder per scenario and per shared run)."""

    comm: MPI.Comm
    case_name: str
    overrides: list[str]
    output: Path
    #: output folder of an installation run of the case (``demos/install.py``): S2 and S4
    #: read its stages, S3, S4 and S5 also run from its last checkpoint, S8 also has the
    #: frequencies there
    installed: Path | None = None

    def case(self, extra: list[str] = ()) -> InstallationCase:
        return InstallationCase.from_dict(read_case(self.case_name, [*self.overrides, *extra]))

    def joint(self) -> str:
        """The joint in words (for the page)."""
        c = self.case()
        return (
            f"`{self.case_name}` {' '.join(self.overrides)}: {c.mesh.n_circumferential} around, "
            f"{1e3 * c.mesh.axial_size:g} mm axially ({1e3 * c.mesh.contact_axial_size:g} mm in "
            f"the contact zone, {1e3 * c.mesh.contact_zone_above:g} mm above the TP's lower "
            f"edge), degree {c.contact.degree}, mu at the "
            + (
                "previous step's slip speed"
                if c.contact.lagged_friction
                else "step's own slip speed"
            )
        ).replace("` :", "`:")

    def self_weight(
        self, name: str, extra: list[str] = (), modes_at_s=(), until_s: float | None = None
    ) -> dict[str, Any]:
        return self_weight_run(
            self.comm,
            self.case_name,
            [*self.overrides, *extra],
            self.output / "runs" / name,
            modes_at_s,
            until_s,
        )

    def reference(self) -> dict[str, Any]:
        """The case's self-weight stage with the modes at half the load and at its end (S1, S6,
        S8 share it)."""
        sw = self.case().self_weight
        return self.self_weight("reference", modes_at_s=(0.5 * sw.ramp_time_s, sw.duration_s))

    def figure(self, key: str, name: str) -> tuple[Path, str]:
        """Path of figure ``name`` of scenario ``key`` and its path relative to the folder."""
        folder = self.output / key
        if self.comm.rank == 0:
            folder.mkdir(parents=True, exist_ok=True)
        return folder / name, name

    def outcome(
        self,
        scenario: "Scenario",
        rows: list[Row],
        runs: dict[str, dict],
        figure_names: list[str],
    ) -> Outcome:
        """The outcome of ``scenario`` on this joint with the wall times of the runs it used."""
        return Outcome(
            scenario.key,
            scenario.title,
            self.joint(),
            rows,
            {r["name"]: r["wall_s"] for r in runs.values()},
            self.comm.size,
            figure_names,
        )


@dataclass(frozen=True)
class Scenario:
    """A scenario: its key (S1, S2, ...), its title, its criterion, and the function that runs it."""

    key: str
    title: str
    criterion: str
    run: Callable[[Context], Outcome]
    #: it reads an installation run of the case (``--installed``)
    installed: bool = False


def events_text(r: dict[str, Any]) -> str:
    """The stick-slip events of a self-weight run in words: their count and sizes [um]."""
    sizes = ", ".join(f"{1e3 * e:.0f}" for e in r["events_mm"])
    n = len(r["events_mm"])
    return f"{n} event{'' if n == 1 else 's'} ({sizes} um)"
