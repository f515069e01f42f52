"""``summary.json`` of a decoupled flight, and the parts each side contributes to it.

The keys are the run folder contract's (docs/decoupled.md; shared with lockstep runs): flight
figures from the physics side's rows, task, energy and chip figures from the chip side's firmware
run, and ``"link"``, the datagram counts of both directions.  Each side writes its own part
(``physics.json``, ``chip.json``) as it ends; :func:`decoupled_summary` joins them.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from robosoc.config.chip import ChipConfig
from robosoc.config.firmware import FirmwareConfig
from robosoc.config.link import LinkConfig
from robosoc.config.scenario import ScenarioConfig
from robosoc.config.vehicle import VehicleConfig
from robosoc.cosim.firmware_run import ReplayResult
from robosoc.outputs.run_summary import (
    SCHEMA,
    chip_figures,
    energy_figures,
    firmware_figures,
    flight_summary,
    task_figures,
)

__all__ = [
    "SCHEMA",
    "chip_part",
    "chip_record",
    "decoupled_summary",
    "flight_part",
    "link_summary",
    "physics_record",
]


def flight_part(rows: np.ndarray, scenario: ScenarioConfig, vehicle: VehicleConfig) -> dict[str, Any]:
    """The ``"flight"`` object of a flight's rows (figures NaN, written null, where they cannot be had)."""
    return flight_summary(rows, scenario, vehicle.rest_height) or {}


def chip_part(result: ReplayResult, fw: FirmwareConfig, chip: ChipConfig) -> dict[str, Any]:
    """The ``"firmware"``, ``"chip"``, ``"tasks"``, ``"deadline_misses"`` and ``"energy"`` objects."""
    return {
        "firmware": firmware_figures(fw),
        "chip": chip_figures(chip, result),
        "tasks": task_figures(result),
        "deadline_misses": result.deadline_misses,
        "energy": energy_figures(result),
    }


def link_summary(physics: Mapping[str, Any], chip: Mapping[str, Any], config: LinkConfig) -> dict[str, Any]:
    """The ``"link"`` object from the sides' parts: per direction the sender's ``sent`` and the
    faults it injected, and what the receiver counted; the chip's readings, the physics' commands
    and telemetry entries."""

    def direction(sender: Mapping[str, Any], receiver: Mapping[str, Any]) -> dict[str, Any]:
        return {"sent": sender.get("sent", 0), **receiver, "injected": sender.get("injected", {})}

    p_link, c_link = physics.get("link", {}), chip.get("link", {})
    return {
        "to_chip": direction(p_link.get("to_chip", {}), c_link.get("from_physics", {})),
        "to_physics": direction(c_link.get("to_physics", {}), p_link.get("from_chip", {})),
        "readings": chip.get("readings", {}),
        "commands": physics.get("commands", {}),
        "telemetry": physics.get("telemetry", {}),
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
    config: LinkConfig,
) -> dict[str, Any]:
    """``summary.json`` of a decoupled flight from the two sides' parts (``physics.json``, ``chip.json``)."""
    simulated = float(physics.get("simulated_s", 0.0))
    host = float(physics.get("host_s", 0.0))
    return {
        "schema": SCHEMA,
        "complete": bool(physics.get("complete")) and bool(chip.get("complete")),
        "scenario": scenario.name,
        "seed": scenario.seed,
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
        "telemetry": outcome.telemetry_counts,
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
