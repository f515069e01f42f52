"""Flight logs on disk: one CSV row per sensor sample, flushed as it is written.

Because every row is flushed, an interrupted or crashed flight leaves a readable file holding
every row up to the interruption.  Columns are :data:`robosoc.control.flight.ROW_FIELDS`.
"""

from __future__ import annotations

from collections.abc import Sequence
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


def header_problem(header: Sequence[str], expected: Sequence[str]) -> str | None:
    """What is wrong with a CSV file's ``header`` (``"missing column pwm3"``), or ``None`` if it is ``expected``."""
    if tuple(header) == tuple(expected):
        return None

    def names(columns: list[str]) -> str:
        shown = ", ".join(columns[:6]) + (f", ... ({len(columns)} in all)" if len(columns) > 6 else "")
        return f"column{'s' if len(columns) > 1 else ''} {shown}"

    missing = [c for c in expected if c not in header]
    unknown = [c for c in header if c not in expected]
    parts = [f"missing {names(missing)}"] if missing else []
    parts += [f"unknown {names(unknown)}"] if unknown else []
    if not parts:
        repeated = sorted({c for c in header if list(header).count(c) > 1})
        parts.append(f"repeated {names(repeated)}" if repeated else "the columns are in another order")
    return "; ".join(parts)


def read_flight_log(path: Path) -> np.ndarray:
    """Read a CSV flight log back into an array with the columns of :data:`ROW_FIELDS`.

    Raises:
        ValueError: the header does not match (the message names the missing columns), or a row has
            another number of values or one that is not a number (the message names the line).
    """
    with path.open(encoding="utf-8") as handle:
        header = handle.readline().strip().split(",")
        problem = header_problem(header, ROW_FIELDS)
        if problem is not None:
            raise ValueError(f"{path}: not a robosoc flight log ({problem})")
        for number, line in enumerate(handle, start=2):
            count = line.count(",") + 1
            if line.strip() and count != len(ROW_FIELDS):
                raise ValueError(f"{path}: line {number}: {count} values, expected {len(ROW_FIELDS)}")
    try:
        data = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    except ValueError as exc:
        raise ValueError(f"{path}: {exc}") from None
    return data.reshape(-1, len(ROW_FIELDS))
