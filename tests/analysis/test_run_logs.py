"""The one call a fly run makes for its logs: MCAP always, the chip trace only for a chip run that
recorded its timeline, and the report last (it reads the folder back)."""

from __future__ import annotations

import json
from pathlib import Path
from types import SimpleNamespace

from mcap.reader import make_reader

from robosoc.control.flight import ROW_FIELDS
from robosoc.control.flight_log import read_flight_log
from robosoc.outputs.run_folder import CHIP_TRACE_JSON, FLIGHT_CSV, FLIGHT_MCAP, REPORT_HTML
from robosoc.outputs.run_logs import write_run_logs
from ros_bags import convert, field, read_bag
from run_folders import chip_rows


def _messages(path: Path) -> int:
    with path.open("rb") as stream:
        return sum(1 for _ in make_reader(stream).iter_messages())


def test_a_chip_run_gets_its_mcap_trace_and_report(chip_flight, chip_run: Path):
    rows = chip_rows(chip_flight.rows)
    written = write_run_logs(chip_run, rows, chip_flight.run, chip_flight.result, {"scenario": "s-42"})
    assert written == {
        "mcap": chip_run / FLIGHT_MCAP,
        "trace": chip_run / CHIP_TRACE_JSON,
        "report": chip_run / REPORT_HTML,
    }
    assert _messages(written["mcap"]) > len(rows)  # several topics per row
    trace = json.loads(written["trace"].read_text())
    assert trace["otherData"]["scenario"] == "s-42"
    assert trace["otherData"]["firmware"] == chip_flight.result.firmware.label
    assert any(e.get("name") == "estimator" for e in trace["traceEvents"])
    page = written["report"].read_text()
    assert page.startswith("<!DOCTYPE html>") and "controller chip" in page


def test_rosbags_reads_and_converts_a_chip_runs_mcap(chip_flight, chip_run: Path, tmp_path: Path):
    """The run folder's flight.mcap, as fly writes it, against its flight.csv: every topic decoded
    by rosbags, the IMU equal to the gyro and accelerometer columns, /tf to the true pose (the chip
    keeps its estimate: no estimate topics, no estimate frame)."""
    write_run_logs(chip_run, chip_rows(chip_flight.rows), chip_flight.run, chip_flight.result)
    csv = read_flight_log(chip_run / FLIGHT_CSV)
    col = {name: csv[:, k] for k, name in enumerate(ROW_FIELDS)}
    messages, bag = read_bag(chip_run / FLIGHT_MCAP)
    assert bag.is2 and not {"/estimate/pose", "/estimate/euler"} & set(messages)
    assert all(len(v) == len(csv) for v in messages.values()) and len(messages) == 10
    imu = [m.message for m in messages["/imu"]]
    for k, axis in enumerate("xyz"):
        assert [field(m, f"angular_velocity.{axis}") for m in imu] == list(col[f"gyro_{axis}"])
        assert [field(m, f"linear_acceleration.{axis}") for m in imu] == list(col[f"accel_{axis}"])
        assert [field(m.message, f"transforms.0.transform.translation.{axis}") for m in messages["/tf"]] == list(
            col["xyz"[k]]
        )
    assert {tuple(t.child_frame_id for t in m.message.transforms) for m in messages["/tf"]} == {("base_link",)}
    assert [m.timestamp for m in messages["/pwm"]] == [1_767_225_600 * 10**9 + round(t * 1e9) for t in col["t"]]
    result = convert(chip_run / FLIGHT_MCAP, tmp_path / "flight.bag")
    assert result.returncode == 0, result.stderr
    converted, ros1 = read_bag(tmp_path / "flight.bag")
    assert not ros1.is2 and {k: len(v) for k, v in converted.items()} == {k: len(v) for k, v in messages.items()}


def test_a_host_run_or_a_run_without_a_timeline_gets_no_trace(chip_flight, chip_run: Path, host_flight, host_run: Path):
    written = write_run_logs(host_run, host_flight)
    assert written == {"mcap": host_run / FLIGHT_MCAP, "report": host_run / REPORT_HTML}
    assert not (host_run / CHIP_TRACE_JSON).exists()
    assert _messages(written["mcap"]) > len(host_flight)

    # a result without its run, or a run whose chip did not record, writes no trace either
    assert "trace" not in write_run_logs(chip_run, chip_rows(chip_flight.rows), None, chip_flight.result)
    quiet = SimpleNamespace(chip=SimpleNamespace(recording=False))  # a run whose chip kept no timeline
    assert "trace" not in write_run_logs(chip_run, chip_rows(chip_flight.rows), quiet, chip_flight.result)
    assert not (chip_run / CHIP_TRACE_JSON).exists()
