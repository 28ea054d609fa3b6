"""What a scenario of the atlas measured: one row per criterion, its wall time and figures,
kept as JSON beside the run's outputs and beside the page, so that the page can be rebuilt
after any subset of the scenarios has run."""

import json
from dataclasses import asdict, dataclass, field
from pathlib import Path

__all__ = ["Outcome", "Row", "verdict"]


def verdict(holds: bool) -> str:
    """The verdict of a criterion with a pass/fail test."""
    return "reproduced" if holds else "not reproduced"


@dataclass
class Row:
    """One criterion of a scenario: what is checked, the measured value (with units) and the
    verdict ("reproduced", "not reproduced", or "measured" where the criterion is a figure to
    report rather than a test)."""

    criterion: str
    measured: str
    verdict: str


@dataclass
class Outcome:
    """A scenario's result on ``joint`` (a description of the case): ``runs`` the wall time [s]
    on ``ranks`` MPI ranks of each run it used (by name: runs shared between scenarios have the
    same name); ``figures``: PNG files (paths relative to the outcome's folder)."""

    key: str
    title: str
    joint: str
    rows: list[Row]
    runs: dict[str, float]
    ranks: int
    figures: list[str] = field(default_factory=list)

    @property
    def wall_s(self) -> float:
        """Wall time [s] of the runs the scenario needs."""
        return sum(self.runs.values())

    def save(self, path: Path) -> None:
        """Write the outcome to the JSON file ``path``."""
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps(asdict(self), indent=1))

    @classmethod
    def load(cls, path: Path) -> "Outcome | None":
        """The outcome in the JSON file ``path`` (None where there is none)."""
        if not path.exists():
            return None
        data = json.loads(path.read_text())
        data["rows"] = [Row(**r) for r in data["rows"]]
        return cls(**data)
