"""A firmware built for the chip, with what the host needs to fly it: the I/O tile's contract.

Every sensor period the I/O tile sends one sensor packet (``robosoc_packets.h``: readings, the
setpoint, the sample's sequence number and time stamp) to ``sensor`` (a tile and port), and each
further packet a project declares (``io_inputs``: the position packet) to its tile and port; the
firmware answers with one PWM packet carrying the same sequence number on ``actuator_port`` of the
I/O tile.  Until a command arrives the motors hold the last one.  :class:`FirmwareImage` holds the
ELF, the tiles to load it on, each tile's task ids by name (how job records are named), and that
contract; the built-in flight application makes one (:func:`robosoc.host.flight_app.image`), and
so does any firmware project (:func:`project_image`).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

from robosoc.config.chip import ChipConfig
from robosoc.config.firmware import FirmwareConfig
from robosoc.config.project import IO, FirmwareProject
from robosoc.config.scenario import ScenarioConfig
from robosoc.config.vehicle import VehicleConfig
from robosoc.host.control_params import control_include_dir
from robosoc.host.project_build import build_project
from robosoc.host.project_main import TASK_REFUSED_EXIT, Tile, task_ids

__all__ = ["FirmwareImage", "project_image"]


@dataclass(frozen=True)
class FirmwareImage:
    """A built firmware and how the host drives it.

    Attributes:
        elf: the image, loaded on every tile of ``tasks``.
        tasks: per tile (in load order), the TASK_ID of each task by name.
        sensor: (tile, port) the I/O tile sends each sensor packet to.
        actuator_port: the I/O tile's port the PWM packets arrive on.
        estimator: the tile whose estimator state the host reads after each period (the built-in
            application's), or None: the flight's estimate columns stay empty.
        project: the project's name, or "" for the built-in application.
    """

    elf: Path
    tasks: Mapping[Tile, Mapping[str, int]]
    sensor: tuple[Tile, int]
    actuator_port: int
    estimator: Tile | None = None
    project: str = ""
    #: the project's tasks in the order of its file (how a refused task's exit code names it)
    task_order: tuple[str, ...] = ()
    #: the further packets the I/O tile sends with each sensor packet: (format name, tile, port)
    io_inputs: tuple[tuple[str, Tile, int], ...] = ()

    @property
    def tiles(self) -> list[Tile]:
        return list(self.tasks)

    def exit_reason(self, code: int) -> str:
        """Why the firmware ended on a tile with exit code ``code`` (it never should)."""
        index = code - TASK_REFUSED_EXIT
        if 0 <= index < len(self.task_order):
            return f"the kernel refused task {self.task_order[index]!r} (no task slot or no memory for its stack)"
        return f"the firmware ended (exit code {code:#x}): its main must not return"

    @property
    def task_names(self) -> list[str]:
        """Every task's name, tile by tile in load order, each tile's in creation order."""
        return [name for names in self.tasks.values() for name in names]


def project_image(
    project: FirmwareProject,
    fw: FirmwareConfig,
    vehicle: VehicleConfig | None = None,
    scenario: ScenarioConfig | None = None,
    chip: ChipConfig | None = None,
) -> FirmwareImage:
    """Build ``project`` for ``fw``'s build (arithmetic, multiplier, kernel tick), with the control
    parameters of ``vehicle`` flying ``scenario`` in reach of its C (``robosoc_control.h``), linked
    for the smallest SRAM of ``chip``'s tiles it runs on (default: the toolchain's 2 MiB).

    Raises:
        ValueError: the project has no single message from the I/O tile (the sensor packets) and to
            it (the PWM commands), or does not support the build (the key named).
        CompileError: the compiler failed.
    """
    all_inputs, outputs = project.inputs(), project.outputs()
    inputs = [m for m in all_inputs if m.io_packet == "sensor"]
    if len(inputs) != 1 or len(outputs) != 1:
        raise ValueError(
            f"messages: a flying project has one message from {IO!r} of the sensor packets and one to {IO!r} "
            f"(the PWM commands), got {len(inputs)} and {len(outputs)}"
        )
    further = [m for m in all_inputs if m.io_packet != "sensor"]
    kinds = [m.io_packet for m in further]
    if len(set(kinds)) != len(kinds):
        raise ValueError(f"messages: the I/O tile sends each packet once per sensor period, got {kinds}")
    sensor = project.task(inputs[0].destination)
    elf = build_project(
        project,
        arith=fw.arith,
        multiplier=fw.multiplier,
        tick_cycles=fw.tick_cycles,
        include_dirs=[control_include_dir(vehicle, scenario)],
        sram_size=min(chip.tile_config(xy).sram_bytes for xy in project.tiles()) if chip is not None else None,
    )
    tiles = project.tiles()
    return FirmwareImage(
        elf=elf,
        tasks={xy: task_ids(project, xy) for xy in tiles},
        sensor=((int(sensor.tile[0]), int(sensor.tile[1])), inputs[0].port),
        actuator_port=outputs[0].port,
        project=project.project.name,
        task_order=project.task_names,
        io_inputs=tuple((m.io_packet, _tile(project.task(m.destination).tile), m.port) for m in further),
    )


def _tile(xy: tuple[int, int]) -> Tile:
    return (int(xy[0]), int(xy[1]))
