"""Flight logs on disk: one CSV row per sensor sample, flushed as it is written.

Because every row is flushed, an interrupted or crashed flight leaves a readable file holding
every row up to the interruption.  Columns are :data:`robosoc.control.flight.ROW_FIELDS`.
"""

from __future__ import annotations

import csv
from collections.abc import Sequence
from pathlib import Path
from types import TracebackType

import numpy as np

from robosoc.control.flight import ROW_FIELDS
from robosoc.output_files import open_in_place
from robosoc.records import POWER_FIELDS


class CsvFlightLog:
    """Append-only CSV writer of flight rows (use as a context manager).

    Args:
        path: the file.
        extra_fields: columns after :data:`ROW_FIELDS` (a battery flight's
            :data:`robosoc.records.POWER_FIELDS`), whose values each :meth:`write` is given.
    """

    def __init__(self, path: Path, extra_fields: Sequence[str] = ()) -> None:
        self.path = path
        self.extra_fields = tuple(extra_fields)
        path.parent.mkdir(parents=True, exist_ok=True)
        self._file = open_in_place(path, "w", encoding="utf-8", newline="\n")
        self._file.write(",".join((*ROW_FIELDS, *self.extra_fields)) + "\n")
        self._file.flush()
        self.rows = 0

    def write(self, row: np.ndarray, extra: Sequence[float] = ()) -> None:
        """Append one row and the values of the extra columns (full float precision), and flush it to the OS.

        Raises:
            ValueError: not one value per extra column.
        """
        if len(extra) != len(self.extra_fields):
            raise ValueError(f"extra: {len(self.extra_fields)} values expected ({', '.join(self.extra_fields)}), "
                             f"got {len(extra)}")  # fmt: skip
        self._file.write(",".join(repr(float(v)) for v in (*row, *extra)) + "\n")
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


MAX_FLIGHT_S = 3600.0
"""Latest time a flight row can have [s]: the longest flight robosoc flies (``fly --duration``)."""

NAN_ALLOWED = tuple(name for name in ROW_FIELDS if name.startswith("est_"))
"""Columns that may hold NaN: the controller's estimate, unknown while it stays on the chip."""


PACKET_COLUMNS = (
    *(f"{sensor}_{axis}" for sensor in ("gyro", "accel", "mag") for axis in "xyz"),
    "baro_altitude",
    *(f"sp_{name}" for name in ("roll", "pitch", "yaw", "height", "height_rate", "height_accel")),
)
"""Columns a replay packs into the firmware's sensor packet, whose fields are Q16.16
(:data:`robosoc.host.packets.SENSOR`): they must fit in -32768 .. 32768 - 2**-16."""
Q16_LOW, Q16_HIGH = -(2**15), 2**15 - 2**-16


WITH_POWER_FIELDS = (*ROW_FIELDS, *POWER_FIELDS)
"""The columns of a battery flight's log: the flight's, then its power system's."""


class FlightLogError(ValueError):
    """A flight log that is not one: ``"<file>: row <k> (line <n>), column <name>: <reason>"``."""


def _where(where: str, k: int, column: str | None = None) -> str:
    place = f"{where}: row {k + 1} (line {k + 2})"
    return f"{place}, column {column}" if column else place


def check_flight_rows(rows: np.ndarray, where: str = "rows") -> np.ndarray:
    """``rows`` if they are a flight (columns :data:`ROW_FIELDS`), else :class:`FlightLogError`
    naming ``where``, the row and the column.

    Every cell is finite, except NaN in the estimate's columns (:data:`NAN_ALLOWED`); the sensor
    and setpoint columns fit the firmware's packet (:data:`PACKET_COLUMNS`); the times are in
    0..:data:`MAX_FLIGHT_S` s and increase from row to row.  This is the one check of a
    flight log's contents, for every reader (``report``, ``firmware replay``, ``report --mcap``,
    the decoupled mode's log) and for :func:`robosoc.cosim.replay.samples_from_rows`.
    """
    rows = np.asarray(rows, dtype=float)
    if rows.ndim != 2 or rows.shape[1] != len(ROW_FIELDS):
        raise FlightLogError(f"{where}: a flight has {len(ROW_FIELDS)} columns (robosoc.control.flight.ROW_FIELDS)")
    bad = ~np.isfinite(rows)
    for name in NAN_ALLOWED:
        c = ROW_FIELDS.index(name)
        bad[:, c] &= ~np.isnan(rows[:, c])
    if bad.any():
        k, c = (int(i) for i in np.argwhere(bad)[0])
        raise FlightLogError(f"{_where(where, k, ROW_FIELDS[c])}: {rows[k, c]}: expected a finite number")
    for name in PACKET_COLUMNS:
        c = ROW_FIELDS.index(name)
        wide = np.flatnonzero((rows[:, c] < Q16_LOW) | (rows[:, c] > Q16_HIGH))
        if len(wide):
            k = int(wide[0])
            raise FlightLogError(
                f"{_where(where, k, name)}: {float(rows[k, c])!r} is outside the Q16.16 range of the firmware's "
                f"sensor packet ({Q16_LOW}..{Q16_HIGH:.5f})"
            )
    times = rows[:, 0]
    out_of_range = np.flatnonzero((times < 0) | (times > MAX_FLIGHT_S))
    if len(out_of_range):
        k = int(out_of_range[0])
        raise FlightLogError(f"{_where(where, k, 't')}: {float(times[k])!r} s is outside 0..{MAX_FLIGHT_S:g} s")
    back = np.flatnonzero(np.diff(times) <= 0)
    if len(back):
        k = int(back[0]) + 1
        raise FlightLogError(
            f"{_where(where, k, 't')}: {float(times[k])!r} s is not after the row before ({float(times[k - 1])!r} s): "
            "times must increase"
        )
    return rows


def flight_header_problem(header: Sequence[str]) -> tuple[tuple[str, ...], str | None]:
    """The flight's own columns of a ``flight.csv`` header (:data:`ROW_FIELDS`, or with a battery
    flight's :data:`WITH_POWER_FIELDS`) and what is wrong with the header (``None``: nothing).

    Columns after those are the firmware's own telemetry (:mod:`robosoc.host.telemetry`): each
    named once, by a name that is not one of the flight's columns.
    """
    known = set(WITH_POWER_FIELDS)
    core = [c for c in header if c in known]
    expected = WITH_POWER_FIELDS if any(c in POWER_FIELDS for c in core) else ROW_FIELDS
    if header_problem(core, expected) is not None:  # not a flight's: every column out of place named
        return expected, header_problem(header, expected)
    own = list(header[len(core) :])
    if list(header[: len(core)]) != core:
        stray = next(c for c in header[: len(core)] if c not in known)
        return expected, f"unknown column {stray} among the flight's columns (telemetry columns come after them)"
    if any(not c for c in own):
        return expected, "a telemetry column without a name"
    repeated = sorted({c for c in own if own.count(c) > 1})
    if repeated:
        return expected, f"repeated column{'s' if len(repeated) > 1 else ''} {', '.join(repeated)}"
    return expected, None


def read_flight_log(
    path: Path,
    notes: list[str] | None = None,
    power: list[np.ndarray] | None = None,
    telemetry: dict[str, np.ndarray] | None = None,
) -> np.ndarray:
    """Read a CSV flight log back into an array with the columns of :data:`ROW_FIELDS`, checked by
    :func:`check_flight_rows` (a battery flight's power columns, :data:`WITH_POWER_FIELDS`, and the
    firmware's own telemetry columns after them are read past).

    Args:
        notes: given, a last line cut short (an interrupted flight) is skipped with a note there;
            without, it is an error.
        power: given, a battery flight's power columns (:data:`robosoc.records.POWER_FIELDS`, one
            row per flight row) are appended to it.
        telemetry: given, each telemetry column (any number, NaN before the firmware's first
            value) is put in it by its name.

    Raises:
        FlightLogError: the header is not a flight log's, or a row is bad (names the file, row, column).
        OSError, UnicodeDecodeError: the file cannot be read.
    """
    with path.open(encoding="utf-8", newline="") as handle:
        reader = csv.reader(handle)
        header = next(reader, None)
        expected, problem = ((), "empty file") if header is None else flight_header_problem(header)
        if problem is not None:
            raise FlightLogError(f"{path}: not a robosoc flight log ({problem})")
        assert header is not None
        lines = list(reader)
    names = tuple(header)
    width = len(names)
    for k, line in enumerate(lines):
        if len(line) != width:
            if notes is not None and k == len(lines) - 1:
                notes.append(f"{path.name}: last line incomplete (interrupted flight?), skipped")
                lines.pop()
                break
            raise FlightLogError(f"{_where(str(path), k)}: {len(line)} values, expected {width}")
    try:
        rows = np.array(lines, dtype=float).reshape(-1, width)
    except ValueError:
        for k, line in enumerate(lines):
            for c, cell in enumerate(line):
                try:
                    float(cell)
                except ValueError:
                    if notes is not None and k == len(lines) - 1:
                        notes.append(f"{path.name}: last line incomplete (interrupted flight?), skipped")
                        rows = np.array(lines[:-1], dtype=float).reshape(-1, width)
                        return _split_columns(rows, str(path), len(expected), names, power, telemetry)
                    raise FlightLogError(f"{_where(str(path), k, names[c])}: {cell[:40]!r} is not a number") from None
        raise
    return _split_columns(rows, str(path), len(expected), names, power, telemetry)


def _split_columns(
    rows: np.ndarray,
    where: str,
    own: int,
    names: tuple[str, ...],
    power: list[np.ndarray] | None,
    telemetry: dict[str, np.ndarray] | None,
) -> np.ndarray:
    """The flight's columns of ``rows`` (the first ``own`` of ``names``), checked; the telemetry
    columns after them to ``telemetry`` (by name; any number)."""
    if telemetry is not None:
        for c in range(own, len(names)):
            telemetry[names[c]] = rows[:, c].copy()
    return _split_power(rows[:, :own], where, power)


def _split_power(rows: np.ndarray, where: str, power: list[np.ndarray] | None) -> np.ndarray:
    """The flight's columns of ``rows``, checked; a battery flight's power columns (finite) to ``power``."""
    width = len(ROW_FIELDS)
    if rows.shape[1] > width:
        extra = rows[:, width:]
        bad = np.argwhere(~np.isfinite(extra))
        if len(bad):
            k, c = (int(i) for i in bad[0])
            raise FlightLogError(f"{_where(where, k, POWER_FIELDS[c])}: {extra[k, c]}: expected a finite number")
        if power is not None:
            power.append(extra)
    return check_flight_rows(rows[:, :width], where)
