"""A run folder (what ``robosoc fly`` writes): its file names, ``jobs.csv`` written, and the folder
read back, tolerating whatever is missing.

A fly run folder holds ``scenario.toml``, ``flight.csv``, ``jobs.csv`` (chip controller only),
``summary.json`` and, with several vehicles, ``vehicle-N/`` sub-folders each with their own.  Any
of the files may be missing (a host flight has no jobs, an interrupted one no summary), and a
flight log cut short by a crash may end in half a line: what is there is read, what is not is
``None``, and :attr:`RunFolder.notes` says what was skipped.
"""

from __future__ import annotations

import csv
import json
import math
import re
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from robosoc import output_files
from robosoc.chip.function_profile import FunctionProfile
from robosoc.control.flight_log import FlightLogError, header_problem, read_flight_log
from robosoc.records import JobRecord

FLIGHT_CSV = "flight.csv"
JOBS_CSV = "jobs.csv"
SUMMARY_JSON = "summary.json"
SCENARIO_TOML = "scenario.toml"
FLIGHT_MCAP = "flight.mcap"
CHIP_TRACE_JSON = "chip-trace.json"
REPORT_HTML = "report.html"
PROFILE_JSON = "profile.json"  # written by robosoc profile / fly --profile (write_profile)
PROFILE_CSV = "profile.csv"
FLIGHT_PNG = "flight.png"
PHYSICS_JSON = "physics.json"  # the decoupled mode's physics side
CHIP_JSON = "chip.json"  # the decoupled mode's chip side
LINK_PHYSICS_LOG = "link-physics.log"
LINK_CHIP_LOG = "link-chip.log"
VEHICLE_FOLDER = re.compile(r"vehicle-(\d+)")
#: Every file robosoc fly may write in a run folder (checked to be regular files before a flight).
RUN_FILES = (
    FLIGHT_CSV, JOBS_CSV, SUMMARY_JSON, SCENARIO_TOML, FLIGHT_MCAP, CHIP_TRACE_JSON, REPORT_HTML, PROFILE_JSON,
    PROFILE_CSV, FLIGHT_PNG,
)  # fmt: skip

JOB_CSV_FIELDS = (
    "task", "tile", "job", "release_cycle", "start_cycle", "completion_cycle", "response_cycles", "exec_cycles",
    "instructions", "task_pj", "kernel_pj", "noc_pj", "idle_pj", "deadline_met",
)  # fmt: skip
"""Columns of ``jobs.csv`` (one job a row; tile as "x,y", energies in pJ, deadline_met 0/1)."""


def write_jobs_csv(jobs: Sequence[JobRecord], path: Path) -> None:
    """Write ``jobs`` to ``path`` with the columns :data:`JOB_CSV_FIELDS`."""
    with output_files.atomic_open(path, "w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(JOB_CSV_FIELDS)
        for j in jobs:
            writer.writerow(
                [
                    j.task, f"{j.tile[0]},{j.tile[1]}", j.job, j.release_cycle, j.start_cycle, j.completion_cycle,
                    j.response_cycles, j.exec_cycles, j.instructions, f"{j.energy_pj['task']:.3f}",
                    f"{j.energy_pj['kernel']:.3f}", f"{j.energy_pj['noc']:.3f}", f"{j.energy_pj['idle']:.3f}",
                    int(j.deadline_met),
                ]
            )  # fmt: skip


def write_profile(profile: FunctionProfile, folder: Path) -> tuple[Path, Path]:
    """Write ``profile.json`` and ``profile.csv`` into ``folder``, each to a temporary name first
    and then renamed, so an interruption never leaves half a file (:mod:`robosoc.output_files`)."""
    paths = folder / PROFILE_JSON, folder / PROFILE_CSV
    for path, text in zip(paths, (profile.json_text(), profile.csv_text()), strict=True):
        output_files.write_atomic(path, text)
    return paths


_TEXT_JOB_FIELDS = ("task", "tile")


def _whole(v: object) -> bool:
    return isinstance(v, int) and not isinstance(v, bool) and v >= 0


def _real(v: object) -> bool:
    return isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)


_PROFILE_ROW = {
    "tile": (lambda v: v is None or isinstance(v, str), "a tile 'x,y' or null"),
    "task": (lambda v: v is None or _whole(v), "a task number or null"),
    "task_name": (lambda v: v is None or isinstance(v, str), "a string or null"),
    "function": (lambda v: isinstance(v, str), "a function name"),
    "cycles": (_whole, "a whole number"),
    "instructions": (_whole, "a whole number"),
    "energy_nj": (_real, "a finite number"),
}
"""The fields of a ``profile.json`` row the report uses, and what each must be."""


class RunFolderError(ValueError):
    """The folder is not a run folder, or one of its files is not what its name says."""


@dataclass
class RunFolder:
    """What one run folder holds (``None``: the file is not there)."""

    path: Path
    rows: np.ndarray | None = None
    jobs: dict[str, np.ndarray] | None = None
    summary: dict | None = None
    scenario_text: str | None = None
    profile: dict | None = None
    power: np.ndarray | None = None  # a battery flight's power columns of flight.csv (POWER_FIELDS)
    #: the firmware's own telemetry columns of flight.csv (name -> one value per row, NaN before the first)
    telemetry: dict[str, np.ndarray] = field(default_factory=dict)
    vehicles: list[RunFolder] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)

    @property
    def clock_ns(self) -> float | None:
        """The chip's clock period from ``summary.json`` (None without one)."""
        chip = (self.summary or {}).get("chip") or {}
        value = chip.get("clock_ns")
        return float(value) if isinstance(value, int | float) and value > 0 else None


def read_flight_rows(
    path: Path,
    notes: list[str],
    power: list[np.ndarray] | None = None,
    telemetry: dict[str, np.ndarray] | None = None,
) -> np.ndarray:
    """The rows of a flight log; a last line cut short (an interrupted flight) is skipped with a note;
    a battery flight's power columns appended to ``power``, the firmware's own telemetry columns
    put in ``telemetry`` by name.

    Raises:
        RunFolderError: the header is not the flight log's, or a row is bad
            (:func:`robosoc.control.flight_log.read_flight_log`: names the row and the column).
    """
    try:
        return read_flight_log(path, notes, power, telemetry)
    except FlightLogError as exc:
        raise RunFolderError(str(exc)) from None


def read_jobs(path: Path, notes: list[str]) -> dict[str, np.ndarray]:
    """``jobs.csv`` as columns (task and tile as text, the rest as numbers).

    Raises:
        RunFolderError: the header is not the job records'.
    """
    with path.open(encoding="utf-8", newline="") as handle:
        reader = csv.reader(handle)
        header = next(reader, None)
        problem = "empty file" if header is None else header_problem(header, JOB_CSV_FIELDS)
        if problem is not None:
            raise RunFolderError(f"{path}: not a robosoc job record file ({problem})")
        lines = [line for line in reader if line]
    if lines and len(lines[-1]) != len(JOB_CSV_FIELDS):
        notes.append(f"{path.name}: last line incomplete, skipped")
        lines = lines[:-1]
    for k, line in enumerate(lines):
        if len(line) != len(JOB_CSV_FIELDS):
            raise RunFolderError(
                f"{path}: row {k + 1} (line {k + 2}): {len(line)} values, expected {len(JOB_CSV_FIELDS)}"
            )
    columns: dict[str, np.ndarray] = {}
    for i, name in enumerate(JOB_CSV_FIELDS):
        values = [line[i] for line in lines]
        if name in _TEXT_JOB_FIELDS:
            columns[name] = np.array(values, dtype=str)
            continue
        try:
            columns[name] = np.array(values, dtype=float)
        except ValueError:
            k = next(k for k, v in enumerate(values) if not _parses(v))
            raise RunFolderError(
                f"{path}: row {k + 1} (line {k + 2}), column {name}: {values[k][:40]!r} is not a number"
            ) from None
        bad = np.flatnonzero(~np.isfinite(columns[name]) | (columns[name] < 0))
        if len(bad):
            k = int(bad[0])
            raise RunFolderError(
                f"{path}: row {k + 1} (line {k + 2}), column {name}: {values[k]}: expected a finite number >= 0"
            )
    return columns


def _parses(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def read_summary(path: Path) -> dict:
    """A run's ``summary.json``, its shape checked (:func:`robosoc.outputs.run_summary.check_summary`).

    Raises:
        RunFolderError: not UTF-8, not JSON, or a field of the wrong kind (names the file and field).
    """
    from robosoc.outputs.run_summary import SummaryError, load_summary

    try:
        return load_summary(path.read_text(encoding="utf-8"), str(path))
    except UnicodeDecodeError as exc:
        raise RunFolderError(f"{path}: not JSON: not UTF-8 text: {exc}") from None
    except SummaryError as exc:
        raise RunFolderError(str(exc)) from None


def _read_json(path: Path) -> dict:
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError, RecursionError) as exc:
        raise RunFolderError(f"{path}: not JSON: {exc}") from None
    if not isinstance(data, dict):
        raise RunFolderError(f"{path}: expected a JSON object")
    return data


def _read_profile(path: Path, notes: list[str]) -> dict | None:
    """``profile.json`` if it is one (rows with tile, task, function, cycles, instructions, energy),
    else None with a note: the profile is an extra, a bad one does not stop the report."""
    try:
        data = _read_json(path)
    except RunFolderError as exc:
        notes.append(f"{PROFILE_JSON}: skipped: {exc}")
        return None
    rows = data.get("rows")
    keys = tuple(_PROFILE_ROW)
    if not isinstance(rows, list) or not all(isinstance(r, dict) and all(k in r for k in keys) for r in rows):
        notes.append(f"{PROFILE_JSON}: skipped: not a robosoc profile (rows with {', '.join(keys)})")
        return None
    for i, row in enumerate(rows):
        for key, (test, kind) in _PROFILE_ROW.items():
            if not test(row[key]):
                notes.append(f"{PROFILE_JSON}: skipped: rows[{i}].{key}: expected {kind}, got {row[key]!r:.40}")
                return None
    return data


def read_run_folder(path: Path) -> RunFolder:
    """Everything a run folder holds.

    Raises:
        RunFolderError: ``path`` is not a folder, holds none of the run files, or one of them is
            malformed (the message names the file).
    """
    if not path.exists():
        raise RunFolderError(f"{path}: folder not found")
    if not path.is_dir():
        raise RunFolderError(f"{path}: is a file, expected a run folder")
    run = RunFolder(path)
    try:
        if (path / FLIGHT_CSV).is_file():
            power: list[np.ndarray] = []
            run.rows = read_flight_rows(path / FLIGHT_CSV, run.notes, power, run.telemetry)
            run.power = power[0] if power else None
        if (path / JOBS_CSV).is_file():
            run.jobs = read_jobs(path / JOBS_CSV, run.notes)
        if (path / SUMMARY_JSON).is_file():
            run.summary = read_summary(path / SUMMARY_JSON)
        if (path / SCENARIO_TOML).is_file():
            run.scenario_text = (path / SCENARIO_TOML).read_text(encoding="utf-8")
        if (path / PROFILE_JSON).is_file():
            run.profile = _read_profile(path / PROFILE_JSON, run.notes)
    except UnicodeDecodeError as exc:
        raise RunFolderError(f"{path}: a run file is not UTF-8 text: {exc}") from None
    except OSError as exc:
        raise RunFolderError(f"{path}: cannot read: {exc}") from None
    subs = sorted(
        (p for p in path.iterdir() if p.is_dir() and VEHICLE_FOLDER.fullmatch(p.name)),
        key=lambda p: int(p.name.split("-")[1]),
    )
    run.vehicles = [read_run_folder(p) for p in subs]
    if run.rows is None and run.jobs is None and run.summary is None and not run.vehicles:
        raise RunFolderError(
            f"{path}: not a run folder (no {FLIGHT_CSV}, {JOBS_CSV}, {SUMMARY_JSON} or vehicle-N/ in it)"
        )
    return run


def finite(value: object) -> float | None:
    """``value`` as a float if it is a finite number (JSON null and NaN are None)."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        return None
    return float(value) if math.isfinite(value) else None


__all__ = [
    "CHIP_JSON",
    "CHIP_TRACE_JSON",
    "FLIGHT_CSV",
    "FLIGHT_MCAP",
    "FLIGHT_PNG",
    "JOBS_CSV",
    "JOB_CSV_FIELDS",
    "LINK_CHIP_LOG",
    "LINK_PHYSICS_LOG",
    "PHYSICS_JSON",
    "PROFILE_CSV",
    "PROFILE_JSON",
    "REPORT_HTML",
    "SCENARIO_TOML",
    "SUMMARY_JSON",
    "RunFolder",
    "RunFolderError",
    "finite",
    "read_flight_rows",
    "read_jobs",
    "read_run_folder",
    "read_summary",
    "write_jobs_csv",
    "write_profile",
]
