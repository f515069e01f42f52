"""The one call a fly run makes for its logs: MCAP always, the chip trace only for a chip run that
recorded its timeline, and the report last (it reads the folder back)."""

from __future__ import annotations

import json
from pathlib import Path
from types import SimpleNamespace

from mcap.reader import make_reader

from robosoc.outputs.run_folder import CHIP_TRACE_JSON, FLIGHT_MCAP, REPORT_HTML
from robosoc.outputs.run_logs import write_run_logs
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
