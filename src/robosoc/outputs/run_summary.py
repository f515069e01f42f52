"""The ``summary.json`` of a ``robosoc fly`` run: what a flight achieved and what its tasks cost.

One JSON object per vehicle (schema 1, shared with the other run kinds; floats in the SI unit its
key names, NaN written as ``null``)::

    {"schema": 1, "complete": true, "scenario": "default", "seed": 1, "controller": "chip",
     "mode": "lockstep", "firmware": {...} | null, "chip": {...} | null,
     "simulated_s": 10.0, "host_s": 4.2, "real_time_factor": 2.4,
     "flight": {"hover_rms_m", "hover_max_m", "overshoot_m", "tracking_rms_deg": {"roll", "pitch", "yaw"},
                "step_rise_s": [{"axis", "time_s", "rise_s"}], "attitude_estimate_rms_deg",
                "height_estimate_rms_m"},
     "tasks": {"estimator": {...}, "pid": {...}} | null, "deadline_misses": 0 | null,
     "energy": {"total_uj", "tiles_uj": {"x,y": ...}, "noc_uj"} | null,
     "cycles": {"chip", "tiles": {"x,y": ...}} | null}

``complete`` is false for a flight that was interrupted or crashed: the figures are those of the
rows flown so far, and ``"stopped"`` says why.  The flight figures are
:func:`robosoc.control.flight.flight_metrics` of the rows; the task figures are
:func:`robosoc.outputs.run_summary.task_summary` of the job records (the same records ``jobs.csv`` holds);
``cycles`` holds the chip's last cycle and each application tile's core cycles (what its energy
and a profile's rows add up to, docs/profile.md); the estimate figures are NaN (null) while the
controller's estimate is not visible in the rows.
A run of several vehicles has one such object per vehicle and a top-level one
(:func:`fleet_summary`) with the shared fields and ``"vehicles": [...]``.
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from robosoc import output_files
from robosoc.config.chip import ChipConfig
from robosoc.config.firmware import FirmwareConfig
from robosoc.config.scenario import ScenarioConfig
from robosoc.control.flight import ROW_FIELDS, column, flight_metrics
from robosoc.cosim.firmware_run import ReplayResult
from robosoc.records import ENERGY_PARTS, JobRecord

SCHEMA = 1
MODE_LOCKSTEP = "lockstep"
TASK_KEYS = (
    "jobs",
    "response_us_mean",
    "response_us_max",
    "exec_cycles_mean",
    "exec_cycles_max",
    "energy_nj_mean",
    *(f"energy_nj_{part}_mean" for part in ENERGY_PARTS),
    "deadline_misses",
)
"""The figures of one task in ``summary.json`` (a subset of :func:`task_summary`'s)."""
HOST_TIMING_KEYS = ("host_s", "real_time_factor")
"""The fields that depend on the host's speed (every other field is the same for the same scenario)."""

__all__ = [
    "HOST_TIMING_KEYS",
    "SCHEMA",
    "TASK_KEYS",
    "chip_figures",
    "cycle_figures",
    "energy_figures",
    "firmware_figures",
    "fleet_summary",
    "flight_summary",
    "json_safe",
    "task_figures",
    "vehicle_summary",
    "write_summary",
]


def flight_summary(rows: np.ndarray, scenario: ScenarioConfig, rest_height: float) -> dict[str, Any] | None:
    """The ``flight`` figures of ``rows`` (None without a row)."""
    if len(rows) == 0:
        return None
    m = flight_metrics(rows, scenario.flight, rest_height)
    armed = column(rows, "armed") > 0.5
    seen = not np.isnan(rows[armed][:, [ROW_FIELDS.index(f"est_q{c}") for c in "wxyz"]]).any()
    return {
        "hover_rms_m": m.hover_rms,
        "hover_max_m": m.hover_max,
        "overshoot_m": m.overshoot,
        "tracking_rms_deg": dict(zip(("roll", "pitch", "yaw"), m.tracking_rms, strict=True)),
        "step_rise_s": [{"axis": axis, "time_s": at, "rise_s": rise} for axis, at, rise in m.step_rise],
        "attitude_estimate_rms_deg": m.ekf_rms if seen else math.nan,
        "height_estimate_rms_m": m.height_estimate_rms,
    }


def task_summary(jobs: Sequence[JobRecord], clock_ns: float) -> dict[str, dict[str, float]]:
    """Per task that has jobs, in the order of their first job: job count, mean/max execution cycles and
    response time [us], mean energy per job [nJ] in all and per part (:data:`ENERGY_PARTS`), the
    kernel's share of it, deadline misses."""
    summary: dict[str, dict[str, float]] = {}
    for name in dict.fromkeys(j.task for j in jobs):
        mine = [j for j in jobs if j.task == name]
        if not mine:
            continue
        exec_c = [j.exec_cycles for j in mine]
        resp = [j.response_cycles for j in mine]
        energy = [j.energy_total_pj for j in mine]
        summary[name] = {
            "jobs": len(mine),
            "exec_cycles_mean": sum(exec_c) / len(mine),
            "exec_cycles_max": max(exec_c),
            "response_us_mean": sum(resp) / len(mine) * clock_ns / 1000,
            "response_us_max": max(resp) * clock_ns / 1000,
            "energy_nj_mean": sum(energy) / len(mine) / 1000,
            **{
                f"energy_nj_{part}_mean": sum(j.energy_pj[part] for j in mine) / len(mine) / 1000
                for part in ENERGY_PARTS
            },
            "kernel_energy_share": sum(j.energy_pj["kernel"] for j in mine) / max(1e-12, sum(energy)),
            "deadline_misses": sum(not j.deadline_met for j in mine),
        }
    return summary


def task_figures(result: ReplayResult) -> dict[str, dict[str, float]]:
    """The ``tasks`` object: per task its jobs' response, execution and energy figures."""
    figures = task_summary(result.jobs, result.clock_ns)
    return {name: {key: values[key] for key in TASK_KEYS} for name, values in figures.items()}


def firmware_figures(fw: FirmwareConfig) -> dict[str, Any]:
    """The ``firmware`` object: the build and its task mapping (a project's folder instead of the
    built-in application's mapping)."""
    common = {"build": fw.label, "arith": fw.arith, "multiplier": fw.multiplier}
    if fw.project:
        return {**common, "scheduler": fw.scheduler, "project": fw.project}
    return {**common, "release": fw.release, "scheduler": fw.scheduler, "ekf_tile": list(fw.ekf_tile),
            "pid_tile": list(fw.pid_tile)}  # fmt: skip


def chip_figures(chip: ChipConfig, result: ReplayResult | None) -> dict[str, Any]:
    """The ``chip`` object: mesh and clock."""
    clock = result.clock_ns if result is not None else chip.tile.clock_period_ns
    return {"width": chip.width, "height": chip.height, "clock_ns": clock}


def energy_figures(result: ReplayResult) -> dict[str, Any]:
    """The ``energy`` object: per tile and NoC, and their total."""
    tiles = {f"{x},{y}": result.energy_pj[f"tile {(x, y)}"] / 1e6 for x, y in result.counters}
    noc = result.energy_pj["noc"] / 1e6
    return {"total_uj": sum(tiles.values()) + noc, "tiles_uj": tiles, "noc_uj": noc}


def cycle_figures(result: ReplayResult) -> dict[str, Any]:
    """The ``cycles`` object: the chip's cycle at the end and each tile's core cycles."""
    return {"chip": result.cycles, "tiles": {f"{x},{y}": c["cycles"] for (x, y), c in result.counters.items()}}


def vehicle_summary(
    scenario: ScenarioConfig,
    rows: np.ndarray,
    rest_height: float,
    result: ReplayResult | None,
    simulated_s: float,
    host_s: float,
    *,
    complete: bool = True,
    stopped: str | None = None,
) -> dict[str, Any]:
    """The summary of one vehicle's flight (``result``: its firmware run, None for the host controller).

    Args:
        scenario: the resolved scenario (its controller, firmware and chip are named).
        rows: the vehicle's flight rows (columns :data:`robosoc.control.flight.ROW_FIELDS`).
        rest_height: the vehicle's (fixes the take-off climb of the flight plan).
        simulated_s, host_s: simulated time flown and the host time it took.
        complete: false for an interrupted or crashed flight; ``stopped`` then says why.
    """
    chip = scenario.controller == "chip"
    summary: dict[str, Any] = {
        **_identity(scenario, complete),
        "firmware": firmware_figures(scenario.firmware) if chip else None,
        "chip": chip_figures(scenario.chip, result) if chip else None,
        **_pace(simulated_s, host_s),
        "flight": flight_summary(rows, scenario, rest_height),
        "tasks": task_figures(result) if result is not None else None,
        "deadline_misses": result.deadline_misses if result is not None else None,
        "energy": energy_figures(result) if result is not None else None,
        "cycles": cycle_figures(result) if result is not None else None,
    }
    return _with_reason(summary, stopped)


def fleet_summary(
    scenario: ScenarioConfig,
    vehicles: Sequence[dict[str, Any]],
    simulated_s: float,
    host_s: float,
    *,
    min_separation_m: float,
    complete: bool = True,
    stopped: str | None = None,
) -> dict[str, Any]:
    """The top-level summary of a run of several vehicles: the shared fields, the closest approach of
    any two vehicles (their body origins, in metres) and each vehicle's summary."""
    misses = sum(v["deadline_misses"] or 0 for v in vehicles) if scenario.controller == "chip" else None
    summary: dict[str, Any] = {
        **_identity(scenario, complete),
        **_pace(simulated_s, host_s),
        "deadline_misses": misses,
        "min_separation_m": min_separation_m,
        "vehicles": list(vehicles),
    }
    return _with_reason(summary, stopped)


def _identity(scenario: ScenarioConfig, complete: bool) -> dict[str, Any]:
    """The fields that say which run a summary is of."""
    return {
        "schema": SCHEMA,
        "complete": complete,
        "scenario": scenario.name,
        "seed": scenario.seed,
        "controller": scenario.controller,
        "mode": MODE_LOCKSTEP,
    }


def _pace(simulated_s: float, host_s: float) -> dict[str, float]:
    """Simulated and host time, and their ratio."""
    return {
        "simulated_s": simulated_s,
        "host_s": host_s,
        "real_time_factor": simulated_s / host_s if host_s > 0 else math.nan,
    }


def _with_reason(summary: dict[str, Any], stopped: str | None) -> dict[str, Any]:
    """``summary`` with why the flight stopped early, if it did."""
    if stopped is not None:
        summary["stopped"] = stopped
    return summary


def json_safe(value: Any) -> Any:
    """``value`` with every NaN (and infinity) replaced by None and numpy scalars made plain."""
    if isinstance(value, dict):
        return {k: json_safe(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [json_safe(v) for v in value]
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    return value


def write_summary(summary: dict[str, Any], path: Path) -> None:
    """Write ``summary`` as JSON (NaN as null) to a temporary name and rename it to ``path``, so that
    a reader never sees half a file."""
    text = json.dumps(json_safe(summary), indent=2, allow_nan=False) + "\n"
    output_files.write_atomic(path, text)
