"""``fly_scenario``: the run folder, summary.json, each firmware build, several vehicles, interruption."""

from __future__ import annotations

import csv
import dataclasses
import json
import math
import tomllib
from pathlib import Path

import numpy as np
import pytest

from robosoc.config.firmware import FirmwareConfig
from robosoc.config.scenario import FlightPlan, ScenarioConfig, SetpointStep
from robosoc.config.validate import from_mapping
from robosoc.config.vehicle import vehicle_preset
from robosoc.control.flight import ROW_FIELDS, column, fly
from robosoc.control.flight_log import read_flight_log
from robosoc.control.host import HostController
from robosoc.outputs.flight_session import SPACING_M, fly_scenario
from robosoc.outputs.run_folder import JOB_CSV_FIELDS
from robosoc.outputs.run_summary import HOST_TIMING_KEYS, TASK_KEYS
from robosoc.records import ENERGY_PARTS

# calibrate until 1 s, climb to 1 m by 2.5 s, a 10° roll step at 2.6 s: 3.6 s in all
SHORT = ScenarioConfig(
    duration_s=3.6,
    flight=FlightPlan(takeoff_s=1.0, steps=(SetpointStep(2.6, "roll", 10.0),)),
    wind=dataclasses.replace(ScenarioConfig().wind, gusts=()),
)
REST = vehicle_preset("default").rest_height


@pytest.mark.parametrize(
    "fw",
    [FirmwareConfig(arith=a, multiplier=m) for a in ("fixed", "float") for m in (True, False)],
    ids=lambda fw: fw.label,
)
def test_each_build_takes_off_and_follows_a_roll_step(fw: FirmwareConfig) -> None:
    flight = fly_scenario(dataclasses.replace(SHORT, firmware=fw), None, plot=False)
    rows, summary = flight.rows[0], flight.summary
    t, z = column(rows, "t"), column(rows, "z")
    assert len(rows) == 360
    assert z[(t > 0.5) & (t < 0.99)].max() < REST + 0.01, "resting on the ground until take-off"
    assert abs(z[-1] - 1.0) < 0.1, "at the 1 m target after the climb"
    # 90 % of the roll step within 1 s (the requirement), measured independently here
    after = t >= 2.6
    reached = np.nonzero(column(rows, "roll")[after] >= 0.9 * math.radians(10.0))[0]
    assert reached.size and t[after][reached[0]] - 2.6 < 1.0
    assert summary["flight"]["step_rise_s"][0]["rise_s"] == pytest.approx(t[after][reached[0]] - 2.6)
    assert summary["deadline_misses"] == 0
    assert summary["firmware"]["build"] == fw.label
    for task in ("estimator", "pid"):
        assert summary["tasks"][task]["jobs"] == 360


def _strip_timing(summary: dict) -> dict:
    out = {k: v for k, v in summary.items() if k not in HOST_TIMING_KEYS}
    if "vehicles" in out:
        out["vehicles"] = [_strip_timing(v) for v in out["vehicles"]]
    return out


@pytest.fixture(scope="module")
def two_runs(tmp_path_factory) -> list[Path]:
    scenario = ScenarioConfig(duration_s=1.3, flight=FlightPlan(takeoff_s=0.5, steps=()))
    folders = []
    for n in range(2):
        out = tmp_path_factory.mktemp(f"run{n}")
        fly_scenario(dataclasses.replace(scenario, seed=7), out, plot=False)
        folders.append(out)
    return folders


def test_two_runs_are_identical_byte_for_byte(two_runs: list[Path]) -> None:
    a, b = two_runs
    for name in ("flight.csv", "jobs.csv", "scenario.toml"):
        assert (a / name).read_bytes() == (b / name).read_bytes(), name
    first, second = (json.loads((f / "summary.json").read_text()) for f in two_runs)
    assert _strip_timing(first) == _strip_timing(second)
    assert first["host_s"] > 0


def test_the_run_folder_keeps_the_resolved_scenario(two_runs: list[Path]) -> None:
    data = tomllib.loads((two_runs[0] / "scenario.toml").read_text())
    expected = ScenarioConfig(duration_s=1.3, seed=7, flight=FlightPlan(takeoff_s=0.5, steps=()))
    assert from_mapping(ScenarioConfig, data) == expected
    assert data["seed"] == 7 and data["controller"] == "chip" and data["firmware"]["arith"] == "fixed"


def test_summary_keys_and_task_figures_equal_the_job_records(two_runs: list[Path]) -> None:
    folder = two_runs[0]
    summary = json.loads((folder / "summary.json").read_text())
    assert summary["schema"] == 1 and summary["complete"] is True and summary["mode"] == "lockstep"
    assert summary["controller"] == "chip" and summary["seed"] == 7 and summary["scenario"] == "default"
    assert summary["chip"] == {"width": 2, "height": 2, "clock_ns": 4.0}
    assert summary["firmware"]["tiles"] == {"estimator": [0, 1], "pid": [1, 0]}
    assert summary["firmware"]["project"] == ""  # the shipped quadrotor project
    assert summary["simulated_s"] == pytest.approx(1.3)
    assert summary["real_time_factor"] == pytest.approx(summary["simulated_s"] / summary["host_s"])
    # the chip's estimate, read by the probe, is in the rows: its errors are figures, and small
    flight = summary["flight"]
    assert 0 < flight["attitude_estimate_rms_deg"] < 5, flight
    assert 0 < flight["height_estimate_rms_m"] < 0.5, flight
    with (folder / "jobs.csv").open() as handle:
        jobs = list(csv.DictReader(handle))
    assert tuple(jobs[0]) == JOB_CSV_FIELDS
    clock_ns = summary["chip"]["clock_ns"]
    for task in ("estimator", "pid"):
        mine = [j for j in jobs if j["task"] == task]
        figures = summary["tasks"][task]
        assert tuple(figures) == TASK_KEYS
        assert figures["jobs"] == len(mine) == 130
        response = [int(j["response_cycles"]) for j in mine]
        assert figures["response_us_mean"] == pytest.approx(np.mean(response) * clock_ns / 1000)
        assert figures["response_us_max"] == pytest.approx(max(response) * clock_ns / 1000)
        assert figures["exec_cycles_max"] == max(int(j["exec_cycles"]) for j in mine)
        for part in ENERGY_PARTS:  # jobs.csv keeps 3 decimals of a pJ
            mean_nj = np.mean([float(j[f"{part}_pj"]) for j in mine]) / 1000
            assert figures[f"energy_nj_{part}_mean"] == pytest.approx(mean_nj, abs=1e-6)
        parts = sum(figures[f"energy_nj_{p}_mean"] for p in ENERGY_PARTS)
        assert figures["energy_nj_mean"] == pytest.approx(parts)
        assert figures["deadline_misses"] == sum(j["deadline_met"] == "0" for j in mine) == 0
    energy = summary["energy"]
    assert set(energy["tiles_uj"]) == {"0,1", "1,0"}
    assert energy["total_uj"] == pytest.approx(sum(energy["tiles_uj"].values()) + energy["noc_uj"])
    jobs_uj = sum(float(j[f"{p}_pj"]) for j in jobs for p in ENERGY_PARTS) / 1e6
    assert 0 < jobs_uj <= energy["total_uj"], "the jobs' shares are part of the chip's energy"


def test_the_host_controller_flies_as_the_host_loop() -> None:
    scenario = dataclasses.replace(SHORT, controller="host", duration_s=2.0)
    flight = fly_scenario(scenario, None, plot=False)
    vehicle = vehicle_preset(scenario.vehicle)
    expected = fly(scenario, vehicle, HostController.for_scenario(scenario, vehicle))
    assert flight.rows[0].tobytes() == expected.tobytes()
    summary = flight.summary
    assert summary["firmware"] is None and summary["chip"] is None and summary["tasks"] is None
    assert summary["flight"]["attitude_estimate_rms_deg"] < 5.0, "the host's estimate is in the rows"


def test_two_vehicles_fly_side_by_side_with_their_own_chips_and_noise(tmp_path: Path) -> None:
    scenario = ScenarioConfig(duration_s=1.5, vehicles=2, flight=FlightPlan(takeoff_s=0.5, steps=()))
    flight = fly_scenario(scenario, tmp_path, plot=False)
    top = json.loads((tmp_path / "summary.json").read_text())
    assert len(top["vehicles"]) == 2 and top["complete"] is True and top["deadline_misses"] == 0
    a, b = (read_flight_log(tmp_path / f"vehicle-{i}" / "flight.csv") for i in (1, 2))
    for i, rows in enumerate((a, b), start=1):
        folder = tmp_path / f"vehicle-{i}"
        assert (folder / "jobs.csv").is_file()
        own = json.loads((folder / "summary.json").read_text())
        assert own["tasks"]["pid"]["jobs"] == 150 == len(rows)
        assert column(rows, "z")[-1] > REST + 0.3, f"vehicle {i} took off"
    assert column(b, "x")[0] - column(a, "x")[0] == pytest.approx(SPACING_M)
    gyro = [ROW_FIELDS.index(f"gyro_{c}") for c in "xyz"]
    assert not np.array_equal(a[:, gyro], b[:, gyro]), "each vehicle has its own sensor noise"
    assert top["min_separation_m"] == pytest.approx(SPACING_M, abs=0.2)
    assert flight.rows[0].tobytes() == a.tobytes(), "the log holds the rows exactly"


@pytest.mark.parametrize(
    ("error", "stopped"), [(KeyboardInterrupt(), "interrupted"), (RuntimeError("boom"), "RuntimeError: boom")]
)
def test_a_stopped_flight_leaves_its_rows_and_an_incomplete_summary(tmp_path: Path, error, stopped) -> None:
    def stop(world, k: int) -> None:
        if k == 40:
            raise error

    with pytest.raises(type(error)):
        fly_scenario(ScenarioConfig(duration_s=2.0), tmp_path, on_sample=stop, plot=False)
    rows = read_flight_log(tmp_path / "flight.csv")
    assert len(rows) == 41
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["complete"] is False and summary["stopped"] == stopped
    assert summary["simulated_s"] == pytest.approx(0.41)
    assert summary["tasks"]["estimator"]["jobs"] == 41
    with (tmp_path / "jobs.csv").open() as handle:
        assert sum(1 for j in csv.DictReader(handle) if j["task"] == "estimator") == 41


def test_the_chip_records_its_timeline_only_for_a_trace_that_is_written(tmp_path: Path, monkeypatch) -> None:
    from robosoc.chip.mpsoc import MPSoC

    recorded = []
    record = MPSoC.record_timeline
    monkeypatch.setattr(MPSoC, "record_timeline", lambda self, *a, **k: recorded.append(self) or record(self, *a, **k))
    scenario = dataclasses.replace(SHORT, duration_s=0.3)
    bare = fly_scenario(scenario, None, plot=False)
    assert recorded == []  # nothing is written: no timeline
    kept = fly_scenario(scenario, tmp_path / "run", plot=False)
    assert len(recorded) == 1 and (tmp_path / "run" / "chip-trace.json").is_file()
    assert np.array_equal(bare.rows[0], kept.rows[0], equal_nan=True)
    assert bare.results[0].jobs == kept.results[0].jobs
    fly_scenario(scenario, tmp_path / "no-logs", plot=False, logs=False)
    assert len(recorded) == 1 and not (tmp_path / "no-logs" / "chip-trace.json").exists()
