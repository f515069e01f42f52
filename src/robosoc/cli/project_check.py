"""The firmware project a command names, checked before anything is built or flown."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING

from robosoc.cli.errors import CliError
from robosoc.config.scenario import ScenarioConfig

if TYPE_CHECKING:
    from robosoc.config.chip import ChipConfig
    from robosoc.config.firmware import FirmwareConfig
    from robosoc.config.project import FirmwareProject


def load_checked(
    folder: str, chip: ChipConfig, source: str, mapping: Mapping[str, tuple[int, int]] | None = None
) -> FirmwareProject:
    """The project in ``folder``, its tasks checked against ``chip``; errors start with ``source``
    (the option or the scenario field that named the folder).

    Raises:
        CliError: no such folder, the project file is missing or wrong (file and key named), or a
            task sits on a tile with no powered core (the task and tile named).
    """
    from robosoc.config.project import PROJECT_FILE, load_project
    from robosoc.config.validate import ConfigError

    if not Path(folder).is_dir():
        raise CliError(f"{source}: no folder {folder} (robosoc new DIR makes a project)")
    try:
        project = load_project(folder)
        project.check_chip(chip, mapping)
    except ConfigError as exc:
        raise CliError(f"{source}: {exc}") from exc
    except ValueError as exc:
        raise CliError(f"{source}: {Path(folder) / PROJECT_FILE}: {exc}") from exc
    return project


def check_project(config: ScenarioConfig, source: str) -> None:
    """Load ``config``'s firmware project (if it names one), check its tasks against the scenario's
    chip and that it supports the scenario's build.

    Raises:
        CliError: as :func:`load_checked`, or a build the project does not list (the key named).
    """
    check_firmware(config.firmware, config.chip, source)


def check_firmware(fw: FirmwareConfig, chip: ChipConfig, source: str) -> None:
    """:func:`check_project` of a firmware configuration and the chip it is to run on."""
    folder = fw.project
    if not folder:
        return
    project = load_checked(folder, chip, source, fw.mapping)
    try:
        fw.load_project()  # the placement's task names
        project.check_build(fw.arith, fw.multiplier)
    except ValueError as exc:
        raise CliError(f"{source}: {Path(folder) / 'robosoc.toml'}: {exc}") from exc
