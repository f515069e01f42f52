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
    ekf_tile = [0, 1]
    pid_tile = [1, 0]
    project = ""             # a firmware project's folder (its robosoc.toml names the tasks and
                             # their tiles; ekf_tile, pid_tile and release are the built-in's)

The defaults are the seed's case study on its 2×2 chip: the I/O tile at (0, 0), the estimator
(EKF and altitude filter) on (0, 1), the PID controller on (1, 0), the fourth tile powered off
(see :func:`seed_chip`), Q16.16 with the multiplier.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from robosoc.config.chip import ChipConfig
from robosoc.config.validate import load_toml

__all__ = [
    "ARITH_CHOICES",
    "FIXED_MUL64_CHOICES",
    "RELEASE_CHOICES",
    "SCHEDULER_CHOICES",
    "FirmwareConfig",
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


def _choice(name: str, value: str, choices: tuple[str, ...]) -> None:
    if value not in choices:
        raise ValueError(f"{name}: must be one of {', '.join(map(repr, choices))}, got {value!r}")


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
        ekf_tile: the tile of the estimator task.
        pid_tile: the tile of the PID task (may equal ``ekf_tile``).
        project: the folder of a firmware project to fly instead of the built-in application
            (docs/firmware-projects.md); in a scenario file, relative to the file's folder.
    """

    arith: str = "fixed"
    multiplier: bool = True
    release: str = "event"
    fixed_mul64: str = "shift-add"
    scheduler: str = "edf"
    tick_cycles: int = 262144
    period_ticks: int = 10
    ekf_tile: tuple[int, int] = (0, 1)
    pid_tile: tuple[int, int] = (1, 0)
    project: str = ""

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
        for name in ("ekf_tile", "pid_tile"):
            xy = getattr(self, name)
            if len(xy) != 2 or min(xy) < 0:
                raise ValueError(f"{name}: must be a tile [x, y] with x, y >= 0, got {list(xy)}")

    @property
    def muldi3(self) -> bool:
        """Whether this build forms Q16.16 products through compiler-rt's ``__muldi3`` (a fixed-point
        build without the multiplier with ``fixed_mul64 = "muldi3"``)."""
        return self.arith == "fixed" and not self.multiplier and self.fixed_mul64 == "muldi3"

    @property
    def label(self) -> str:
        """``fixed+mul``, ``float-no-mul``...: how tables and file names name a build."""
        return f"{self.arith}{'+mul' if self.multiplier else '-no-mul'}"

    def check_chip(self, chip: ChipConfig) -> None:
        """Raise ValueError unless both task tiles are powered core tiles of ``chip``."""
        for name in ("ekf_tile", "pid_tile"):
            x, y = getattr(self, name)
            xy = (int(x), int(y))
            problem = chip.core_tile_problem(xy)
            if problem:
                raise ValueError(f"{name}: {list(xy)} {problem}")

    def default_chip(self) -> ChipConfig:
        """The chip a replay runs on when none is given: the seed's for the built-in application
        (:meth:`seed_chip`), the seed's 2×2 with every core tile powered for a project."""
        return ChipConfig(width=2, height=2, io_tile=(0, 0)) if self.project else self.seed_chip()

    def seed_chip(self) -> ChipConfig:
        """The seed's 2×2 chip for this mapping: I/O tile (0, 0), every unused core tile powered off."""
        used = {tuple(self.ekf_tile), tuple(self.pid_tile)}
        off = tuple(xy for xy in ((0, 1), (1, 0), (1, 1)) if xy not in used)
        return ChipConfig(width=2, height=2, io_tile=(0, 0), powered_off=off)


def load_firmware_config(path: str | Path, section: str | None = None) -> FirmwareConfig:
    """Read a :class:`FirmwareConfig` from TOML (optionally from one top-level table).

    Raises:
        robosoc.config.ConfigError: naming the file and the dotted field.
    """
    return load_toml(FirmwareConfig, path, section)
