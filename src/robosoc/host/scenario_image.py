"""The firmware a scenario flies: the built-in flight application, or the project its
``[firmware] project`` names (a folder with a robosoc.toml), built once for the flight."""

from __future__ import annotations

from robosoc.config.project import load_project
from robosoc.config.scenario import ScenarioConfig
from robosoc.config.vehicle import VehicleConfig
from robosoc.host import flight_app
from robosoc.host.firmware_image import FirmwareImage, project_image

__all__ = ["scenario_image"]


def scenario_image(scenario: ScenarioConfig, vehicle: VehicleConfig) -> FirmwareImage:
    """Build the scenario's firmware for its build options, with the controller parameters of
    ``vehicle`` flying ``scenario``.

    Raises:
        ConfigError: the project file is wrong (file and key named).
        ValueError: a task on a tile the chip has no powered core on, or a build the project does
            not support.
        CompileError: the compiler failed (file and line named).
    """
    fw = scenario.firmware
    if not fw.project:
        return flight_app.image(fw, vehicle, scenario)
    project = load_project(fw.project)
    project.check_chip(scenario.chip)
    return project_image(project, fw, vehicle, scenario)
