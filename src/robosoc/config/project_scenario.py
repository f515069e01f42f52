"""A scenario's defaults from the firmware project it flies.

A project file may carry a ``[chip]`` table (the chip it is made for) and a ``[scenario]`` table
(scenario defaults: its mission, sensors, duration).  A scenario that flies the project starts
from them, in this order, each layer field by field over the one before:

1. the built-in scenario (:class:`~robosoc.config.scenario.ScenarioConfig`);
2. the project's chip (:meth:`~robosoc.config.firmware.FirmwareConfig.project_chip`) and its
   ``[scenario]`` fields;
3. the scenario file's fields (or a sweep's base and point), then a command's options.

:func:`scenario_from_fields` does 1-3 for flat dotted fields; the command line
(``cli/scenario_flags.py``) and sweeps (``config/sweep.py``, a point that flies another project)
resolve scenarios through it, so a project's defaults apply however the project was named.  The
shipped quadrotor project (the default firmware) declares neither table: the built-in scenario is
its own (a test keeps it so).
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

from robosoc.config.dotted import nest
from robosoc.config.firmware import FirmwareConfig
from robosoc.config.scenario import ScenarioConfig
from robosoc.config.validate import ConfigError, from_mapping

__all__ = ["PROJECT_FIELD", "project_beside", "project_scenario", "scenario_from_fields"]

PROJECT_FIELD = "firmware.project"


def project_beside(value: Any, folder: Path) -> Any:
    """A ``firmware.project`` value read from a file in ``folder``: a relative folder is the file's
    neighbour (made absolute); anything else (absolute, "", a wrong type) as it is."""
    if isinstance(value, str) and value and not Path(value).is_absolute():
        return str((folder / value).absolute())
    return value


def project_scenario(project: str) -> ScenarioConfig:
    """The built-in scenario flying ``project`` (a folder; "" the shipped default) with the project's
    ``[chip]`` and ``[scenario]`` defaults.

    Raises:
        ConfigError: the project's folder or file is wrong, or one of its defaults (the project file
            and ``chip.<field>`` or ``scenario.<field>`` named).
    """
    if not project:
        return ScenarioConfig()
    firmware = FirmwareConfig(project=project)
    try:
        loaded = firmware.load_project()
    except ConfigError:
        raise
    except ValueError as exc:
        raise ConfigError("", PROJECT_FIELD, str(exc).partition(": ")[2] or str(exc)) from exc
    where = str(loaded.file)
    chip = firmware.project_chip(loaded)
    try:
        base = ScenarioConfig(firmware=firmware, chip=chip)
    except ValueError as exc:  # the project's tasks do not fit its own chip
        raise ConfigError(where, "chip", str(exc)) from exc
    try:
        return from_mapping(ScenarioConfig, nest(loaded.scenario), where, base=base)
    except ConfigError as exc:
        raise ConfigError(where, f"scenario.{exc.field}" if exc.field else "scenario", exc.reason) from exc


def scenario_from_fields(fields: Mapping[str, Any], where: str) -> ScenarioConfig:
    """The scenario of flat dotted ``fields`` (a scenario file's; a sweep's base and point) over the
    defaults of the project they fly (``firmware.project``; the shipped one if they name none).

    Raises:
        ConfigError: a field is wrong (``where`` and the field named) or the project's defaults are
            (the project file named).
    """
    project = fields.get(PROJECT_FIELD, "")
    try:
        base = project_scenario(project) if isinstance(project, str) else ScenarioConfig()  # else: a type error below
    except ConfigError as exc:
        if exc.where:  # the project file's own error
            raise
        raise ConfigError(where, exc.field, exc.reason) from exc
    return from_mapping(ScenarioConfig, nest(fields), where, base=base)
