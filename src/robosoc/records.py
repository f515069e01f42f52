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


#: The consumers of a vehicle's power budget (:attr:`PowerSample.energy_j`), docs/power.md.
POWER_CONSUMERS = ("motors", "chip", "avionics")
#: The power columns a battery flight's ``flight.csv`` gets after :data:`robosoc.control.flight.ROW_FIELDS`.
POWER_FIELDS = ("pack_v", "pack_a", "soc", "motors_w", "chip_w")


@dataclass(frozen=True)
class PowerSample:
    """A vehicle's power system at time ``t``: the pack's terminal voltage and current and state of
    charge after the last physics step, the consumers' power in it, and the energy each consumer has
    drawn from the pack since the start (``energy_j``, keys :data:`POWER_CONSUMERS`)."""

    t: float
    pack_v: float
    pack_a: float
    soc: float
    motors_w: float
    chip_w: float
    avionics_w: float
    energy_j: dict[str, float]
    empty_at_s: float | None
    low_at_s: float | None = None  # when the state of charge fell below the reserve (the failsafe's cue)

    @property
    def columns(self) -> tuple[float, ...]:
        """The values of :data:`POWER_FIELDS`."""
        return (self.pack_v, self.pack_a, self.soc, self.motors_w, self.chip_w)
