"""Run folders for the log and report tests, written here the way ``robosoc fly`` writes them
(docs/results-logs.md): a short host flight, and the same flight replayed into the firmware on the
chip (its rows with the estimate unknown, as the chip controller logs them, plus jobs.csv)."""

from __future__ import annotations

import json
import math
from collections import defaultdict
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from robosoc.chip.energy import EnergyModel
from robosoc.config.firmware import FirmwareConfig
from robosoc.config.scenario import ScenarioConfig
from robosoc.config.vehicle import vehicle_preset
from robosoc.control.flight import ROW_FIELDS, fly
from robosoc.control.flight_log import CsvFlightLog
from robosoc.control.host import HostController
from robosoc.cosim.firmware_run import FirmwareRun, ReplayResult
from robosoc.cosim.replay import samples_from_rows
from robosoc.host.scenario_image import firmware_image
from robosoc.outputs.run_folder import write_jobs_csv
from robosoc.outputs.run_summary import task_summary

HOST_SECONDS = 1.0
CHIP_SECONDS = 0.3


def host_rows(seconds: float = HOST_SECONDS, seed: int = 5) -> np.ndarray:
    scenario = ScenarioConfig(duration_s=seconds, seed=seed)
    vehicle = vehicle_preset(scenario.vehicle)
    return fly(scenario, vehicle, HostController.for_scenario(scenario, vehicle))


def _write_rows(folder: Path, rows: np.ndarray) -> None:
    with CsvFlightLog(folder / "flight.csv") as log:
        for row in rows:
            log.write(row)


def _scenario_toml(folder: Path, seconds: float) -> None:
    (folder / "scenario.toml").write_text(f'name = "default"\nduration_s = {seconds}\nvehicle = "default"\n')


def write_host_run(folder: Path, rows: np.ndarray) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    _write_rows(folder, rows)
    _scenario_toml(folder, HOST_SECONDS)
    summary = {
        "schema": 1, "complete": True, "scenario": "default", "seed": 5, "controller": "host", "mode": "lockstep",
        "firmware": None, "chip": None, "simulated_s": HOST_SECONDS, "host_s": 0.5, "real_time_factor": 2.0,
        "flight": {"hover_rms_m": None, "tracking_rms_deg": {"roll": 0.5, "pitch": 0.4, "yaw": None}},
    }  # fmt: skip
    (folder / "summary.json").write_text(json.dumps(summary, allow_nan=False))
    return folder


def chip_rows(rows: np.ndarray) -> np.ndarray:
    """The rows as the chip controller logs them: the estimate stays on the chip (NaN)."""
    out = rows.copy()
    for name in ROW_FIELDS:
        if name.startswith("est_"):
            out[:, ROW_FIELDS.index(name)] = math.nan
    return out


@dataclass(frozen=True)
class ChipReplay:
    rows: np.ndarray
    run: FirmwareRun  # the chip recorded its timeline
    result: ReplayResult


def chip_replay(seconds: float = CHIP_SECONDS) -> ChipReplay:
    """The host flight's samples replayed into the fixed+mul firmware, step by step as
    :func:`robosoc.cosim.replay.replay` does it, keeping the firmware run for its timeline."""
    rows = host_rows(seconds, seed=6)
    fw = FirmwareConfig()
    run = FirmwareRun(fw, firmware_image(fw))
    samples = samples_from_rows(rows, run.clock_ns)
    period = samples[1].cycle - samples[0].cycle
    for k, sample in enumerate(samples):
        run.inject(sample)
        run.run_to(samples[k + 1].cycle if k + 1 < len(samples) else sample.cycle + period)
        run.close_period()
    return ChipReplay(rows, run, run.result())


def write_chip_run(folder: Path, chip: ChipReplay) -> Path:
    rows, result = chip.rows, chip.result
    folder.mkdir(parents=True, exist_ok=True)
    _write_rows(folder, chip_rows(rows))
    _scenario_toml(folder, CHIP_SECONDS)
    write_jobs_csv(result.jobs, folder / "jobs.csv")
    model = EnergyModel.load()
    classes: dict[str, float] = defaultdict(float)
    for counters in result.counters.values():
        for name, pj in model.breakdown_pj(counters).items():
            classes[name] += pj / 1e6
    fw = result.firmware
    summary = {
        "schema": 1, "complete": True, "scenario": "default", "seed": 6, "controller": "chip", "mode": "lockstep",
        "firmware": {"build": fw.label, "project": fw.project, "tiles": {"estimator": [0, 1], "pid": [1, 0]}},
        "chip": {"width": 2, "height": 2, "clock_ns": result.clock_ns},
        "simulated_s": CHIP_SECONDS, "host_s": result.host_seconds, "real_time_factor": None,
        "tasks": task_summary(result.jobs, result.clock_ns), "deadline_misses": result.deadline_misses,
        "energy": {
            "total_uj": sum(result.energy_pj.values()) / 1e6,
            "tiles_uj": {f"{k[5:].strip('()').replace(' ', '')}": v / 1e6 for k, v in result.energy_pj.items()
                         if k.startswith("tile")},
            "noc_uj": result.energy_pj["noc"] / 1e6,
            "classes_uj": {k: v for k, v in classes.items() if v > 0},
        },
    }  # fmt: skip
    (folder / "summary.json").write_text(json.dumps(summary))
    return folder
