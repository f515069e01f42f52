"""``summary.json`` of a decoupled flight, and the parts each side contributes to it.

The keys are the run folder contract's (docs/decoupled.md; shared with lockstep runs): flight
figures from the physics side's rows, task, energy and chip figures from the chip side's firmware
run, and ``"link"``, the datagram counts of both directions.  Each side writes its own part
(``physics.json``, ``chip.json``) as it ends; :func:`decoupled_summary` joins them.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from robosoc.config.chip import ChipConfig
from robosoc.config.firmware import FirmwareConfig
from robosoc.config.link import LinkConfig
from robosoc.config.scenario import ScenarioConfig
from robosoc.config.vehicle import VehicleConfig
from robosoc.control.flight import flight_metrics
from robosoc.cosim.replay import TASK_NAMES, ReplayResult

__all__ = [
    "SCHEMA",
    "chip_part",
    "chip_record",
    "decoupled_summary",
    "flight_part",
    "link_summary",
    "physics_record",
    "write_json",
]

SCHEMA = 1


def _finite(value: Any) -> Any:
    """``value`` with every NaN or infinity replaced by None (JSON has neither)."""
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, Mapping):
        return {k: _finite(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_finite(v) for v in value]
    return value


def write_json(data: Mapping[str, Any], path: Path) -> None:
    """Write ``data`` (NaN as null) to ``path`` through a temporary file, so a reader never sees half."""
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(json.dumps(_finite(data), indent=2) + "\n", encoding="utf-8")
    os.replace(tmp, path)


def flight_part(rows: np.ndarray, scenario: ScenarioConfig, vehicle: VehicleConfig) -> dict[str, Any]:
    """The ``"flight"`` object of a flight's rows (figures NaN, written null, where they cannot be had)."""
    if len(rows) == 0:
        return {}
    m = flight_metrics(rows, scenario.flight, vehicle.rest_height)
    return {
        "hover_rms_m": m.hover_rms,
        "hover_max_m": m.hover_max,
        "overshoot_m": m.overshoot,
        "tracking_rms_deg": dict(zip(("roll", "pitch", "yaw"), m.tracking_rms, strict=True)),
        "step_rise_s": [{"axis": a, "time_s": t, "rise_s": r} for a, t, r in m.step_rise],
        "attitude_estimate_rms_deg": m.ekf_rms,
        "height_estimate_rms_m": m.height_estimate_rms,
    }


def _mean(values: list[float]) -> float:
    return sum(values) / len(values) if values else math.nan


def chip_part(result: ReplayResult, fw: FirmwareConfig, chip: ChipConfig) -> dict[str, Any]:
    """The ``"firmware"``, ``"chip"``, ``"tasks"``, ``"deadline_misses"`` and ``"energy"`` objects."""
    tasks: dict[str, Any] = {}
    for name in TASK_NAMES:
        jobs = result.jobs_of(name)
        if not jobs:
            continue
        us = result.clock_ns / 1000
        tasks[name] = {
            "jobs": len(jobs),
            "response_us_mean": _mean([j.response_cycles * us for j in jobs]),
            "response_us_max": max(j.response_cycles for j in jobs) * us,
            "exec_cycles_mean": _mean([j.exec_cycles for j in jobs]),
            "exec_cycles_max": max(j.exec_cycles for j in jobs),
            "energy_nj_mean": _mean([j.energy_total_pj / 1000 for j in jobs]),
            **{
                f"energy_nj_{part}_mean": _mean([j.energy_pj[part] / 1000 for j in jobs])
                for part in ("task", "kernel", "idle", "noc")
            },
            "deadline_misses": sum(not j.deadline_met for j in jobs),
        }
    tiles = {f"{x},{y}": result.energy_pj[f"tile {(x, y)}"] / 1e6 for (x, y) in result.counters}
    noc = result.energy_pj["noc"] / 1e6
    return {
        "firmware": {
            "build": fw.label,
            "arith": fw.arith,
            "multiplier": fw.multiplier,
            "release": fw.release,
            "scheduler": fw.scheduler,
            "ekf_tile": list(fw.ekf_tile),
            "pid_tile": list(fw.pid_tile),
        },
        "chip": {"width": chip.width, "height": chip.height, "clock_ns": result.clock_ns},
        "tasks": tasks,
        "deadline_misses": result.deadline_misses,
        "energy": {"total_uj": sum(tiles.values()) + noc, "tiles_uj": tiles, "noc_uj": noc},
    }


def link_summary(physics: Mapping[str, Any], chip: Mapping[str, Any], config: LinkConfig) -> dict[str, Any]:
    """The ``"link"`` object from the sides' parts: per direction the sender's ``sent`` and the
    faults it injected, and what the receiver counted; the chip's readings, the physics' commands."""

    def direction(sender: Mapping[str, Any], receiver: Mapping[str, Any]) -> dict[str, Any]:
        return {"sent": sender.get("sent", 0), **receiver, "injected": sender.get("injected", {})}

    p_link, c_link = physics.get("link", {}), chip.get("link", {})
    return {
        "to_chip": direction(p_link.get("to_chip", {}), c_link.get("from_physics", {})),
        "to_physics": direction(c_link.get("to_physics", {}), p_link.get("from_chip", {})),
        "readings": chip.get("readings", {}),
        "commands": physics.get("commands", {}),
        "pace": config.pace,
        "hold": config.hold,
        "resend": config.resend,
        "faults": config.faults.as_dict(),
        "physics_ended": physics.get("ended"),
        "chip_ended": chip.get("ended"),
    }


def decoupled_summary(
    physics: Mapping[str, Any],
    chip: Mapping[str, Any],
    *,
    scenario: ScenarioConfig,
    seed: int,
    config: LinkConfig,
) -> dict[str, Any]:
    """``summary.json`` of a decoupled flight from the two sides' parts (``physics.json``, ``chip.json``)."""
    simulated = float(physics.get("simulated_s", 0.0))
    host = float(physics.get("host_s", 0.0))
    return {
        "schema": SCHEMA,
        "complete": bool(physics.get("complete")) and bool(chip.get("complete")),
        "scenario": scenario.name,
        "seed": seed,
        "controller": "chip",
        "mode": "decoupled",
        "firmware": chip.get("firmware"),
        "chip": chip.get("chip"),
        "simulated_s": simulated,
        "host_s": host,
        "real_time_factor": simulated / host if host > 0 else math.nan,
        "flight": physics.get("flight", {}),
        "tasks": chip.get("tasks", {}),
        "deadline_misses": chip.get("deadline_misses"),
        "energy": chip.get("energy"),
        "link": link_summary(physics, chip, config),
    }


def physics_record(outcome: Any, scenario: ScenarioConfig, vehicle: VehicleConfig) -> dict[str, Any]:
    """``physics.json``: how the physics side ended, its flight figures and link counts
    (``outcome``: a :class:`robosoc.cosim.decoupled_physics.PhysicsOutcome`)."""
    return {
        "side": "physics",
        "ended": outcome.ended,
        "message": outcome.message,
        "complete": outcome.complete,
        "samples": outcome.samples,
        "rows": len(outcome.rows),
        "simulated_s": outcome.simulated_s,
        "host_s": outcome.host_s,
        "cpu_s": outcome.cpu_s,
        "max_lag_s": outcome.max_lag_s,
        "flight": flight_part(outcome.rows, scenario, vehicle),
        "link": outcome.link,
        "commands": outcome.commands,
    }


def chip_record(outcome: Any, fw: FirmwareConfig, chip: ChipConfig) -> dict[str, Any]:
    """``chip.json``: how the chip side ended, its tasks, energy and link counts
    (``outcome``: a :class:`robosoc.cosim.decoupled_chip.ChipOutcome`)."""
    return {
        "side": "chip",
        "ended": outcome.ended,
        "message": outcome.message,
        "complete": outcome.complete,
        "simulated_s": outcome.simulated_s,
        "host_s": outcome.host_s,
        "cpu_s": outcome.cpu_s,
        **(chip_part(outcome.result, fw, chip) if outcome.result is not None else {}),
        "link": outcome.link,
        "readings": outcome.readings,
    }
