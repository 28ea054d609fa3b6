"""The CSV files of a run: one writer for tables written at once and for histories written
row by row as a run goes (rank 0 writes; the header names the columns, which carry units).

Floats are written with ``digits`` significant digits (``None``: Python's shortest exact
form), everything else as ``str``. Rows are mappings (column -> value) or sequences in
column order.
"""

import csv
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any

__all__ = ["CsvWriter", "format_value", "write_csv"]


def format_value(value: Any, digits: int | None = 10) -> str:
    """A table entry: a float with ``digits`` significant digits, anything else as ``str``."""
    if digits is not None and isinstance(value, float):
        return f"{value:.{digits}g}"
    return str(value)


class CsvWriter:
    """A CSV file written row by row on rank 0 of ``comm`` (every rank without one), flushed
    after each row so that a killed run leaves its rows so far.

    ``columns``: the header; ``None`` takes the keys of the first row written. ``rows``: rows
    already known, written first (e.g. a resumed run's history). Parent folders are created.
    """

    def __init__(
        self,
        path: str | Path,
        columns: Sequence[str] | None = None,
        comm=None,
        rows: Iterable = (),
        digits: int | None = 10,
    ):
        self.path = Path(path)
        self.columns = None if columns is None else list(columns)
        self.digits = digits
        self._writes = comm is None or comm.rank == 0
        self._file = None
        if self.columns is not None:
            self._open()
        for row in rows:
            self.write(row)

    def _open(self) -> None:
        if not self._writes:
            return
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._file = open(self.path, "w", newline="")
        self._writer = csv.writer(self._file)
        self._writer.writerow(self.columns)
        self._file.flush()

    def write(self, row: Mapping[str, Any] | Sequence[Any]) -> None:
        if self.columns is None:
            self.columns = list(row)
            self._open()
        if self._file is not None:
            values = [row[c] for c in self.columns] if isinstance(row, Mapping) else row
            self._writer.writerow([format_value(v, self.digits) for v in values])
            self._file.flush()

    def close(self) -> None:
        if self._file is not None:
            self._file.close()
            self._file = None

    def __enter__(self) -> "CsvWriter":
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def write_csv(
    path: str | Path, columns: Sequence[str], rows: Iterable, comm=None, digits: int | None = 10
) -> None:
    """The whole table at once (rank 0 of ``comm`` writes)."""
    with CsvWriter(path, columns, comm, rows, digits):
        pass
