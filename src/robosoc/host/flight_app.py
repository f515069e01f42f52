"""The flight application (``firmware/app/flight_app.c``): build it for a firmware configuration,
and what the host needs to drive it and read it back (docs/firmware-app.md).

    fw = FirmwareConfig(arith="float", multiplier=False)
    elf = build(fw)
    chip = MPSoC(fw.seed_chip())
    for xy in app_tiles(fw):
        chip.load(xy, load_elf(elf, chip.regions(xy)))
    for k, packet in enumerate(sensor_packets):
        for payload in sensor_payloads(packet, fw, chip.config, seq=k):
            chip.inject(fw.ekf_tile, payload, sample_cycle(k))
    ...
    pwm = [m for m in images.reassemble(chip.received()) if m.port == PWM_PORT]

One ELF serves every tile: ``main`` creates the tasks mapped to its tile (os_tile()).
"""

from __future__ import annotations

import struct
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from robosoc.config.chip import ChipConfig
from robosoc.config.firmware import FirmwareConfig
from robosoc.config.scenario import ScenarioConfig
from robosoc.config.vehicle import VehicleConfig
from robosoc.firmware import (
    ALTITUDE_SOURCES,
    APP_DIR,
    EKF_SOURCES,
    ESTIMATOR_SOURCES,
    MATH_DIR,
    MATH_SOURCES,
    PID_SOURCES,
    arith_defines,
)
from robosoc.host import images
from robosoc.host.control_params import control_include_dir
from robosoc.host.firmware_image import FirmwareImage
from robosoc.host.packets import ESTIMATE_PORT, PWM_PORT, SENSOR_PORT

if TYPE_CHECKING:
    from robosoc.chip.mpsoc import MPSoC

APP_SOURCE = APP_DIR / "flight_app.c"
APP_STATS_SYMBOL = "app_stats"
APP_STATS_MAGIC = 0x53505041
_APP_STATS_FIELDS = (
    "magic", "est_jobs", "est_foreign", "est_empty", "est_stale",
    "pid_jobs", "pid_foreign", "pid_empty", "pid_stale", "send_errors",
)  # fmt: skip
_APP_STATS = struct.Struct("<" + "I" * len(_APP_STATS_FIELDS))

SAMPLE_PERIOD_US = 10_000
"""The sensor period of the default scenario (100 Hz)."""
FIRST_SAMPLE_CYCLE = 500_000
"""Cycle at which the host injects sample 0: every tile has started its kernel well before
(``os_start`` runs within the first 100,000 cycles; read_stats().start_cycle tells)."""


def sources() -> tuple[Path, ...]:
    """The application's sources (the kernel comes with :func:`images.build`)."""
    return (APP_SOURCE, *ESTIMATOR_SOURCES, *EKF_SOURCES, *ALTITUDE_SOURCES, *PID_SOURCES, *MATH_SOURCES)


def defines(fw: FirmwareConfig) -> dict[str, str | int | None]:
    """The preprocessor defines of ``fw``'s build: real_t, kernel tick and policy, mapping, release."""
    return {
        **arith_defines(fw.arith),
        "OS_TICK_CYCLES": fw.tick_cycles,
        "OS_SCHED_POLICY": "OS_SCHED_EDF" if fw.scheduler == "edf" else "OS_SCHED_RM",
        "APP_EST_TILE": images.tile_address(fw.ekf_tile),
        "APP_PID_TILE": images.tile_address(fw.pid_tile),
        "APP_PERIODIC": int(fw.release == "periodic"),
        "APP_PERIOD_TICKS": fw.period_ticks,
    }


def build(fw: FirmwareConfig, vehicle: VehicleConfig | None = None, scenario: ScenarioConfig | None = None) -> Path:
    """The flight application's ELF for ``fw`` (cached), with the controller parameters of
    ``vehicle`` flying ``scenario`` (defaults: the default scenario and its vehicle preset).

    Raises:
        CompileError: the compiler failed.
        ValueError: a controller parameter does not fit its fixed-point unit.
    """
    return images.build(
        list(sources()),
        mul=fw.multiplier,
        defines=defines(fw),
        include_dirs=[MATH_DIR, APP_DIR, control_include_dir(vehicle, scenario)],
    )


def image(
    fw: FirmwareConfig, vehicle: VehicleConfig | None = None, scenario: ScenarioConfig | None = None
) -> FirmwareImage:
    """The flight application built for ``fw`` (:func:`build`) with its tasks, sensor input and
    actuator port: what the host needs to fly it."""
    estimator = (int(fw.ekf_tile[0]), int(fw.ekf_tile[1]))
    return FirmwareImage(
        elf=build(fw, vehicle, scenario),
        tasks={xy: task_ids(fw, xy) for xy in app_tiles(fw)},
        sensor=(estimator, SENSOR_PORT),
        actuator_port=PWM_PORT,
        estimator=estimator,
    )


def app_tiles(fw: FirmwareConfig) -> list[tuple[int, int]]:
    """The tiles to load the ELF on (one, if both tasks share it)."""
    est, pid = fw.ekf_tile, fw.pid_tile
    return [est] if est == pid else [est, pid]


def task_ids(fw: FirmwareConfig, xy: tuple[int, int]) -> dict[str, int]:
    """TASK_ID of each application task on tile ``xy``: ``estimator`` and/or ``pid`` (the estimator
    is created first, so it has the lower id on a shared tile); empty for another tile."""
    out: dict[str, int] = {}
    next_id = images.FIRST_TASK_ID
    for name, tile in (("estimator", fw.ekf_tile), ("pid", fw.pid_tile)):
        if tuple(tile) == tuple(xy):
            out[name] = next_id
            next_id += 1
    return out


def sensor_payloads(packet: bytes, fw: FirmwareConfig, chip: ChipConfig, seq: int) -> list[list[int]]:
    """The payloads for :meth:`MPSoC.inject` carrying one sensor packet to the estimator's port."""
    return images.io_packets(packet, SENSOR_PORT, chip.io_tile, seq)


def sample_cycle(k: int, period_us: int = SAMPLE_PERIOD_US, clock_period_ns: float = 4.0) -> int:
    """The cycle at which sample ``k`` (taken at k · period) leaves the I/O tile:
    :data:`FIRST_SAMPLE_CYCLE` + k · period in cycles (10 ms = 2,500,000 cycles at 4 ns)."""
    per_sample = round(period_us * 1000 / clock_period_ns)
    return FIRST_SAMPLE_CYCLE + k * per_sample


@dataclass(frozen=True)
class AppStats:
    """``app_stats`` of one tile (meanings in flight_app.c)."""

    est_jobs: int
    est_foreign: int
    est_empty: int
    est_stale: int
    pid_jobs: int
    pid_foreign: int
    pid_empty: int
    pid_stale: int
    send_errors: int


EST_STATE_SYMBOL = "app_est"
"""The estimator task's state (``est_t app_est`` in flight_app.c), read by :func:`read_estimate`."""


@dataclass(frozen=True)
class ChipEstimate:
    """The estimator task's state estimate as it stands in the estimator tile's memory.

    ``sample`` is the index of the sample period at whose close it was read; ``jobs`` the
    estimates the task had computed by then (``app_stats.est_jobs``)."""

    sample: int
    jobs: int
    quaternion: tuple[float, float, float, float]  # w, x, y, z
    height: float  # [m]
    vertical_velocity: float  # [m/s]


def read_estimate(chip: MPSoC, fw: FirmwareConfig, sample: int = -1) -> ChipEstimate:
    """The estimator's quaternion, height and vertical speed, read from the estimator tile's memory
    by symbol and DWARF member offsets: a host read that costs the chip no cycle.

    Read it while the estimator task is not mid-job (e.g. while its tile sleeps), or the fields
    may come from two different steps.

    Raises:
        ValueError: no flight application on the estimator tile, or main has not run.
    """
    return EstimateReader(chip, fw).read(sample)


class EstimateReader:
    """:func:`read_estimate` for one chip, with the fields' addresses looked up once (a flight reads
    the estimate at every sample: looking up the symbol and the DWARF members each time cost more
    than the read).

    Raises:
        ValueError: no program on the estimator tile.
        ElfError: the program lacks the estimator's state or its debug information.
    """

    def __init__(self, chip: MPSoC, fw: FirmwareConfig) -> None:
        from robosoc.program.dwarf import member_offset

        xy = fw.ekf_tile
        t = chip.config.tile_index(xy)
        program = chip.programs.get(t)
        if program is None:
            raise ValueError(f"tile {xy} has no program loaded")
        base = program.address_of(EST_STATE_SYMBOL)

        def address(member: str, index: int = 0) -> int:
            return base + member_offset(program.path, "est_t", member)[0] + 4 * index

        self.chip, self.xy, self.tile = chip, xy, t
        #: w, x, y, z of the quaternion, the height, the vertical speed: read as one span
        addresses = (*(address("ekf.x", i) for i in range(4)), address("alt.h"), address("alt.v"))
        self.first = min(addresses)
        self.span = max(addresses) + 4 - self.first
        self.offsets = [a - self.first for a in addresses]
        self.format = "<i" if fw.arith == "fixed" else "<f"
        self.scale = 1.0 / 65536.0 if fw.arith == "fixed" else 1.0
        try:  # app_stats (read_app_stats without its dict: only the magic and est_jobs are read)
            self.stats = program.address_of(APP_STATS_SYMBOL)
        except ValueError as exc:
            raise ValueError(f"tile {xy}: {program.path} is not the flight application") from exc

    def read(self, sample: int = -1) -> ChipEstimate:
        """The estimate now, as read at the close of sample period ``sample``.

        Raises:
            ValueError: main has not run.
        """
        read = self.chip.cores.read
        stats = _APP_STATS.unpack(read(self.stats, _APP_STATS.size, tile=self.tile))
        magic, est_jobs = stats[_APP_STATS_FIELDS.index("magic")], stats[_APP_STATS_FIELDS.index("est_jobs")]
        if magic != APP_STATS_MAGIC:
            raise ValueError(f"tile {self.xy}: the application has not started")
        raw = read(self.first, self.span, tile=self.tile)
        w, x, y, z, h, v = (float(struct.unpack_from(self.format, raw, o)[0]) * self.scale for o in self.offsets)
        return ChipEstimate(sample, est_jobs, (w, x, y, z), h, v)


def read_app_stats(chip: MPSoC, xy: tuple[int, int]) -> AppStats:
    """The application's counters on tile ``xy``.

    Raises:
        ValueError: no program on the tile, not the flight application, or main has not run.
    """
    t = chip.config.tile_index(xy)
    program = chip.programs.get(t)
    if program is None:
        raise ValueError(f"tile {xy} has no program loaded")
    try:
        addr = program.address_of(APP_STATS_SYMBOL)
    except ValueError as exc:
        raise ValueError(f"tile {xy}: {program.path} is not the flight application") from exc
    values = dict(
        zip(_APP_STATS_FIELDS, _APP_STATS.unpack(chip.cores.read(addr, _APP_STATS.size, tile=t)), strict=True)
    )
    if values.pop("magic") != APP_STATS_MAGIC:
        raise ValueError(f"tile {xy}: the application has not started")
    return AppStats(**values)


__all__ = [
    "APP_SOURCE",
    "APP_STATS_SYMBOL",
    "ESTIMATE_PORT",
    "EST_STATE_SYMBOL",
    "FIRST_SAMPLE_CYCLE",
    "PWM_PORT",
    "SAMPLE_PERIOD_US",
    "SENSOR_PORT",
    "AppStats",
    "ChipEstimate",
    "EstimateReader",
    "app_tiles",
    "build",
    "defines",
    "image",
    "read_app_stats",
    "read_estimate",
    "sample_cycle",
    "sensor_payloads",
    "task_ids",
]
