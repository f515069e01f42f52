"""Runs the flight application on the seed's chip against a recorded flight's sensor packets."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from app_data import SensorRecord

from robosoc.chip.mpsoc import MPSoC
from robosoc.config.firmware import FirmwareConfig
from robosoc.host import images
from robosoc.host.flight_app import build, read_app_stats, sample_cycle, sensor_payloads
from robosoc.host.packets import PWM, PWM_PORT
from robosoc.program.elf import load_elf


@dataclass
class ChipRun:
    chip: MPSoC
    seq: list[int]
    pwm: np.ndarray
    arrival: list[int]
    """Cycle each PWM message reached the I/O tile."""


def run_app(fw: FirmwareConfig, record: SensorRecord, extra: dict[int, list[list[int]]] | None = None) -> ChipRun:
    """Inject every sample at its cycle (and ``extra`` payloads just before sample k), step the chip
    between injections, collect the PWM messages."""
    chip = MPSoC(fw.seed_chip())
    elf = build(fw)
    for xy in {tuple(fw.ekf_tile), tuple(fw.pid_tile)}:
        chip.load(xy, load_elf(elf, chip.regions(xy)))
    received = []
    for k in range(record.steps):
        at = sample_cycle(k)
        chip.step(at)
        received += chip.received()
        for payload in (extra or {}).get(k, []):
            chip.inject(tuple(fw.ekf_tile), payload, at)
        for payload in sensor_payloads(record.packet(k), fw, chip.config, seq=k):
            chip.inject(tuple(fw.ekf_tile), payload, at)
    chip.step(sample_cycle(record.steps))
    received += chip.received()
    messages = [m for m in images.reassemble(received) if m.port == PWM_PORT]
    fields = [PWM.unpack(m.data) for m in messages]
    return ChipRun(
        chip,
        [int(f["seq"]) for f in fields],  # type: ignore[arg-type]
        np.array([f["pwm"] for f in fields], dtype=np.int64).reshape(-1, 4),
        [m.cycle for m in messages],
    )


__all__ = ["ChipRun", "read_app_stats", "run_app"]
