"""Files read back from earlier runs are input too (issue 34, item 4): ``summary.json``,
``flight.csv``, ``jobs.csv`` and a sweep's ``results/KEY.json``, each with its shape checked in one
place, drawn by hypothesis with wrong types, shapes, NaN and infinities.  Every such file is either
read and then used without an exception, or refused with one line naming the file and the field
(or row and column); the commands exit 2, never 1."""

from __future__ import annotations

import copy
import json
import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

from robosoc.chip.function_profile import FunctionProfile, summary_mismatches
from robosoc.cli import app
from robosoc.control.flight import ROW_FIELDS
from robosoc.control.flight_log import CsvFlightLog, FlightLogError, read_flight_log
from robosoc.cosim.replay import samples_from_rows
from robosoc.outputs.report import render_report
from robosoc.outputs.run_folder import JOB_CSV_FIELDS, RunFolderError, read_jobs, read_run_folder
from robosoc.outputs.run_summary import SummaryError, check_summary, load_summary
from robosoc.sweep.store import RecordError, SweepStore, check_record

SUMMARY = {
    "schema": 1, "complete": True, "scenario": "default", "seed": 1, "controller": "chip", "mode": "lockstep",
    "firmware": {"build": "fixed+mul", "arith": "fixed", "multiplier": True, "release": "event", "scheduler": "edf",
                 "project": "", "tiles": {"estimator": [0, 1], "pid": [1, 0]}},
    "chip": {"width": 2, "height": 2, "clock_ns": 4.0},
    "simulated_s": 0.3, "host_s": 59.5, "real_time_factor": 0.005,
    "flight": {"hover_rms_m": None, "hover_max_m": None, "overshoot_m": 0.0,
               "tracking_rms_deg": {"roll": None, "pitch": 0.5, "yaw": None},
               "step_rise_s": [{"axis": "roll", "time_s": 5.0, "rise_s": None}],
               "attitude_estimate_rms_deg": None, "height_estimate_rms_m": 0.1},
    "tasks": {"estimator": {"jobs": 30, "response_us_mean": 36.2, "response_us_max": 125.6, "exec_cycles_mean": 8160.0,
                            "exec_cycles_max": 9000, "energy_nj_mean": 2504.7, "deadline_misses": 0}},
    "deadline_misses": 0,
    "energy": {"total_uj": 3320.0, "tiles_uj": {"0,1": 1000.0, "1,0": 2000.0}, "noc_uj": 320.0},
    "cycles": {"chip": 75_000_000, "tiles": {"0,1": 75_000_000, "1,0": 75_000_000}},
}  # fmt: skip

JSON_VALUES = st.recursive(
    st.none() | st.booleans() | st.integers(-(2**70), 2**70) | st.floats() | st.text(max_size=8),
    lambda inner: st.lists(inner, max_size=3) | st.dictionaries(st.text(max_size=6), inner, max_size=3),
    max_leaves=8,
)


def _paths(value: object, prefix: tuple = ()) -> list[tuple]:
    """Every place in a JSON value (key paths), the root included."""
    out = [prefix]
    if isinstance(value, dict):
        for k, v in value.items():
            out += _paths(v, (*prefix, k))
    elif isinstance(value, list):
        for i, v in enumerate(value):
            out += _paths(v, (*prefix, i))
    return out


def _replace(value: object, path: tuple, new: object) -> object:
    if not path:
        return new
    out = copy.deepcopy(value)
    node = out
    for part in path[:-1]:
        node = node[part]  # type: ignore[index]
    node[path[-1]] = new  # type: ignore[index]
    return out


@st.composite
def mutated_summaries(draw) -> object:
    paths = _paths(SUMMARY)
    path = draw(st.sampled_from(paths))
    return _replace(SUMMARY, path, draw(JSON_VALUES))


def _profile() -> FunctionProfile:
    return FunctionProfile(rows=[], clock_ns=4.0)


@settings(max_examples=200, deadline=None)
@given(mutated_summaries())
def test_a_summary_is_checked_or_refused_by_field_and_then_used_without_error(summary) -> None:
    text = json.dumps(summary, allow_nan=True)
    try:
        data = load_summary(text, "run/summary.json")
    except SummaryError as exc:
        message = str(exc)
        assert message.startswith("run/summary.json: ") and "\n" not in message
        return
    # what report and profile do with an accepted summary must work
    summary_mismatches(_profile(), data)
    check_summary(data, "again")


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(summary=mutated_summaries())
def test_report_on_a_mutated_summary_exits_0_or_2(tmp_path: Path, summary) -> None:
    folder = tmp_path / "run"
    folder.mkdir(exist_ok=True)
    (folder / "summary.json").write_text(json.dumps(summary, allow_nan=True))
    try:
        run = read_run_folder(folder)
    except RunFolderError as exc:
        assert str(exc).startswith(f"{folder / 'summary.json'}: ")
        return
    render_report(run)


def test_report_and_profile_refuse_a_summary_of_the_wrong_shape_before_flying(tmp_path: Path) -> None:
    folder = tmp_path / "run"
    folder.mkdir()
    (folder / "scenario.toml").write_text('name = "default"\nduration_s = 0.05\n')
    (folder / "summary.json").write_text(json.dumps(_replace(SUMMARY, ("cycles",), [1, 2])))
    result = CliRunner().invoke(app, ["profile", str(folder)])
    assert result.exit_code == 2 and "Traceback" not in result.output
    assert f"{folder / 'summary.json'}: cycles: expected an object or null, got a list" in result.output
    assert "profiling" not in result.output  # refused before the re-flight
    (folder / "summary.json").write_text(json.dumps(_replace(SUMMARY, ("chip",), "2x2")))
    result = CliRunner().invoke(app, ["report", str(folder)])
    assert result.exit_code == 2 and "chip: expected an object or null" in result.output


def test_nan_and_infinity_are_not_json_numbers(tmp_path: Path) -> None:
    with pytest.raises(SummaryError, match="NaN is not a JSON number"):
        load_summary('{"simulated_s": NaN}', "s.json")
    with pytest.raises(SummaryError, match="Infinity is not a JSON number"):
        load_summary('{"energy": {"total_uj": -Infinity}}', "s.json")
    with pytest.raises(SummaryError, match="nested more than"):
        load_summary("[" * 100 + "]" * 100, "s.json")
    with pytest.raises(SummaryError, match="nested"):
        load_summary('{"a": ' + "[" * 100_000 + "]" * 100_000 + "}", "s.json")


# --- flight.csv ----------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def rows() -> np.ndarray:
    from run_folders import chip_rows, host_rows

    return chip_rows(host_rows(0.1, seed=3))  # 10 rows, the estimate NaN as the chip logs it


def _write(path: Path, cells: list[list[str]]) -> None:
    path.write_text(",".join(ROW_FIELDS) + "\n" + "".join(",".join(c) + "\n" for c in cells))


def _cells(rows: np.ndarray) -> list[list[str]]:
    return [[repr(float(v)) for v in row] for row in rows]


BAD_CELLS = st.sampled_from(["nan", "inf", "-inf", "1e400", "-1", "1e300", "", "abc", "0x10", "1,5"]) | st.floats(
    allow_nan=True, allow_infinity=True
).map(repr)


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(data=st.data())
def test_a_flight_log_is_read_and_replayable_or_refused_by_row_and_column(tmp_path: Path, rows, data) -> None:
    cells = _cells(rows)
    kind = data.draw(st.sampled_from(["cell", "time", "shuffle", "drop", "header only", "extra"]))
    if kind == "cell":
        k = data.draw(st.integers(0, len(cells) - 1))
        c = data.draw(st.integers(0, len(ROW_FIELDS) - 1))
        cells[k][c] = data.draw(BAD_CELLS)
    elif kind == "time":
        k = data.draw(st.integers(0, len(cells) - 1))
        cells[k][0] = repr(data.draw(st.floats(-1e9, 1e12) | st.sampled_from([11 * 86400.0, -0.01, 3600.5])))
    elif kind == "shuffle":
        cells = data.draw(st.permutations(cells))
    elif kind == "drop":
        k = data.draw(st.integers(0, len(cells) - 1))
        cells[k] = cells[k][: data.draw(st.integers(0, len(ROW_FIELDS) - 1))]
    elif kind == "header only":
        cells = []
    else:
        cells[0].append("1.0")
    path = tmp_path / "flight.csv"
    _write(path, cells)
    try:
        back = read_flight_log(path)
    except FlightLogError as exc:
        message = str(exc)
        assert message.startswith(f"{path}: ") and "\n" not in message
        if kind in ("cell", "time"):
            assert "row " in message and ("column " in message or "values, expected" in message)
        return
    assert np.isfinite(back[:, 0]).all() and (np.diff(back[:, 0]) > 0).all()
    if len(back):
        samples_from_rows(back, 4.0)  # what firmware replay does first: no exception


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (lambda c: c[3].__setitem__(ROW_FIELDS.index("gyro_x"), "nan"), "row 4 (line 5), column gyro_x: nan"),
        (lambda c: c[3].__setitem__(ROW_FIELDS.index("accel_z"), "inf"), "row 4 (line 5), column accel_z: inf"),
        (
            lambda c: c.__setitem__(slice(2, 6), [c[5], c[3], c[4], c[2]]),
            "column t: 0.03 s is not after the row before (0.05 s)",
        ),
        (lambda c: c[0].__setitem__(0, "-1.0"), "row 1 (line 2), column t: -1.0 s is outside 0..3600 s"),
        (lambda c: [r.__setitem__(0, repr(float(r[0]) + 11 * 86400)) for r in c[5:]], "row 6 (line 7), column t"),
        (lambda c: c.clear(), "no rows after the header"),
    ],
)
def test_firmware_replay_refuses_a_bad_flight_log_naming_row_and_column(tmp_path: Path, rows, change, message):
    cells = _cells(rows)
    change(cells)
    path = tmp_path / "flight.csv"
    _write(path, cells)
    result = CliRunner().invoke(app, ["firmware", "replay", str(path)])
    assert result.exit_code == 2, result.output
    assert "Traceback" not in result.output and message in result.output and str(path) in result.output


def test_the_flight_log_writer_and_reader_agree(tmp_path: Path, rows) -> None:
    with CsvFlightLog(tmp_path / "flight.csv") as log:
        for row in rows:
            log.write(row)
    np.testing.assert_array_equal(read_flight_log(tmp_path / "flight.csv"), rows)


# --- jobs.csv ------------------------------------------------------------------------------------


@settings(max_examples=100, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(cell=BAD_CELLS, k=st.integers(0, 2), column=st.sampled_from(JOB_CSV_FIELDS[2:]))
def test_a_job_record_file_is_read_or_refused_by_row_and_column(tmp_path: Path, cell, k, column) -> None:
    good = ["pid", "1,0", "1", "10", "12", "20", "10", "8", "100", "1.0", "1.0", "0.0", "0.5", "1"]
    lines = [list(good) for _ in range(3)]
    lines[k][JOB_CSV_FIELDS.index(column)] = cell
    path = tmp_path / "jobs.csv"
    path.write_text(",".join(JOB_CSV_FIELDS) + "\n" + "".join(",".join(line) + "\n" for line in lines))
    try:
        jobs = read_jobs(path, [])
    except RunFolderError as exc:
        assert str(exc).startswith(f"{path}: row ") and (
            f"column {column}" in str(exc) or "values, expected" in str(exc)
        )
        return
    for name in JOB_CSV_FIELDS[2:]:
        assert np.isfinite(jobs[name]).all() and (jobs[name] >= 0).all()


# --- a sweep's records ---------------------------------------------------------------------------

RECORD = {"key": "0123456789abcdef", "index": 0, "seed": 1, "values": {"sensors.noise": True}, "status": "ok",
          "error": "", "worker_s": 0.5, "summary": SUMMARY}  # fmt: skip


@settings(max_examples=200, deadline=None)
@given(st.data())
def test_a_sweep_record_is_checked_or_refused_by_file_and_field(data) -> None:
    path = data.draw(st.sampled_from(_paths(RECORD)[1:]))
    record = _replace(RECORD, path, data.draw(JSON_VALUES))
    if path == ("key",):
        return  # a record whose key is not its file name is skipped (a stray file), not refused
    where = Path("out/results/0123456789abcdef.json")
    try:
        check_record(record, where)  # type: ignore[arg-type]
    except RecordError as exc:
        assert str(exc).startswith(f"{where}: ") and "delete the file" in str(exc)
        return
    assert isinstance(record, dict) and not any(isinstance(v, float) and not math.isfinite(v) for v in [0.0])


def test_a_sweep_resume_with_a_gutted_record_names_it(tmp_path: Path) -> None:
    sweep = tmp_path / "s.toml"
    sweep.write_text('metrics = ["flight.hover_max_m"]\n[base]\nduration_s = 0.03\ncontroller = "host"\n')
    out = tmp_path / "out"
    store = SweepStore(out)
    from robosoc.config.sweep import load_sweep
    from robosoc.sweep.plan import plan

    key = plan(load_sweep(sweep))[0].key
    (store.results_dir / f"{key}.json").write_text(json.dumps({"key": key}))
    result = CliRunner().invoke(app, ["sweep", str(sweep), "--out", str(out), "--workers", "1"])
    assert result.exit_code == 2 and "Traceback" not in result.output
    assert f"{store.results_dir / f'{key}.json'}: index: missing" in result.output


def test_a_summary_key_with_a_line_break_is_named_quoted_on_one_line() -> None:
    from robosoc.outputs.run_summary import SummaryError, check_summary

    with pytest.raises(SummaryError) as refused:
        check_summary({"energy": {"tiles_uj": {"0,1\n": False}}}, "run/summary.json")
    assert str(refused.value) == 'run/summary.json: energy.tiles_uj["0,1\\n"]: expected a number or null, got false'
    with pytest.raises(SummaryError, match=r"^run/summary\.json: energy\.tiles_uj\.0,1: expected"):
        check_summary({"energy": {"tiles_uj": {"0,1": "x"}}}, "run/summary.json")
