"""Runs the flight firmware (the shipped quadrotor project) on the seed's chip against a recorded
flight's sensor packets, and reads its counters (``app_stats`` in the project's flight_app.c)."""

from __future__ import annotations

import struct
from dataclasses import dataclass

import numpy as np
from app_data import SensorRecord

from robosoc.chip.mpsoc import MPSoC
from robosoc.config.firmware import FirmwareConfig
from robosoc.host import images
from robosoc.host.firmware_image import FirmwareImage, sample_cycle
from robosoc.host.packets import PWM
from robosoc.host.scenario_image import firmware_image
from robosoc.program.elf import load_elf

APP_STATS_MAGIC = 0x53505041  # "APPS"
_APP_STATS_FIELDS = (
    "magic", "est_jobs", "est_foreign", "est_empty", "est_stale",
    "pid_jobs", "pid_foreign", "pid_empty", "pid_stale", "send_errors",
)  # fmt: skip
_APP_STATS = struct.Struct("<" + "I" * len(_APP_STATS_FIELDS))


@dataclass(frozen=True)
class AppStats:
    """``app_stats`` of one tile (meanings in the quadrotor project's flight_app.c)."""

    est_jobs: int
    est_foreign: int
    est_empty: int
    est_stale: int
    pid_jobs: int
    pid_foreign: int
    pid_empty: int
    pid_stale: int
    send_errors: int


def read_app_stats(chip: MPSoC, xy: tuple[int, int]) -> AppStats:
    t = chip.config.tile_index(xy)
    addr = chip.programs[t].address_of("app_stats")
    values = dict(
        zip(_APP_STATS_FIELDS, _APP_STATS.unpack(chip.cores.read(addr, _APP_STATS.size, tile=t)), strict=True)
    )
    assert values.pop("magic") == APP_STATS_MAGIC, f"tile {xy}: main has not run"
    return AppStats(**values)


def task_tile(image: FirmwareImage, name: str) -> tuple[int, int]:
    """The tile task ``name`` runs on."""
    return next(xy for xy, ids in image.tasks.items() if name in ids)


@dataclass
class ChipRun:
    chip: MPSoC
    image: FirmwareImage
    seq: list[int]
    pwm: np.ndarray
    arrival: list[int]
    """Cycle each PWM message reached the I/O tile."""

    def tile_of(self, name: str) -> tuple[int, int]:
        return task_tile(self.image, name)


def run_app(fw: FirmwareConfig, record: SensorRecord, extra: dict[int, list[list[int]]] | None = None) -> ChipRun:
    """Inject every sample at its cycle (and ``extra`` payloads just before sample k), step the chip
    between injections, collect the PWM messages."""
    chip = MPSoC(fw.seed_chip())
    image = firmware_image(fw)
    for xy in image.tiles:
        chip.load(xy, load_elf(image.elf, chip.regions(xy)))
    tile, port = image.sensor
    received = []
    for k in range(record.steps):
        at = sample_cycle(k)
        chip.step(at)
        received += chip.received()
        for payload in (extra or {}).get(k, []):
            chip.inject(tile, payload, at)
        for payload in images.io_packets(record.packet(k), port, chip.config.io_tile, k):
            chip.inject(tile, payload, at)
    chip.step(sample_cycle(record.steps))
    received += chip.received()
    messages = [m for m in images.reassemble(received) if m.port == image.actuator_port]
    fields = [PWM.unpack(m.data) for m in messages]
    return ChipRun(
        chip,
        image,
        [int(f["seq"]) for f in fields],  # type: ignore[arg-type]
        np.array([f["pwm"] for f in fields], dtype=np.int64).reshape(-1, 4),
        [m.cycle for m in messages],
    )


__all__ = ["AppStats", "ChipRun", "read_app_stats", "run_app", "task_tile"]
