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


def check_project(config: ScenarioConfig, source: str, *, sends: tuple[str, ...] | None = None, what: str = "") -> None:
    """Load ``config``'s firmware project (if it names one), check its tasks against the scenario's
    chip, that it supports the scenario's build, and that it is given the packets it takes from the
    I/O tile: in a flight of ``config`` (``sends`` None) a position packet needs the scenario's
    position sensor on; otherwise each input must be one of ``sends`` (the packets the command's
    run can give, ``what`` naming the run).

    Raises:
        CliError: as :func:`load_checked`, or a build the project does not list (the key named), or
            an input the run cannot give (the message named).
    """
    project = check_firmware(config.firmware, config.chip, source, sends=sends, what=what)
    if project is None or sends is not None:
        return
    for message in project.inputs():
        if message.io_packet == "position" and not config.sensors.position.enabled:
            raise CliError(
                f"sensors.position.enabled: the project {project.project.name!r} takes position packets from "
                f"the I/O tile (its message {message.name!r}), but the scenario's position sensor is off: "
                "set [sensors.position] enabled = true (the position example's robosoc.toml does, in its [scenario])"
            )


def check_firmware(
    fw: FirmwareConfig, chip: ChipConfig | None, source: str, *, sends: tuple[str, ...] | None = None, what: str = ""
) -> FirmwareProject | None:
    """:func:`check_project` of a firmware configuration and the chip it is to run on (None: the
    project's own, :meth:`~robosoc.config.firmware.FirmwareConfig.project_chip`; without the
    scenario's sensors); the project it names, or None for the shipped default."""

    folder = fw.project
    if not folder:
        return None
    if chip is None:
        if not Path(folder).is_dir():
            raise CliError(f"{source}: no folder {folder} (robosoc new DIR makes a project)")
        try:
            chip = fw.project_chip()
        except ValueError as exc:  # ConfigError too: the project file and key named
            raise CliError(f"{source}: {exc}") from exc
    project = load_checked(folder, chip, source, fw.mapping)
    try:
        fw.load_project()  # the placement's task names
        project.check_build(fw.arith, fw.multiplier)
    except ValueError as exc:
        raise CliError(f"{source}: {Path(folder) / 'robosoc.toml'}: {exc}") from exc
    if sends is not None:
        check_inputs(project, source, sends, what)
    return project


def check_inputs(project: FirmwareProject, source: str, sends: tuple[str, ...], what: str) -> None:
    """Refuse a project that takes a packet from the I/O tile that a run of ``what`` cannot send
    (``sends``: the packets it can).

    Raises:
        CliError: naming the project file, the message and the packet.
    """
    from robosoc.config.project import IO, PROJECT_FILE

    for i, message in enumerate(project.messages):
        if message.source == IO and message.io_packet not in sends:
            raise CliError(
                f"{source}: {Path(project.folder) / PROJECT_FILE}: messages[{i}]: the project takes "
                f"{message.io_packet} packets from the I/O tile, which {what} cannot send (it sends "
                f"{', '.join(sends)} packets)"
            )
