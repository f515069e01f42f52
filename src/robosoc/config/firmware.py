"""Firmware configuration: which build, which kernel settings, which task runs on which tile.

A frozen dataclass checked in ``__post_init__`` (errors ``ValueError("field: reason")``) and
loadable from TOML with :func:`load_firmware_config`, whose errors name the file and the field::

    arith = "fixed"          # "float" (soft-float) or "fixed" (Q16.16)
    multiplier = true        # build for cores with the iterative multiplier
    release = "event"        # "event": a job per sensor message, as in the seed; "periodic": robosoc's option
    fixed_mul64 = "shift-add"  # Q16.16 multiply without the multiplier: "shift-add" (fix16_mul64_soft) or
                             # "muldi3" (the 64-bit product through compiler-rt's __muldi3, as HellfireOS)
    scheduler = "edf"        # "edf" or "rm"
    tick_cycles = 262144     # the kernel's tick (the seed's 1 ms at 250 MHz)
    period_ticks = 10        # periodic release: the tasks' period (and relative deadline) in ticks
    command_timeout_periods = 10  # sensor periods without an actuator command before a run is marked
    project = ""             # a firmware project's folder ("": the shipped quadrotor project)

    [[placement]]            # optional, any number: move a task of the project to another tile
    task = "estimator"
    tile = [1, 1]

The defaults are the seed's case study on its 2×2 chip: the shipped ``quadrotor`` project (the
estimator, EKF and altitude filter, on (0, 1), the PID controller on (1, 0)), the I/O tile at
(0, 0), the fourth tile powered off (see :func:`seed_chip`), Q16.16 with the multiplier.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from robosoc.config.chip import ChipConfig
from robosoc.config.validate import load_toml
from robosoc.firmware import TEMPLATES_DIR

if TYPE_CHECKING:
    from robosoc.config.project import FirmwareProject

__all__ = [
    "ARITH_CHOICES",
    "DEFAULT_PROJECT",
    "FIXED_MUL64_CHOICES",
    "RELEASE_CHOICES",
    "SCHEDULER_CHOICES",
    "FirmwareConfig",
    "Placement",
    "load_firmware_config",
]

ARITH_CHOICES = ("float", "fixed")
RELEASE_CHOICES = ("event", "periodic")
SCHEDULER_CHOICES = ("edf", "rm")
FIXED_MUL64_CHOICES = ("shift-add", "muldi3")
"""How a Q16.16 build without the multiplier forms the 64-bit product of a multiply: robosoc's
shift-and-add over the smaller operand (``fix16_mul64_soft``, about 190 cycles for values near 1), or
the C product ``(int64_t)a * b``, which compiler-rt's general 64 x 64-bit ``__muldi3`` computes (about
470 cycles), as HellfireOS's fixed-point library does (docs/firmware-libraries.md)."""
#: The kernel's tick must be a multiple of 16 cycles in this range (kernel/os_config.h explains why).
TICK_CYCLES_RANGE = (4096, 1 << 30)
DEFAULT_PROJECT = TEMPLATES_DIR / "quadrotor"
"""The firmware a scenario flies unless it names a project: the seed's estimator and PID tasks."""


def _choice(name: str, value: str, choices: tuple[str, ...]) -> None:
    if value not in choices:
        raise ValueError(f"{name}: must be one of {', '.join(map(repr, choices))}, got {value!r}")


@dataclass(frozen=True)
class Placement:
    """A task of the project moved to another tile than its robosoc.toml gives."""

    task: str
    tile: tuple[int, int]

    def __post_init__(self) -> None:
        if len(self.tile) != 2 or min(self.tile) < 0:
            raise ValueError(f"tile: must be a tile [x, y] with x, y >= 0, got {list(self.tile)}")


@dataclass(frozen=True)
class FirmwareConfig:
    """One build of the control firmware and where its tasks run.

    Attributes:
        arith: ``"float"`` (soft-float, compiler-rt) or ``"fixed"`` (Q16.16).
        multiplier: compile for cores with the iterative multiplier (RV32I+Zmmul) or without.
        fixed_mul64: :data:`FIXED_MUL64_CHOICES`; only the Q16.16 builds without the multiplier differ
            (with it the product is MUL + MULH, and soft-float has its own multiply).
        release: ``"event"`` (each sensor message releases an estimator job, whose estimate
            releases a PID job: the seed's "every sensor message triggers a complete EKF and PID
            iteration") or ``"periodic"`` (both tasks periodic on the kernel tick: robosoc's option).
        scheduler: the kernel's real-time policy, ``"edf"`` or ``"rm"``.
        tick_cycles: the kernel's tick in core cycles.
        period_ticks: period and relative deadline of the tasks in ticks (periodic release); the
            relative deadline of event-released jobs too.
        command_timeout_periods: this many sensor periods in a row without an actuator command
            reaching the I/O tile mark the run (``summary.json``: ``"no_actuator_command"``; the
            motors hold the last command meanwhile).
        project: the folder of the firmware project to fly (docs/firmware-projects.md; in a
            scenario file, relative to the file's folder); "" for the shipped quadrotor project.
        placement: tasks of the project moved to other tiles (by task name).
    """

    arith: str = "fixed"
    multiplier: bool = True
    release: str = "event"
    fixed_mul64: str = "shift-add"
    scheduler: str = "edf"
    tick_cycles: int = 262144
    period_ticks: int = 10
    command_timeout_periods: int = 10
    project: str = ""
    placement: tuple[Placement, ...] = ()

    def __post_init__(self) -> None:
        _choice("arith", self.arith, ARITH_CHOICES)
        _choice("release", self.release, RELEASE_CHOICES)
        _choice("fixed_mul64", self.fixed_mul64, FIXED_MUL64_CHOICES)
        _choice("scheduler", self.scheduler, SCHEDULER_CHOICES)
        low, high = TICK_CYCLES_RANGE
        if not low <= self.tick_cycles <= high or self.tick_cycles % 16:
            raise ValueError(f"tick_cycles: must be a multiple of 16 from {low} to {high}, got {self.tick_cycles}")
        if not 1 <= self.period_ticks <= 1_000_000:
            raise ValueError(f"period_ticks: must be between 1 and 1000000, got {self.period_ticks}")
        if not 1 <= self.command_timeout_periods <= 1_000_000:
            raise ValueError(
                f"command_timeout_periods: must be between 1 and 1000000, got {self.command_timeout_periods}"
            )
        seen: dict[str, int] = {}
        for i, moved in enumerate(self.placement):
            if moved.task in seen:
                raise ValueError(f"placement[{i}].task: {moved.task!r} is also placement[{seen[moved.task]}]")
            seen[moved.task] = i

    @property
    def muldi3(self) -> bool:
        """Whether this build forms Q16.16 products through compiler-rt's ``__muldi3`` (a fixed-point
        build without the multiplier with ``fixed_mul64 = "muldi3"``)."""
        return self.arith == "fixed" and not self.multiplier and self.fixed_mul64 == "muldi3"

    @property
    def label(self) -> str:
        """``fixed+mul``, ``float-no-mul``...: how tables and file names name a build."""
        return f"{self.arith}{'+mul' if self.multiplier else '-no-mul'}"

    @property
    def project_folder(self) -> Path:
        """The project's folder: :attr:`project`, or the shipped quadrotor project."""
        return Path(self.project) if self.project else DEFAULT_PROJECT

    @property
    def mapping(self) -> dict[str, tuple[int, int]]:
        """The tasks :attr:`placement` moves, by name, to their tiles."""
        return {moved.task: (int(moved.tile[0]), int(moved.tile[1])) for moved in self.placement}

    def load_project(self) -> FirmwareProject:
        """The project this build flies, its placement checked against its tasks.

        Raises:
            ConfigError: the project file is missing or wrong (file and key named).
            ValueError: no such folder (``project``), or a placement names no task of the project
                (``placement[i].task``).
        """
        from robosoc.config.project import load_project

        if not self.project_folder.exists():
            raise ValueError(f"project: no folder {self.project} (robosoc new DIR makes a project)")
        project = load_project(self.project_folder)
        for i, moved in enumerate(self.placement):
            if moved.task not in project.task_names:
                raise ValueError(
                    f"placement[{i}].task: the project {project.project.name!r} has no task {moved.task!r} "
                    f"(its tasks: {', '.join(project.task_names)})"
                )
        return project

    def tiles(self) -> list[tuple[int, int]]:
        """The tiles the project's tasks run on, with :attr:`placement` applied."""
        return self.load_project().tiles(self.mapping)

    def check_chip(self, chip: ChipConfig) -> None:
        """Raise ValueError unless every task's tile is a powered core tile of ``chip``, with the
        multiplier if the build uses it (the task and tile named)."""
        project = self.load_project()
        for i, moved in enumerate(self.placement):
            xy = (int(moved.tile[0]), int(moved.tile[1]))
            problem = chip.core_tile_problem(xy)
            if problem:
                raise ValueError(f"placement[{i}].tile: {list(xy)} ({moved.task}) {problem}")
        project.check_chip(chip, self.mapping)
        if self.multiplier:
            for task in project.tasks:
                xy = self.mapping.get(task.name, (int(task.tile[0]), int(task.tile[1])))
                if not chip.tile_config(xy).multiplier:
                    raise ValueError(
                        f"multiplier: the build uses the multiplier but task {task.name!r} runs on {list(xy)}, "
                        "which has none (chip.tile or chip.tiles)"
                    )
        low = TICK_CYCLES_RANGE[0]
        for task in project.tasks:
            xy = self.mapping.get(task.name, (int(task.tile[0]), int(task.tile[1])))
            d = chip.tile_divider(xy)
            if d > 1 and (self.tick_cycles % (16 * d) or self.tick_cycles // d < low):
                raise ValueError(
                    f"tick_cycles: task {task.name!r} runs on {list(xy)}, whose core clock is the chip's divided by "
                    f"{d} (chip.tiles clock_period_ns): its kernel's tick of {self.tick_cycles} chip cycles must be "
                    f"a multiple of 16 of its cycles and at least {low} of them, got {self.tick_cycles} / {d}"
                )

    def default_chip(self) -> ChipConfig:
        """The chip a replay or Table I runs on when none is given: :meth:`project_chip`."""
        return self.project_chip()

    def project_chip(self, project: FirmwareProject | None = None) -> ChipConfig:
        """The chip the project is made for: the seed's 2×2 (I/O tile (0, 0)) with the project
        file's ``[chip]`` fields, and, unless those name ``powered_off``, every core tile no task
        uses powered off (the seed's rule, :meth:`seed_chip`).  ``project``: the loaded project.

        Raises:
            ConfigError: a ``[chip]`` field is wrong (the project file and ``chip.<field>`` named).
        """
        from robosoc.config.dotted import nest
        from robosoc.config.validate import ConfigError, from_mapping

        project = project or self.load_project()
        fields = dict(project.chip)
        if not fields:
            return self.seed_chip()
        base = ChipConfig(width=2, height=2, io_tile=(0, 0))
        try:
            chip = from_mapping(ChipConfig, nest(fields), str(project.file), base=base)
            if "powered_off" in fields:
                return chip
            used = set(project.tiles(self.mapping))
            cores = (chip.tile_xy(i) for i in range(chip.n_tiles))
            off = tuple(xy for xy in cores if xy != tuple(chip.io_tile) and xy not in used)
            return dataclasses.replace(chip, powered_off=off)
        except ConfigError as exc:
            raise ConfigError(exc.where, f"chip.{exc.field}" if exc.field else "chip", exc.reason) from exc
        except ValueError as exc:
            raise ConfigError(str(project.file), "chip", str(exc)) from exc

    def seed_chip(self) -> ChipConfig:
        """The seed's 2×2 chip for this mapping: I/O tile (0, 0), every unused core tile powered off."""
        used = set(self.tiles())
        off = tuple(xy for xy in ((0, 1), (1, 0), (1, 1)) if xy not in used)
        return ChipConfig(width=2, height=2, io_tile=(0, 0), powered_off=off)


def load_firmware_config(path: str | Path, section: str | None = None) -> FirmwareConfig:
    """Read a :class:`FirmwareConfig` from TOML (optionally from one top-level table).

    Raises:
        robosoc.config.ConfigError: naming the file and the dotted field.
    """
    return load_toml(FirmwareConfig, path, section)
