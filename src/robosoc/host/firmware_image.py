"""A firmware built for the chip, with what the host needs to fly it: the I/O tile's contract.

Every sensor period the I/O tile sends one sensor packet (``robosoc_packets.h``: readings, the
setpoint, the sample's sequence number and time stamp) to ``sensor`` (a tile and port), and each
further packet a project declares (``io_inputs``: the position packet) to its tile and port; the
firmware answers with one PWM packet carrying the same sequence number on ``actuator_port`` of the
I/O tile.  Until a command arrives the motors hold the last one.  :class:`FirmwareImage` holds the
ELF, the tiles to load it on, each tile's task ids by name (how job records are named), and that
contract; :func:`project_image` makes one for a firmware project.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

from robosoc.config.chip import ChipConfig
from robosoc.config.firmware import FirmwareConfig
from robosoc.config.project import IO, PROJECT_FILE, FirmwareProject
from robosoc.config.scenario import ScenarioConfig
from robosoc.config.vehicle import VehicleConfig
from robosoc.host.control_params import control_include_dir
from robosoc.host.project_build import build_project, firmware_defines
from robosoc.host.project_main import TASK_REFUSED_EXIT, Tile, task_ids
from robosoc.host.task_table import TaskTable
from robosoc.host.telemetry import TelemetryProbe, resolve_telemetry

__all__ = ["FIRST_SAMPLE_CYCLE", "SAMPLE_PERIOD_US", "FirmwareImage", "project_image", "sample_cycle"]

SAMPLE_PERIOD_US = 10_000
"""The sensor period of the default scenario (100 Hz)."""
FIRST_SAMPLE_CYCLE = 500_000
"""Cycle at which the host injects sample 0: every tile has started its kernel well before
(``os_start`` runs within the first 100,000 cycles; ``images.read_stats().start_cycle`` tells)."""


def sample_cycle(k: int, period_us: int = SAMPLE_PERIOD_US, clock_period_ns: float = 4.0) -> int:
    """The cycle at which sample ``k`` (taken at k · period) leaves the I/O tile:
    :data:`FIRST_SAMPLE_CYCLE` + k · period in cycles (10 ms = 2,500,000 cycles at 4 ns)."""
    per_sample = round(period_us * 1000 / clock_period_ns)
    return FIRST_SAMPLE_CYCLE + k * per_sample


@dataclass(frozen=True)
class FirmwareImage:
    """A built firmware and how the host drives it.

    Attributes:
        elf: the image, loaded on every tile of ``tasks``.
        tasks: per tile (in load order), the TASK_ID of each task by name.
        sensor: (tile, port) the I/O tile sends each sensor packet to.
        actuator_port: the I/O tile's port the PWM packets arrive on.
        telemetry: the values the host reads from the chip after each period
            (:mod:`robosoc.host.telemetry`; the estimate columns of ``flight.csv`` among them).
        project: the project's name (``[project] name`` of its robosoc.toml).
    """

    elf: Path
    tasks: Mapping[Tile, Mapping[str, int]]
    sensor: tuple[Tile, int]
    actuator_port: int
    telemetry: tuple[TelemetryProbe, ...] = ()
    #: the kernel's task table, to check after boot that main created the tasks of ``tasks``
    task_table: TaskTable | None = None
    project: str = ""
    #: the project's tasks in the order of its file (how a refused task's exit code names it)
    task_order: tuple[str, ...] = ()
    #: the further packets the I/O tile sends with each sensor packet: (format name, tile, port)
    io_inputs: tuple[tuple[str, Tile, int], ...] = ()
    #: the name of the message of the PWM packets (how an error names it)
    actuator_message: str = "pwm"
    #: the image of a tile whose core runs on a divided clock (docs/power.md, "Per-tile clock"): the
    #: same program with the kernel's tick in that core's cycles
    tile_elfs: Mapping[Tile, Path] = field(default_factory=dict)
    #: the kernel's task table in those images
    tile_task_tables: Mapping[Tile, TaskTable] = field(default_factory=dict)

    def elf_for(self, xy: Tile) -> Path:
        """The image tile ``xy`` runs."""
        return self.tile_elfs.get(xy, self.elf)

    def task_table_of(self, xy: Tile) -> TaskTable | None:
        """The kernel's task table in the image tile ``xy`` runs."""
        return self.tile_task_tables.get(xy, self.task_table)

    @property
    def tiles(self) -> list[Tile]:
        return list(self.tasks)

    def missing_tasks(self, created: dict[Tile, list[int]]) -> str:
        """What is wrong with the tasks the kernels hold after boot (``created``: TASK_IDs per
        tile), or "" when every tile holds exactly the tasks of :attr:`tasks`."""
        for xy, ids in self.tasks.items():
            have = created.get(xy, [])
            for name, tid in ids.items():
                if tid not in have:
                    return f"tile {xy}: the kernel refused task {name!r} (no task slot or no memory for its stack)"
            extra = sorted(set(have) - set(ids.values()))
            if extra:
                return f"tile {xy}: main created tasks the project does not declare (TASK_IDs {extra})"
        return ""

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
    """Build ``project`` for ``fw``'s build (arithmetic, multiplier, kernel settings) with its tasks
    placed as ``fw.placement`` moves them, the control parameters of ``vehicle`` flying ``scenario``
    in reach of its C (``robosoc_control.h``), linked for the smallest SRAM of ``chip``'s tiles it
    runs on (default: the toolchain's 2 MiB).

    Raises:
        ValueError: the project has no single message from the I/O tile (the sensor packets) and to
            it (the PWM commands), or does not support the build (the key named).
        CompileError: the compiler failed.
        TelemetryError: a ``[[telemetry]]`` value is not in the program (file and key named).
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
    mapping = fw.mapping
    tiles = project.tiles(mapping)
    elf = build_project(
        project,
        arith=fw.arith,
        multiplier=fw.multiplier,
        mapping=mapping,
        settings=firmware_defines(fw),
        include_dirs=[control_include_dir(vehicle, scenario)],
        sram_size=min(chip.tile_config(xy).sram_bytes for xy in tiles) if chip is not None else None,
    )
    tile_elfs = _divided_clock_images(project, fw, vehicle, scenario, chip, tiles)
    where = str(project.path(PROJECT_FILE))
    ids = {xy: task_ids(project, xy, mapping) for xy in tiles}
    task_tiles = {name: (xy, tid) for xy, named in ids.items() for name, tid in named.items()}
    telemetry = resolve_telemetry(project.telemetry, elf, fw.arith, task_tiles, where)
    for other in dict.fromkeys(tile_elfs.values()):  # a divided tile's values where its own image has them
        mine = {xy for xy, path in tile_elfs.items() if path == other}
        theirs = resolve_telemetry(project.telemetry, other, fw.arith, task_tiles, where)
        telemetry = tuple(b if b.tile in mine else a for a, b in zip(telemetry, theirs, strict=True))
    return FirmwareImage(
        elf=elf,
        tasks=ids,
        telemetry=telemetry,
        task_table=TaskTable.of(elf),
        sensor=(task_tiles[inputs[0].destination][0], inputs[0].port),
        actuator_port=outputs[0].port,
        project=project.project.name,
        task_order=project.task_names,
        io_inputs=tuple((m.io_packet, task_tiles[m.destination][0], m.port) for m in further),
        actuator_message=outputs[0].name,
        tile_elfs=tile_elfs,
        tile_task_tables={xy: TaskTable.of(path) for xy, path in tile_elfs.items()},
    )


def _divided_clock_images(
    project: FirmwareProject,
    fw: FirmwareConfig,
    vehicle: VehicleConfig | None,
    scenario: ScenarioConfig | None,
    chip: ChipConfig | None,
    tiles: list[Tile],
) -> dict[Tile, Path]:
    """The images of the tiles whose core runs at the chip's clock divided by d > 1: the same build
    with ``OS_TICK_CYCLES`` = tick_cycles / d, so that their kernel's tick (and every period and
    deadline counted in ticks) lasts as long as on the other tiles.  Its symbols may lie elsewhere
    (a smaller tick constant can take one instruction less): the host reads such a tile by its own
    image (:meth:`FirmwareImage.task_table_of`, the telemetry probes, the chip's program per tile).
    The tick's divisibility is checked before (``FirmwareConfig.check_chip``)."""
    if chip is None:
        return {}
    out: dict[Tile, Path] = {}
    built: dict[int, Path] = {}
    for xy in tiles:
        d = chip.tile_divider(xy)
        if d == 1:
            continue
        if d not in built:
            built[d] = build_project(
                project,
                arith=fw.arith,
                multiplier=fw.multiplier,
                mapping=fw.mapping,
                settings={**firmware_defines(fw), "OS_TICK_CYCLES": fw.tick_cycles // d},
                include_dirs=[control_include_dir(vehicle, scenario)],
                sram_size=min(chip.tile_config(t).sram_bytes for t in tiles),
            )
        out[xy] = built[d]
    return out
