"""Telemetry under names of its own (issue 32, item 4): a project's value lands in ``flight.csv``
(a column after the flight's), in ``flight.mcap`` (``/telemetry/<name>``, read back with rosbags)
and in the report, in lockstep and in the decoupled mode (equal row for row); the readers of
``flight.csv`` keep or read past it."""

from __future__ import annotations

import csv
import json
import math
import re
import shutil
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from headless_chromium import BROWSER, load
from robosoc.cli import app, exit_codes
from robosoc.control.flight import ROW_FIELDS
from robosoc.control.flight_log import CsvFlightLog, FlightLogError, read_flight_log
from robosoc.outputs.ros2_flight import START_NS, stamp_ns
from robosoc.outputs.run_folder import read_run_folder
from ros_bags import read_bag
from telemetry_project import counting_project

SECONDS = 0.3
SAMPLES = 30  # 100 Hz sensor samples in SECONDS


def invoke(*args: object):
    return CliRunner().invoke(app, [str(a) for a in args])


@pytest.fixture(scope="module")
def counted_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    tmp = tmp_path_factory.mktemp("telemetry")
    project = counting_project(tmp)
    out = tmp / "run"
    result = invoke("fly", "--firmware", project, "--duration", SECONDS, "--out", out)
    assert result.exit_code == 0, result.output
    return out


def _expected() -> np.ndarray:
    """One job per sensor sample, each done within its period: the count read at the close of
    period k-1 (row k) is k; row 0 has no read before it (NaN)."""
    return np.array([math.nan, *range(1, SAMPLES)])


def test_flight_csv_gets_the_column_with_the_counted_jobs(counted_run: Path) -> None:
    with (counted_run / "flight.csv").open() as handle:
        header = next(csv.reader(handle))
    assert header == [*ROW_FIELDS, "jobs_counted"]
    telemetry: dict[str, np.ndarray] = {}
    rows = read_flight_log(counted_run / "flight.csv", telemetry=telemetry)
    assert rows.shape == (SAMPLES, len(ROW_FIELDS))
    np.testing.assert_array_equal(telemetry["jobs_counted"], _expected())
    assert read_run_folder(counted_run).telemetry.keys() == {"jobs_counted"}

    out = counted_run.parent / "replayed"  # firmware replay reads the flight's columns past the telemetry
    result = invoke("firmware", "replay", counted_run / "flight.csv", "--out", out)
    assert result.exit_code == 0, result.output


def test_the_mcap_file_has_a_topic_per_value_that_rosbags_decodes(counted_run: Path) -> None:
    messages, bag = read_bag(counted_run / "flight.mcap")
    assert {c.topic: c.msgtype for c in bag.connections}["/telemetry/jobs_counted"] == "std_msgs/msg/Float64"
    got = messages["/telemetry/jobs_counted"]
    rows = read_flight_log(counted_run / "flight.csv")
    times = [stamp_ns(float(t), START_NS) for t in rows[1:, ROW_FIELDS.index("t")]]
    assert [m.timestamp for m in got] == times  # from the first row with a value on
    assert [m.message.data for m in got] == list(range(1, SAMPLES))
    assert "/imu" in messages  # the flight's topics as ever


def test_the_report_plots_the_telemetry(counted_run: Path, tmp_path: Path) -> None:
    text = (counted_run / "report.html").read_text()
    plots = re.findall(r'<figure class="plot" data-plot="([^"]+)"', text)
    assert plots[:4] == ["trajectory", "attitude", "pwm", "telemetry"]
    assert "jobs_counted" in text
    if BROWSER is not None:
        page = load(counted_run / "report.html", tmp_path)
        assert page.console == []
        assert page.body_attribute("data-rendered") == str(len(plots))
    again = tmp_path / "again"
    shutil.copytree(counted_run, again)
    (again / "flight.mcap").unlink()
    result = invoke("report", again, "--mcap")  # the MCAP made again from flight.csv: the same bytes
    assert result.exit_code == 0, result.output
    assert (again / "flight.mcap").read_bytes() == (counted_run / "flight.mcap").read_bytes()


def test_a_name_that_is_a_flight_column_is_refused(tmp_path: Path) -> None:
    project = counting_project(tmp_path, name="roll")
    result = invoke("fly", "--firmware", project, "--duration", 0.05, "--no-out")
    assert result.exit_code == exit_codes.USAGE, result.output
    assert "telemetry[0].name: 'roll' is a column of flight.csv already" in " ".join(result.output.split())


def _log(path: Path, extra: tuple[str, ...], cells: list[list[str]]) -> None:
    rows = np.zeros((len(cells), len(ROW_FIELDS)))
    rows[:, 0] = np.arange(len(cells)) * 0.01
    with CsvFlightLog(path, extra) as log:
        for row, own in zip(rows, cells, strict=True):
            log.write(row, [float(c) for c in own] if all(c != "x" for c in own) else [0.0] * len(own))
    if any("x" in own for own in cells):  # a cell that is not a number, written by hand
        lines = path.read_text().splitlines()
        k = next(i for i, own in enumerate(cells) if "x" in own)
        lines[k + 1] = lines[k + 1].rsplit(",", 1)[0] + ",x"
        path.write_text("\n".join(lines) + "\n")


def test_the_reader_keeps_or_reads_past_telemetry_and_names_bad_cells(tmp_path: Path) -> None:
    path = tmp_path / "flight.csv"
    _log(path, ("a", "b"), [["nan", "1"], ["2", "3"]])
    telemetry: dict[str, np.ndarray] = {}
    rows = read_flight_log(path, telemetry=telemetry)
    assert rows.shape == (2, len(ROW_FIELDS))
    np.testing.assert_array_equal(telemetry["a"], [math.nan, 2.0])
    np.testing.assert_array_equal(telemetry["b"], [1.0, 3.0])
    assert read_flight_log(path).shape == (2, len(ROW_FIELDS))  # read past
    _log(path, ("a",), [["1"], ["x"]])
    with pytest.raises(FlightLogError, match=r"flight\.csv: row 2 \(line 3\), column a: 'x' is not a number$"):
        read_flight_log(path)
    path.write_text(",".join((*ROW_FIELDS, "a", "a")) + "\n")
    with pytest.raises(FlightLogError, match=r"not a robosoc flight log \(repeated column a\)$"):
        read_flight_log(path)
    path.write_text(",".join(("a", *ROW_FIELDS)) + "\n")
    with pytest.raises(FlightLogError, match=r"unknown column a among the flight's columns"):
        read_flight_log(path)


@pytest.fixture(scope="module")
def decoupled_run(counted_run: Path) -> Path:
    """The counting project flown in the decoupled mode (two processes over UDP), paced fast."""
    out = counted_run.parent / "decoupled"
    project = counted_run.parent / "p"
    result = invoke("fly", "--decoupled", "--pace", "fast", "--firmware", project, "--duration", SECONDS, "--out", out)
    assert result.exit_code == 0, result.output
    assert f"telemetry entries logged {SAMPLES - 1} (datagrams refused 0)" in result.output
    return out


def test_the_decoupled_flight_logs_the_telemetry_as_lockstep(counted_run: Path, decoupled_run: Path) -> None:
    """Paced fast without faults the decoupled flight is the lockstep flight: flight.csv has the same
    header and every cell equal (the telemetry's column, the estimate's too), and flight.mcap the
    same /telemetry/jobs_counted messages."""
    for run in (counted_run, decoupled_run):
        with (run / "flight.csv").open() as handle:
            assert next(csv.reader(handle)) == [*ROW_FIELDS, "jobs_counted"]
    told: dict[str, np.ndarray] = {}
    rows = read_flight_log(decoupled_run / "flight.csv", telemetry=told)
    lockstep_told: dict[str, np.ndarray] = {}
    lockstep = read_flight_log(counted_run / "flight.csv", telemetry=lockstep_told)
    np.testing.assert_array_equal(rows, lockstep)
    assert np.isnan(rows[:, [ROW_FIELDS.index(n) for n in ROW_FIELDS if n.startswith("est_")]]).all()  # no estimate
    np.testing.assert_array_equal(told["jobs_counted"], _expected())
    np.testing.assert_array_equal(told["jobs_counted"], lockstep_told["jobs_counted"])
    messages, _ = read_bag(decoupled_run / "flight.mcap")
    expected, _ = read_bag(counted_run / "flight.mcap")
    got = [(m.timestamp, m.message.data) for m in messages["/telemetry/jobs_counted"]]
    assert got == [(m.timestamp, m.message.data) for m in expected["/telemetry/jobs_counted"]]
    summary = json.loads((decoupled_run / "summary.json").read_text())
    # the reads at the close of periods 0 .. SAMPLES-2 go out while the physics flies
    assert summary["link"]["telemetry"] == {"received": SAMPLES - 1, "refused": 0}


def test_each_row_goes_to_the_live_view_with_its_telemetry(counted_run: Path) -> None:
    """fly_scenario hands the live view (``fly --foxglove``) each row with the values of its
    telemetry columns, the ones flight.csv gets."""
    from robosoc.cli.fly import _live_rows
    from robosoc.config.firmware import FirmwareConfig
    from robosoc.config.scenario import ScenarioConfig
    from robosoc.outputs.flight_session import fly_scenario

    class Live:
        def __init__(self) -> None:
            self.told: list[dict[str, float]] = []

        def publish(self, row: np.ndarray, telemetry: dict[str, float]) -> None:
            self.told.append(telemetry)

    live = Live()
    project = counted_run.parent / "p"
    config = ScenarioConfig(duration_s=SECONDS, firmware=FirmwareConfig(project=str(project)))
    fly_scenario(config, None, on_row=_live_rows(live), plot=False, logs=False)
    assert [list(t) for t in live.told] == [["jobs_counted"]] * SAMPLES
    np.testing.assert_array_equal([t["jobs_counted"] for t in live.told], _expected())
