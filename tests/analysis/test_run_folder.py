"""Reading a run folder back from hand-made files: what is read, what is skipped with a note, and the
error that names the file for everything else."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from robosoc.control.flight import ROW_FIELDS
from robosoc.outputs.run_folder import (
    JOB_CSV_FIELDS,
    RunFolder,
    RunFolderError,
    finite,
    read_flight_rows,
    read_jobs,
    read_run_folder,
)

PROFILE_KEYS = "tile, task, task_name, function, cycles, instructions, energy_nj"


def _flight_text(rows: list[list[str]]) -> str:
    return "\n".join([",".join(ROW_FIELDS), *(",".join(r) for r in rows)]) + "\n"


def _row(k: int) -> list[str]:
    return [str(k + i / 8) for i in range(len(ROW_FIELDS))]


def _job(task: str, tile: str, k: int) -> list[str]:
    values = {"task": task, "tile": tile}
    return [values.get(name, str(k * 10 + i)) for i, name in enumerate(JOB_CSV_FIELDS)]


def _jobs_text(lines: list[list[str]]) -> str:
    return "\n".join([",".join(JOB_CSV_FIELDS), *(",".join(f'"{v}"' if "," in v else v for v in r) for r in lines)])


def test_flight_rows_are_read_and_a_cut_last_line_is_skipped_with_a_note(tmp_path: Path) -> None:
    path = tmp_path / "flight.csv"
    path.write_text(_flight_text([_row(0), _row(1), _row(2)[:5]]))
    notes: list[str] = []
    rows = read_flight_rows(path, notes)
    assert rows.shape == (2, len(ROW_FIELDS))
    assert rows[1, 3] == 1 + 3 / 8
    assert notes == ["flight.csv: last line incomplete (interrupted flight?), skipped"]
    path.write_text(_flight_text([]))
    notes = []
    assert read_flight_rows(path, notes).shape == (0, len(ROW_FIELDS)) and notes == []


def test_a_bad_flight_row_before_the_last_names_its_line(tmp_path: Path) -> None:
    path = tmp_path / "flight.csv"
    path.write_text(_flight_text([_row(0), _row(1)[:3], _row(2)]))
    with pytest.raises(RunFolderError) as caught:
        read_flight_rows(path, [])
    assert str(caught.value) == f"{path}: row 2 (line 3): 3 values, expected {len(ROW_FIELDS)}"
    bad = _row(1)
    bad[4] = "fast"
    path.write_text(_flight_text([_row(0), bad, _row(2)]))
    with pytest.raises(RunFolderError, match=r"flight\.csv: row 2 \(line 3\), column roll: 'fast' is not a number$"):
        read_flight_rows(path, [])


@pytest.mark.parametrize(
    ("name", "read", "text", "what", "problem"),
    [
        ("flight.csv", read_flight_rows, "", "a robosoc flight log", "empty file"),
        (
            "flight.csv",
            read_flight_rows,
            "t,x,y\n1,2,3\n",
            "a robosoc flight log",
            "missing columns z, roll, pitch, yaw,",
        ),
        ("jobs.csv", read_jobs, "", "a robosoc job record file", "empty file"),
        ("jobs.csv", read_jobs, "task,tile\n", "a robosoc job record file", "missing columns job, release_cycle,"),
    ],
)
def test_a_file_without_its_header_is_refused(
    tmp_path: Path, name: str, read, text: str, what: str, problem: str
) -> None:
    path = tmp_path / name
    path.write_text(text)
    with pytest.raises(RunFolderError) as caught:
        read(path, [])
    assert str(caught.value).startswith(f"{path}: not {what} ({problem}"), caught.value


def test_jobs_are_columns_with_text_for_task_and_tile(tmp_path: Path) -> None:
    path = tmp_path / "jobs.csv"
    path.write_text(_jobs_text([_job("estimator", "0,1", 1), [], _job("pid", "1,0", 2), _job("pid", "1,0", 3)[:4]]))
    notes: list[str] = []
    jobs = read_jobs(path, notes)
    assert set(jobs) == set(JOB_CSV_FIELDS)
    assert jobs["task"].tolist() == ["estimator", "pid"] and jobs["tile"].tolist() == ["0,1", "1,0"]
    number = next(n for n in JOB_CSV_FIELDS if n not in ("task", "tile"))
    i = JOB_CSV_FIELDS.index(number)
    assert jobs[number].dtype == float and jobs[number].tolist() == [10.0 + i, 20.0 + i]
    assert notes == ["jobs.csv: last line incomplete, skipped"]  # the empty line between is no job


def test_a_job_with_a_bad_number_names_its_column(tmp_path: Path) -> None:
    number = next(n for n in JOB_CSV_FIELDS if n not in ("task", "tile"))
    job = _job("pid", "1,0", 1)
    job[JOB_CSV_FIELDS.index(number)] = "soon"
    path = tmp_path / "jobs.csv"
    path.write_text(_jobs_text([job, _job("pid", "1,0", 2)]))
    with pytest.raises(RunFolderError) as caught:
        read_jobs(path, [])
    assert str(caught.value).startswith(f"{path}: row 1 (line 2), column {number}: ") and "soon" in str(caught.value)


def test_a_run_folder_reads_every_file_and_its_vehicles_in_number_order(tmp_path: Path) -> None:
    (tmp_path / "flight.csv").write_text(_flight_text([_row(0)]))
    (tmp_path / "scenario.toml").write_text('name = "x"\n', encoding="utf-8")
    (tmp_path / "summary.json").write_text(json.dumps({"chip": {"clock_ns": 4}}))
    for n in (10, 2):
        sub = tmp_path / f"vehicle-{n}"
        sub.mkdir()
        (sub / "summary.json").write_text(json.dumps({"vehicle": n}))
    (tmp_path / "vehicle-x").mkdir()  # not a vehicle folder
    (tmp_path / "vehicle-3.txt").write_text("not a folder")
    run = read_run_folder(tmp_path)
    assert run.rows is not None and run.rows.shape == (1, len(ROW_FIELDS))
    assert run.jobs is None and run.profile is None and run.notes == []
    assert run.scenario_text == 'name = "x"\n' and run.clock_ns == 4.0
    assert [v.summary for v in run.vehicles] == [{"vehicle": 2}, {"vehicle": 10}]
    assert [v.path.name for v in run.vehicles] == ["vehicle-2", "vehicle-10"]


def test_a_folder_of_vehicles_alone_is_a_run_folder(tmp_path: Path) -> None:
    sub = tmp_path / "vehicle-0"
    sub.mkdir()
    (sub / "flight.csv").write_text(_flight_text([_row(0)]))
    run = read_run_folder(tmp_path)
    assert run.rows is None and len(run.vehicles) == 1 and run.vehicles[0].rows is not None


def test_what_is_not_a_run_folder_is_named(tmp_path: Path) -> None:
    missing = tmp_path / "nowhere"
    with pytest.raises(RunFolderError) as caught:
        read_run_folder(missing)
    assert str(caught.value) == f"{missing}: folder not found"
    a_file = tmp_path / "notes.txt"
    a_file.write_text("x")
    with pytest.raises(RunFolderError) as caught:
        read_run_folder(a_file)
    assert str(caught.value) == f"{a_file}: is a file, expected a run folder"
    empty = tmp_path / "empty"
    empty.mkdir()
    (empty / "scenario.toml").write_text("x = 1\n")  # a scenario alone is no run
    with pytest.raises(RunFolderError) as caught:
        read_run_folder(empty)
    assert str(caught.value) == (
        f"{empty}: not a run folder (no flight.csv, jobs.csv, summary.json or vehicle-N/ in it)"
    )


@pytest.mark.parametrize(
    ("text", "message"),
    [("{not json", "not JSON: Expecting property name"), ("[1, 2]", "expected a JSON object")],
)
def test_a_bad_summary_is_an_error_that_names_it(tmp_path: Path, text: str, message: str) -> None:
    (tmp_path / "summary.json").write_text(text)
    with pytest.raises(RunFolderError) as caught:
        read_run_folder(tmp_path)
    assert str(caught.value).startswith(f"{tmp_path / 'summary.json'}: {message}")


def test_a_run_file_that_is_not_utf8_is_named(tmp_path: Path) -> None:
    (tmp_path / "summary.json").write_bytes(b'{"a": "\xff"}')
    with pytest.raises(RunFolderError) as caught:
        read_run_folder(tmp_path)
    assert str(caught.value).startswith(f"{tmp_path / 'summary.json'}: not JSON: ")
    (tmp_path / "summary.json").write_text("{}")
    (tmp_path / "scenario.toml").write_bytes(b"name = '\xff'\n")
    with pytest.raises(RunFolderError) as caught:
        read_run_folder(tmp_path)
    assert str(caught.value).startswith(f"{tmp_path}: a run file is not UTF-8 text: ")


def test_a_bad_profile_is_skipped_with_a_note(tmp_path: Path) -> None:
    (tmp_path / "summary.json").write_text("{}")
    profile = tmp_path / "profile.json"
    profile.write_text("[]")
    run = read_run_folder(tmp_path)
    assert run.profile is None and run.notes == [f"profile.json: skipped: {profile}: expected a JSON object"]
    profile.write_text(json.dumps({"rows": [{"tile": "0,0", "task": 0}]}))
    run = read_run_folder(tmp_path)
    assert run.profile is None
    assert run.notes == [f"profile.json: skipped: not a robosoc profile (rows with {PROFILE_KEYS})"]
    profile.write_text(json.dumps({"rows": "none"}))
    assert read_run_folder(tmp_path).notes == run.notes
    good = {
        "rows": [dict.fromkeys(PROFILE_KEYS.split(", "), 0) | {"tile": "0,0", "task_name": "pid", "function": "main"}],
        "totals": {},
    }
    profile.write_text(json.dumps(good))
    run = read_run_folder(tmp_path)
    assert run.profile == good and run.notes == []


@pytest.mark.parametrize(
    ("summary", "clock"),
    [
        (None, None),
        ({}, None),
        ({"chip": None}, None),
        ({"chip": {"clock_ns": 2.5}}, 2.5),
        ({"chip": {"clock_ns": 0}}, None),
        ({"chip": {"clock_ns": -4}}, None),
        ({"chip": {"clock_ns": "4"}}, None),
    ],
)
def test_the_clock_comes_from_the_summary_when_it_is_a_positive_number(summary, clock) -> None:
    assert RunFolder(Path("."), summary=summary).clock_ns == clock


def test_finite_is_a_float_for_finite_numbers_only() -> None:
    assert finite(3) == 3.0 and type(finite(3)) is float
    assert finite(-0.5) == -0.5
    for value in (math.nan, math.inf, -math.inf, None, "1.0", True, False, [1.0], np.float64(1.0)):
        expected = 1.0 if isinstance(value, np.float64) else None
        assert finite(value) == expected, value


def test_a_run_folder_notes_a_cut_last_job(tmp_path: Path) -> None:
    (tmp_path / "jobs.csv").write_text(_jobs_text([_job("pid", "1,0", 1), _job("pid", "1,0", 2)[:3]]))
    run = read_run_folder(tmp_path)
    assert run.jobs is not None and run.jobs["task"].tolist() == ["pid"]
    assert run.notes == ["jobs.csv: last line incomplete, skipped"]
