"""The ROS 1 nodes with their files: ``robosoc serve physics --ros`` and ``robosoc serve chip --ros``.

* :func:`run_ros_physics_side`: :func:`robosoc.cosim.ros_physics.serve_physics_ros` with each
  vehicle's ``flight.csv`` (as it flies, with the project's telemetry columns),
  ``link-physics.log`` and ``physics.json`` -- in the run
  folder for one vehicle, in ``vehicle-N/`` for several (as ``robosoc fly --vehicles N``);
* :func:`run_ros_chip_side`: the chip node (:class:`robosoc.cosim.ros_chip.RosChipLink` under
  :func:`robosoc.cosim.decoupled_chip.serve_chip`) with ``jobs.csv``, ``link-chip.log`` and
  ``chip.json``, as the UDP chip side writes them (:func:`run_chip_side`).

Both sides' firmware digest is that of the scenario with one vehicle and its preset: every chip of
a fleet runs the same firmware, whichever namespace it serves.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from pathlib import Path
from typing import Any

from robosoc.config.link import LinkConfig
from robosoc.config.scenario import ScenarioConfig
from robosoc.config.vehicle import VehicleConfig, vehicle_preset
from robosoc.cosim.decoupled_chip import ChipOutcome
from robosoc.cosim.decoupled_physics import PhysicsOutcome, scenario_digest
from robosoc.cosim.firmware_run import FirmwareRun
from robosoc.cosim.link import LinkLog
from robosoc.cosim.ros1 import Node
from robosoc.cosim.ros_chip import RosChipLink, check_topics
from robosoc.cosim.ros_physics import serve_physics_ros
from robosoc.cosim.ros_topics import vehicle_namespace
from robosoc.host.telemetry import declared_names, own_columns
from robosoc.outputs.decoupled_flight import fleet_logs, run_chip_side
from robosoc.outputs.decoupled_summary import physics_record
from robosoc.outputs.flight_session import fleet_vehicles
from robosoc.outputs.run_folder import LINK_PHYSICS_LOG, PHYSICS_JSON
from robosoc.outputs.run_summary import write_summary

__all__ = ["firmware_digest", "run_ros_chip_side", "run_ros_physics_side"]


def firmware_digest(scenario: ScenarioConfig) -> bytes:
    """What a chip node's firmware is built for: the scenario with one vehicle, its preset."""
    return scenario_digest(scenario, vehicle_preset(scenario.vehicle))


def run_ros_physics_side(
    scenario: ScenarioConfig,
    config: LinkConfig,
    out: Path | None,
    *,
    start_delay_s: float = 0.0,
    **callbacks: Any,
) -> tuple[list[PhysicsOutcome], list[dict[str, Any]]]:
    """The physics node with its files in ``out`` (nothing if None); each vehicle's outcome and record."""
    vehicles = fleet_vehicles(scenario)
    count = len(vehicles)
    telemetry = declared_names(scenario.firmware)
    folders, logs, on_row = fleet_logs(out, count, own_columns(telemetry))

    try:
        outcomes = serve_physics_ros(
            scenario, vehicles, firmware_digest(scenario), config, telemetry=telemetry,
            log_paths=[f / LINK_PHYSICS_LOG if f is not None else None for f in folders], on_row=on_row,
            start_delay_s=start_delay_s, **callbacks,
        )  # fmt: skip
    finally:
        for log in logs:
            if log is not None:
                log.close()
    records = []
    for i, (outcome, vehicle, folder) in enumerate(zip(outcomes, vehicles, folders, strict=True)):
        record = physics_record(outcome, scenario, vehicle)
        record["namespace"] = vehicle_namespace(i, count)
        if folder is not None:
            write_summary(record, folder / PHYSICS_JSON)
        records.append(record)
    return outcomes, records


def run_ros_chip_side(
    scenario: ScenarioConfig,
    vehicle: VehicleConfig,
    config: LinkConfig,
    namespace: str,
    out: Path | None,
    *,
    on_status: Callable[[str], None] | None = None,
) -> tuple[ChipOutcome, dict[str, Any]]:
    """The chip node for the vehicle in ``namespace``, with its files in ``out``.

    Raises:
        RosUnavailable: ROS is not installed, no master answers, a topic has another type, or the
            namespace has no vehicle.
    """
    say = on_status or (lambda _text: None)
    say(f"connecting to the ROS master, waiting for {namespace.rstrip('/')}/raw_imu ...")
    node = Node("robosoc_chip")
    check_topics(node, namespace, config.connect_timeout_s)
    links: list[RosChipLink] = []

    def transport(log: LinkLog) -> RosChipLink:
        links.append(RosChipLink(node, scenario, vehicle, namespace, log, firmware_digest(scenario)))
        return links[-1]

    def on_period(run: FirmwareRun) -> None:
        links[-1].period_closed(run)

    one = dataclasses.replace(scenario, vehicles=1)
    return run_chip_side(
        one, vehicle, config, f"the ROS namespace {namespace}", None, out, on_status=on_status,
        transport=transport, on_period=on_period,
    )  # fmt: skip
