"""Flight logs on disk: one CSV row per sensor sample, flushed as it is written.

Because every row is flushed, an interrupted or crashed flight leaves a readable file holding
every row up to the interruption.  Columns are :data:`robosoc.control.flight.ROW_FIELDS`.
"""

from __future__ import annotations

from pathlib import Path
from types import TracebackType

import numpy as np

from robosoc.control.flight import ROW_FIELDS
from robosoc.output_files import open_in_place


class CsvFlightLog:
    """Append-only CSV writer of flight rows (use as a context manager)."""

    def __init__(self, path: Path) -> None:
        self.path = path
        path.parent.mkdir(parents=True, exist_ok=True)
        self._file = open_in_place(path, "w", encoding="utf-8", newline="\n")
        self._file.write(",".join(ROW_FIELDS) + "\n")
        self._file.flush()
        self.rows = 0

    def write(self, row: np.ndarray) -> None:
        """Append one row (full float precision) and flush it to the OS."""
        self._file.write(",".join(repr(float(v)) for v in row) + "\n")
        self._file.flush()
        self.rows += 1

    def close(self) -> None:
        """Close the file."""
        if not self._file.closed:
            self._file.close()

    def __enter__(self) -> CsvFlightLog:
        return self

    def __exit__(
        self, exc_type: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None
    ) -> None:
        self.close()


def read_flight_log(path: Path) -> np.ndarray:
    """Read a CSV flight log back into an array with the columns of :data:`ROW_FIELDS`.

    Raises:
        ValueError: the header does not match.
    """
    with path.open(encoding="utf-8") as handle:
        header = handle.readline().strip().split(",")
    if tuple(header) != ROW_FIELDS:
        raise ValueError(f"{path}: not a robosoc flight log (unexpected header)")
    data = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    return data.reshape(-1, len(ROW_FIELDS))
