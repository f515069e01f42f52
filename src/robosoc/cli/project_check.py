"""The firmware project a scenario names, checked before anything is built or flown."""

from __future__ import annotations

from pathlib import Path

from robosoc.cli.errors import CliError
from robosoc.config.scenario import ScenarioConfig


def check_project(config: ScenarioConfig) -> None:
    """Load ``config``'s firmware project (if it names one) and check its tasks against the chip.

    Raises:
        CliError: the project file is missing or wrong (file and key named), or a task sits on a
            tile with no powered core (the task and tile named).
    """
    from robosoc.config.project import PROJECT_FILE, load_project
    from robosoc.config.validate import ConfigError

    folder = config.firmware.project
    if not folder:
        return
    if not Path(folder).is_dir():
        raise CliError(f"the firmware project: no folder {folder} (robosoc new DIR makes a project)")
    try:
        project = load_project(folder)
        project.check_chip(config.chip)
        project.check_build(config.firmware.arith, config.firmware.multiplier)
    except ConfigError as exc:
        raise CliError(f"the firmware project: {exc}") from exc
    except ValueError as exc:
        raise CliError(f"the firmware project: {folder}/{PROJECT_FILE}: {exc}") from exc
