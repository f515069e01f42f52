"""``summary.json`` of a fly run, built from hand-made job records and counters whose figures are
worked out here by hand (docs/results-logs.md gives the schema)."""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path

import numpy as np
import pytest

from robosoc import output_files
from robosoc.config.firmware import FirmwareConfig
from robosoc.config.scenario import ScenarioConfig
from robosoc.config.vehicle import vehicle_preset
from robosoc.control.flight import ROW_FIELDS, flight_metrics
from robosoc.cosim.firmware_run import ReplayResult
from robosoc.outputs.run_summary import (
    HOST_TIMING_KEYS,
    SCHEMA,
    TASK_KEYS,
    fleet_summary,
    flight_summary,
    json_safe,
    vehicle_summary,
    write_summary,
)
from robosoc.records import JobRecord
from run_folders import host_rows

CLOCK_NS = 4.0


def job(
    task: str, tile: tuple[int, int], n: int, release: int, start: int, done: int, ok: bool, pj: float
) -> JobRecord:
    parts = {"task": pj * 0.5, "kernel": pj * 0.25, "idle": pj * 0.125, "noc": pj * 0.125}
    return JobRecord(task, tile, n, release, start, done, done - start, ok, 100, parts, False)


def result() -> ReplayResult:
    """Two estimator jobs and one PID job on a 2x2 chip; the second estimator job misses its deadline."""
    fw = FirmwareConfig(arith="float", multiplier=False)
    jobs = [
        job("estimator", (0, 1), 0, 1000, 1010, 3010, True, 8000.0),  # response 2010 cycles
        job("estimator", (0, 1), 1, 5000, 5020, 9990, False, 16000.0),  # response 4990 cycles
        job("pid", (1, 0), 0, 1000, 1100, 1600, True, 2000.0),  # response 600 cycles
    ]
    counters = {(0, 1): {"cycles": 12_000}, (1, 0): {"cycles": 11_000}}
    energy = {"tile (0, 1)": 3_000_000.0, "tile (1, 0)": 1_000_000.0, "noc": 500_000.0}
    return ReplayResult(fw, CLOCK_NS, [], [], jobs, {}, counters, {}, energy, 12_345, 0.5)


def test_a_chip_vehicle_summary_holds_the_hand_worked_figures():
    scenario = ScenarioConfig(name="s1", seed=9, firmware=FirmwareConfig(arith="float", multiplier=False))
    summary = vehicle_summary(scenario, np.zeros((0, len(ROW_FIELDS))), 0.1, result(), 2.0, 0.5)
    assert {k: summary[k] for k in ("schema", "complete", "scenario", "seed", "controller", "mode")} == {
        "schema": SCHEMA,
        "complete": True,
        "scenario": "s1",
        "seed": 9,
        "controller": "chip",
        "mode": "lockstep",
    }
    assert summary["firmware"] == {
        "build": "float-no-mul",
        "arith": "float",
        "multiplier": False,
        "release": scenario.firmware.release,
        "scheduler": scenario.firmware.scheduler,
        "project": "",
        "tiles": {"estimator": [0, 1], "pid": [1, 0]},
    }
    assert summary["chip"] == {"width": 2, "height": 2, "clock_ns": CLOCK_NS}
    assert (summary["simulated_s"], summary["host_s"], summary["real_time_factor"]) == (2.0, 0.5, 4.0)
    assert summary["flight"] is None  # no rows
    est = summary["tasks"]["estimator"]
    assert list(est) == list(TASK_KEYS)
    assert est["jobs"] == 2
    assert est["response_us_mean"] == pytest.approx((2010 + 4990) / 2 * 4 / 1000)
    assert est["response_us_max"] == pytest.approx(4990 * 4 / 1000)
    assert est["exec_cycles_mean"] == (2000 + 4970) / 2 and est["exec_cycles_max"] == 4970
    assert est["energy_nj_mean"] == pytest.approx(12.0)
    assert est["energy_nj_kernel_mean"] == pytest.approx(3.0)
    assert est["deadline_misses"] == 1
    assert summary["tasks"]["pid"]["response_us_max"] == pytest.approx(2.4)
    assert summary["deadline_misses"] == 1
    assert summary["energy"] == {"total_uj": 4.5, "tiles_uj": {"0,1": 3.0, "1,0": 1.0}, "noc_uj": 0.5}
    assert summary["cycles"] == {"chip": 12_345, "tiles": {"0,1": 12_000, "1,0": 11_000}}
    assert "stopped" not in summary


def test_a_host_vehicle_summary_has_no_chip_parts_and_an_interrupted_one_says_why():
    scenario = ScenarioConfig(controller="host")
    summary = vehicle_summary(
        scenario, np.zeros((0, len(ROW_FIELDS))), 0.1, None, 1.5, 0.0, complete=False, stopped="Ctrl-C"
    )
    for key in ("firmware", "chip", "tasks", "deadline_misses", "energy", "cycles", "flight"):
        assert summary[key] is None, key
    assert summary["complete"] is False and summary["stopped"] == "Ctrl-C"
    assert math.isnan(summary["real_time_factor"])  # no host time measured
    assert summary["controller"] == "host"


def test_the_chip_clock_comes_from_the_chip_config_without_a_result():
    scenario = ScenarioConfig()
    summary = vehicle_summary(scenario, np.zeros((0, len(ROW_FIELDS))), 0.1, None, 1.0, 1.0)
    assert summary["chip"]["clock_ns"] == scenario.chip.tile.clock_period_ns
    assert summary["firmware"]["build"] == scenario.firmware.label


@pytest.fixture(scope="module")
def hover_flight() -> np.ndarray:
    """A host flight long enough to take off and hover (take-off at 3 s, climb 1.5 s)."""
    return host_rows(6.0, seed=5)


def test_flight_figures_are_the_flight_metrics_and_the_estimate_is_null_when_unseen(hover_flight):
    host_flight = hover_flight
    scenario = ScenarioConfig(duration_s=6.0)
    rest = vehicle_preset(scenario.vehicle).rest_height
    m = flight_metrics(host_flight, scenario.flight, rest)
    assert all(math.isfinite(v) for v in (m.hover_rms, m.ekf_rms, *m.tracking_rms))
    figures = flight_summary(host_flight, scenario, rest)
    assert figures == {
        "hover_rms_m": m.hover_rms,
        "hover_max_m": m.hover_max,
        "overshoot_m": m.overshoot,
        "tracking_rms_deg": {"roll": m.tracking_rms[0], "pitch": m.tracking_rms[1], "yaw": m.tracking_rms[2]},
        "step_rise_s": [{"axis": a, "time_s": t, "rise_s": r} for a, t, r in m.step_rise],
        "attitude_estimate_rms_deg": m.ekf_rms,
        "height_estimate_rms_m": m.height_estimate_rms,
    }
    hidden = host_flight.copy()
    armed = hidden[:, ROW_FIELDS.index("armed")] > 0.5
    assert armed.any()
    hidden[np.flatnonzero(armed)[-1], ROW_FIELDS.index("est_qx")] = math.nan  # one armed row unseen
    assert math.isnan(flight_summary(hidden, scenario, rest)["attitude_estimate_rms_deg"])
    hidden = host_flight.copy()
    hidden[~armed, ROW_FIELDS.index("est_qw")] = math.nan  # unseen only while disarmed: still seen
    assert flight_summary(hidden, scenario, rest)["attitude_estimate_rms_deg"] == m.ekf_rms


def test_a_fleet_summary_adds_up_the_misses_of_its_vehicles():
    scenario = ScenarioConfig(name="fleet", vehicles=3)
    vehicles = [{"deadline_misses": 2}, {"deadline_misses": None}, {"deadline_misses": 3}]
    summary = fleet_summary(scenario, vehicles, 4.0, 2.0, min_separation_m=0.75)
    assert summary == {
        "schema": SCHEMA,
        "complete": True,
        "scenario": "fleet",
        "seed": 1,
        "controller": "chip",
        "mode": "lockstep",
        "simulated_s": 4.0,
        "host_s": 2.0,
        "real_time_factor": 2.0,
        "deadline_misses": 5,
        "min_separation_m": 0.75,
        "vehicles": vehicles,
    }
    host = fleet_summary(ScenarioConfig(controller="host"), vehicles, 1.0, 1.0, min_separation_m=1.0, stopped="crash")
    assert host["deadline_misses"] is None and host["stopped"] == "crash"
    assert set(HOST_TIMING_KEYS) == {"host_s", "real_time_factor"}


def test_json_safe_turns_nan_and_infinities_into_null_and_numpy_into_plain_values():
    value = {"a": [1.0, math.nan, (np.float64(math.inf), np.int64(3))], "b": {"c": -math.inf, "d": np.float32(0.5)}}
    safe = json_safe(value)
    assert safe == {"a": [1.0, None, [None, 3]], "b": {"c": None, "d": 0.5}}
    assert type(safe["a"][2][1]) is int and type(safe["b"]["d"]) is float
    assert json_safe("text") == "text" and json_safe(None) is None and json_safe(True) is True


def test_write_summary_writes_json_with_null_for_nan_and_leaves_no_temporary(tmp_path: Path):
    path = tmp_path / "summary.json"
    write_summary({"x": math.nan, "y": [1, 2]}, path)
    text = path.read_text()
    assert text.endswith("}\n") and "\n  " in text  # indented, one trailing newline
    assert json.loads(text) == {"x": None, "y": [1, 2]}
    assert sorted(p.name for p in tmp_path.iterdir()) == ["summary.json"]
    write_summary({"x": 1}, path)  # replaces
    assert json.loads(path.read_text()) == {"x": 1}


def test_the_chip_clock_is_the_runs_own_when_there_is_one():
    scenario = ScenarioConfig()
    run = dataclasses.replace(result(), clock_ns=scenario.chip.tile.clock_period_ns * 2.5)
    summary = vehicle_summary(scenario, np.zeros((0, len(ROW_FIELDS))), 0.1, run, 1.0, 1.0)
    assert summary["chip"]["clock_ns"] == scenario.chip.tile.clock_period_ns * 2.5


def test_a_summary_file_is_two_space_json_and_an_interrupted_write_keeps_the_last_one(tmp_path: Path, monkeypatch):
    path = tmp_path / "summary.json"
    write_summary({"a": 1, "b": {"c": [1, 2]}, "é": math.nan}, path)
    assert path.read_bytes() == (
        b'{\n  "a": 1,\n  "b": {\n    "c": [\n      1,\n      2\n    ]\n  },\n  "\\u00e9": null\n}\n'
    )

    def interrupted(src, dst):
        raise KeyboardInterrupt

    monkeypatch.setattr(output_files.os, "replace", interrupted)
    with pytest.raises(KeyboardInterrupt):
        write_summary({"a": 2}, path)
    assert json.loads(path.read_text()) == {"a": 1, "b": {"c": [1, 2]}, "é": None}  # still the last whole one
    assert not (tmp_path / "summary.json.partial").exists()  # the unfinished one is removed


def test_a_vehicle_summary_of_a_flight_holds_its_flight_figures(hover_flight):
    scenario = ScenarioConfig(duration_s=6.0, controller="host")
    rest = vehicle_preset(scenario.vehicle).rest_height
    summary = vehicle_summary(scenario, hover_flight, rest, None, 6.0, 3.0)
    assert summary["flight"] == flight_summary(hover_flight, scenario, rest)
    assert summary["flight"]["hover_rms_m"] < 0.5
