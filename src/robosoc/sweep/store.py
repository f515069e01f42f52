"""A sweep's output folder, written so that an interruption at any moment loses no finished point.

Layout::

    OUT/sweep.toml           the sweep file as given (for the record)
    OUT/points/KEY/          each finished point's run folder (summary.json, flight.csv, ...)
    OUT/results/KEY.json     each finished point's record: its values, seed, status, error, summary
    OUT/points.csv           the table: one row per finished point, its values and metrics

A point is finished once its record exists: the run folder is written first (into a scratch
folder renamed into place), then the record (a scratch file renamed into place), so a record
never names a half-written folder.  ``points.csv`` is derived from the records and rewritten
(atomically) after every point.
"""

from __future__ import annotations

import csv
import fcntl
import io
import json
import os
import shutil
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from robosoc import output_files
from robosoc.outputs.run_summary import SummaryError, check_summary, json_safe
from robosoc.sweep.plan import Point
from robosoc.sweep.point import FAILED, OK, PointResult, metric

TABLE_LEADING = ("index", "key", "seed", "status", "error")
"""The first columns of ``points.csv``; then the varied fields, then the metrics."""


LOCK_FILE = ".lock"
"""In a sweep's folder: locked (flock) by the sweep running in it, and holding its pid."""

_HELD: dict[str, list[Any]] = {}
"""The folders this process holds: lock file -> [open file, depth]."""


class FolderInUse(Exception):
    """Another sweep is running in this folder."""

    def __init__(self, folder: Path, pid: int | None) -> None:
        by = f"pid {pid}" if pid is not None else "another process"
        super().__init__(f"{folder}: in use by another sweep ({by}): wait for it to end, or choose another folder")
        self.folder, self.pid = folder, pid


class RecordError(ValueError):
    """A ``results/KEY.json`` that is not a point's record: names the file and the field."""


_RECORD_FIELDS: dict[str, tuple[Any, str]] = {
    "key": (lambda v: isinstance(v, str), "the point's key"),
    "index": (lambda v: isinstance(v, int) and not isinstance(v, bool) and v >= 0, "an integer >= 0"),
    "seed": (lambda v: isinstance(v, int) and not isinstance(v, bool), "an integer"),
    "values": (lambda v: isinstance(v, dict), "an object of field values"),
    "status": (lambda v: v in (OK, FAILED), f"{OK!r} or {FAILED!r}"),
    "error": (lambda v: isinstance(v, str), "a string"),
    "worker_s": (lambda v: isinstance(v, int | float) and not isinstance(v, bool), "a number"),
    "summary": (lambda v: v is None or isinstance(v, dict), "a summary object or null"),
}


def check_record(record: dict[str, Any], path: Path) -> dict[str, Any]:
    """``record`` if it has the shape :meth:`SweepStore.save` writes (its summary checked by
    :func:`robosoc.outputs.run_summary.check_summary`), else :class:`RecordError`."""
    hint = "delete the file to run the point again"
    for name, (test, kind) in _RECORD_FIELDS.items():
        if name not in record:
            raise RecordError(f"{path}: {name}: missing: not a point's record ({hint})")
        if not test(record[name]):
            raise RecordError(f"{path}: {name}: expected {kind}, got {json.dumps(record[name])[:40]} ({hint})")
    if record["summary"] is not None:
        try:
            check_summary(record["summary"], f"{path}: summary")
        except SummaryError as exc:
            raise RecordError(f"{exc} ({hint})") from None
    return record


def write_atomic(path: Path, data: bytes) -> None:
    """Write ``path`` so that it is either absent or complete, whatever interrupts the write
    (never over a device, a FIFO or a socket: :func:`robosoc.output_files.write_atomic`)."""
    output_files.write_atomic(path, data, fsync=True)


class SweepStore:
    """The output folder of one sweep (see the module docstring)."""

    def __init__(self, folder: Path) -> None:
        self.folder = folder
        self.points_dir = folder / "points"
        self.results_dir = folder / "results"
        self.points_dir.mkdir(parents=True, exist_ok=True)
        self.results_dir.mkdir(parents=True, exist_ok=True)

    @contextmanager
    def lock(self) -> Iterator[None]:
        """Hold the folder for this process: another sweep into it (another process) gets
        :class:`FolderInUse` naming this process.  Re-entrant within one process."""
        path = self.folder / LOCK_FILE
        key = str(path.resolve())
        if key in _HELD:
            _HELD[key][1] += 1
        else:
            handle = open(path, "a+", encoding="utf-8")  # noqa: SIM115 (held until released)
            try:
                fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                handle.seek(0)
                holder = handle.read().strip()
                handle.close()
                raise FolderInUse(self.folder, int(holder) if holder.isdigit() else None) from None
            except BaseException:
                handle.close()
                raise
            handle.seek(0)
            handle.truncate()
            handle.write(f"{os.getpid()}\n")
            handle.flush()
            _HELD[key] = [handle, 1]
        try:
            yield
        finally:
            _HELD[key][1] -= 1
            if _HELD[key][1] == 0:
                handle = _HELD.pop(key)[0]
                handle.close()  # releases the lock; the file stays (removing it would race a newcomer)

    @property
    def table_path(self) -> Path:
        return self.folder / "points.csv"

    def records(self) -> dict[str, dict[str, Any]]:
        """Every finished point's record by key (unreadable records, from a crash, are skipped).

        Raises:
            RecordError: a record that is JSON but not of the shape :meth:`save` writes (edited by
                hand?): the message names the file and the field.
        """
        found = {}
        for path in sorted(self.results_dir.glob("*.json")):
            try:
                record = json.loads(path.read_text(encoding="utf-8"))
            except (OSError, ValueError, RecursionError):
                continue
            if isinstance(record, dict) and record.get("key") == path.stem:
                found[path.stem] = check_record(record, path)
        return found

    def save(self, point: Point, result: PointResult) -> dict[str, Any]:
        """Keep a finished point: its run folder, then its record."""
        folder = self.points_dir / point.key
        scratch = self.points_dir / f".{point.key}.partial"
        shutil.rmtree(scratch, ignore_errors=True)
        scratch.mkdir()
        for name, data in result.files.items():
            relative = Path(name)
            if relative.is_absolute() or ".." in relative.parts:
                raise ValueError(f"point {point.key}: a run folder file outside the folder: {name!r}")
            (scratch / relative).parent.mkdir(parents=True, exist_ok=True)
            (scratch / relative).write_bytes(data)
        shutil.rmtree(folder, ignore_errors=True)
        os.replace(scratch, folder)
        record = {
            "key": point.key,
            "index": point.index,
            "seed": point.seed,
            "values": {name: value for name, value in point.assignment},
            "status": result.status,
            "error": result.error,
            "worker_s": result.worker_s,
            "summary": result.summary,
        }
        text = json.dumps(json_safe(record), indent=1, allow_nan=False) + "\n"
        write_atomic(self.results_dir / f"{point.key}.json", text.encode())
        return record

    def forget(self, key: str) -> None:
        """Drop a point's record (its run folder goes when the point is saved again)."""
        (self.results_dir / f"{key}.json").unlink(missing_ok=True)

    def write_table(self, points: list[Point], varied: list[str], metrics: tuple[str, ...]) -> Path:
        """``points.csv``: the finished points among ``points``, in plan order."""
        records = self.records()
        buffer = io.StringIO()
        writer = csv.writer(buffer, lineterminator="\n")
        writer.writerow([*TABLE_LEADING, *varied, *metrics])
        for point in points:
            record = records.get(point.key)
            if record is None:
                continue
            values = record["values"]
            row = [point.index, point.key, point.seed, record["status"], record["error"]]
            row += [_cell(values.get(name)) for name in varied]
            row += [_cell(metric(record["summary"], name)) for name in metrics]
            writer.writerow(row)
        write_atomic(self.table_path, buffer.getvalue().encode())
        return self.table_path


def _cell(value: Any) -> Any:
    """A CSV cell: empty for a missing value, JSON for lists and tables, repr-exact floats."""
    if value is None:
        return ""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, list | dict):
        return json.dumps(value)
    if isinstance(value, float):
        return repr(value)
    return value


__all__ = ["LOCK_FILE", "TABLE_LEADING", "FolderInUse", "RecordError", "SweepStore", "check_record", "write_atomic"]
