"""Records of a run that every layer may read: sensor samples as the firmware receives them, the
actuator commands it sends back, and one record per job of a task (timing and energy).

They hold numbers only; the firmware run (:mod:`robosoc.cosim.firmware_run`) makes them and the
run's outputs (:mod:`robosoc.outputs`) write them.
"""

from __future__ import annotations

from dataclasses import dataclass

#: The parts of a job's energy (:attr:`JobRecord.energy_pj`), see :mod:`robosoc.cosim.firmware_run`.
ENERGY_PARTS = ("task", "kernel", "idle", "noc")


@dataclass(frozen=True)
class SampleInput:
    """One sensor sample as the firmware receives it, and the cycle it is injected in: the sensor
    packet (``payload``) and the further packets sent with it, by format name (``extra``: the
    position packet, for a firmware project that takes it)."""

    seq: int
    time_s: float
    cycle: int
    payload: bytes
    extra: tuple[tuple[str, bytes], ...] = ()


@dataclass(frozen=True)
class JobRecord:
    """One job of a firmware task: timing from the kernel's job log, cost from the simulator's counters."""

    task: str
    tile: tuple[int, int]
    job: int
    release_cycle: int
    start_cycle: int
    completion_cycle: int
    exec_cycles: int
    deadline_met: bool
    instructions: int
    energy_pj: dict[str, float]
    spans_periods: bool

    @property
    def response_cycles(self) -> int:
        return self.completion_cycle - self.release_cycle

    @property
    def energy_total_pj(self) -> float:
        return sum(self.energy_pj.values())


@dataclass(frozen=True)
class PwmCommand:
    seq: int
    pwm: tuple[int, int, int, int]
    cycle: int  # the PWM message's last packet reached the I/O tile
