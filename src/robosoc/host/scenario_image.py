"""The firmware a flight runs: the firmware project that ``[firmware] project`` names (a folder with
a robosoc.toml; by default the shipped quadrotor project), its tasks placed as ``[[firmware.placement]]``
moves them, built once for the flight."""

from __future__ import annotations

from robosoc.config.chip import ChipConfig
from robosoc.config.firmware import FirmwareConfig
from robosoc.config.scenario import ScenarioConfig
from robosoc.config.vehicle import VehicleConfig
from robosoc.host.firmware_image import FirmwareImage, project_image

__all__ = ["firmware_image", "scenario_image"]


def firmware_image(
    fw: FirmwareConfig,
    vehicle: VehicleConfig | None = None,
    scenario: ScenarioConfig | None = None,
    chip: ChipConfig | None = None,
) -> FirmwareImage:
    """Build ``fw``'s firmware project with the controller parameters of ``vehicle`` flying
    ``scenario``; its tasks, placed, are checked against ``chip``.

    Raises:
        ConfigError: the project file is wrong (file and key named).
        ValueError: a task on a tile the chip has no powered core on, or a build the project does
            not support.
        CompileError: the compiler failed (file and line named).
    """
    project = fw.load_project()
    if chip is not None:
        fw.check_chip(chip)
    return project_image(project, fw, vehicle, scenario, chip)


def scenario_image(scenario: ScenarioConfig, vehicle: VehicleConfig) -> FirmwareImage:
    """The firmware of ``scenario`` (:func:`firmware_image` of its firmware, vehicle and chip)."""
    return firmware_image(scenario.firmware, vehicle, scenario, scenario.chip)
