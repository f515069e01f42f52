"""Lockstep co-simulation: the physics world and the firmware on the chip under one clock.

One owner of time (PX4's lockstep idea): the loop of :func:`fly_lockstep` keeps simulated time as
an integer number of nanoseconds, ``t_ns``; the physics advances in whole steps (1 ms) and the
chip is run to the cycle of each step's end, so neither side ever waits on the host's clock and a
flight is as fast as the host allows and bit-for-bit repeatable.

Time mapping: ``t_ns`` is cycle ``first_cycle + round(t_ns / clock_ns)`` of the chip
(:func:`ChipController.cycle_of`); ``first_cycle`` (:data:`robosoc.host.firmware_image.FIRST_SAMPLE_CYCLE`) leaves
the firmware its boot, as in the replay harness.

Per sensor sample k, taken at ``t_k`` (a multiple of the sensor period):

1. the flight row of sample k is formed (truth at ``t_k``, the sample, the setpoint at ``t_k``,
   the controller's estimate once it has the sample);
2. the controller is given the sample (:meth:`LockstepController.sense`): the chip controller
   packs it exactly as :func:`robosoc.cosim.replay.samples_from_rows` would and injects it from
   the I/O tile at the cycle of ``t_k``;
3. for each physics step [t, t + 1 ms) of the sample period, the controller runs to ``t + 1 ms``
   (:meth:`LockstepController.advance`); the newest PWM command that reached the I/O tile in that
   step is applied to the motors from that step on and held until the next one (zero-order hold,
   quantised to the physics step containing the arrival cycle); then the world takes the step.

The row's PWM columns are the command in force during the sample's first physics step.  The chip's
state estimate never leaves the chip (only PWM messages reach the I/O tile); the host reads it from
the estimator tile's memory at each sample period's close (telemetry, :mod:`robosoc.host.telemetry`; no
simulated cycle), so row k's estimate columns hold the chip's newest estimate at ``t_k``: that of
sample k - 1 (the chip has not yet run sample k), NaN before the first.
"""

from __future__ import annotations

import contextlib
import gc
import math
import time
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from robosoc.chip.energy import EnergyModel
from robosoc.chip.step_calls import ChipThreads, StepCalls, host_cores
from robosoc.config.scenario import ScenarioConfig
from robosoc.config.vehicle import VehicleConfig
from robosoc.control import mission
from robosoc.control.flight import ROW_FIELDS, flight_row
from robosoc.control.host import Estimate, HostController
from robosoc.control.setpoint import Setpoint, setpoint_at
from robosoc.cosim.firmware_run import DEFAULT_FIRST_CYCLE, FirmwareRun, ReplayResult
from robosoc.cosim.replay import position_packet, sensor_packet
from robosoc.host.firmware_image import FirmwareImage
from robosoc.host.scenario_image import scenario_image
from robosoc.host.telemetry import estimate_of, own_names
from robosoc.physics import SensorSample, World
from robosoc.physics.clock import PHYSICS_STEP_NS, FlightClock
from robosoc.records import PowerSample, PwmCommand, SampleInput

"""The physics step in nanoseconds (1 ms)."""

PWM_COLUMNS = [ROW_FIELDS.index(f"pwm{i}") for i in range(4)]

Pwm = tuple[int, int, int, int]


class LockstepController(Protocol):
    """A controller that lives in simulated time: it is told each sample and run step by step."""

    def reset(self) -> None:
        """Start a new flight."""

    def sense(self, k: int, t_ns: int, sample: SensorSample, setpoint: Setpoint, row: np.ndarray) -> None:
        """Sample ``k``, taken at ``t_ns``, the setpoint then, and the flight row holding both (its
        PWM columns are not final yet)."""

    def advance(self, t_ns: int) -> Pwm | None:
        """Run to ``t_ns``; the newest command that arrived since the last call, or None."""

    def finish(self) -> None:
        """The flight is over (the controller has been advanced to its end)."""

    def energy_j(self) -> float:
        """The energy its computer has spent so far [J] (the chip's; 0 for one not simulated)."""

    def warn_low_battery(self) -> None:
        """The pack is below its reserve (a battery flight): from the next sample on, tell the firmware."""

    @property
    def estimate(self) -> Estimate:
        """The controller's current state estimate (NaN where it cannot be seen)."""


UNKNOWN_ESTIMATE = Estimate(np.full(4, math.nan), np.full(3, math.nan), math.nan, math.nan)
"""The chip controller's estimate before the host has read one from the chip."""


class ChipController:
    """A scenario's firmware project on the chip as a lockstep controller.

    Args:
        scenario, vehicle: what is flown (the firmware's control parameters come from them), by
            the scenario's firmware on its chip.
        image: the firmware, built once per flight by the caller (default: built here,
            :func:`robosoc.host.scenario_image.scenario_image`).
        energy: the energy model for the job records (default: the packaged coefficients).
        first_cycle: the cycle of simulated time 0 (the firmware boots before it).
        profile: count every instruction per function, tile and task (``result.profile``).
        timeline: record the chip's timeline for its trace (:class:`FirmwareRun`; off when no trace
            is written).

    Raises:
        ValueError: the mapping does not fit the chip; a controller parameter does not fit Q16.16.
        CompileError: the firmware failed to build.
    """

    def __init__(
        self,
        scenario: ScenarioConfig,
        vehicle: VehicleConfig,
        *,
        image: FirmwareImage | None = None,
        energy: EnergyModel | None = None,
        first_cycle: int = DEFAULT_FIRST_CYCLE,
        profile: bool = False,
        timeline: bool = True,
    ) -> None:
        self.scenario = scenario
        self.profile = profile
        self.timeline = timeline
        self.vehicle = vehicle
        self.fw = scenario.firmware
        self.chip = scenario.chip
        self.energy = energy or EnergyModel.load()
        self.first_cycle = first_cycle
        self.sample_period_us = FlightClock.of(scenario).sample_period_ns // 1000
        self.image = image if image is not None else scenario_image(scenario, vehicle)
        self.run: FirmwareRun | None = None
        self.result: ReplayResult | None = None
        #: (telemetry reads, run, estimate): the estimate of that run after that many reads
        self._estimate: tuple[int, FirmwareRun, Estimate] | None = None
        self._extra = tuple(name for name, _, _ in self.image.io_inputs)
        #: the firmware's telemetry under names of its own: columns of flight.csv after the flight's
        self.telemetry_names = own_names(self.image.telemetry)
        if "position" in self._extra and not scenario.sensors.position.enabled:
            raise ValueError(
                "sensors.position.enabled: the firmware takes position packets from the I/O tile, but the "
                "scenario's position sensor is off ([sensors.position] enabled = true)"
            )

    def reset(self) -> None:
        """A freshly booted chip with the firmware loaded."""
        self.run = FirmwareRun(
            self.fw,
            self.image,
            chip=self.chip,
            energy=self.energy,
            first_cycle=self.first_cycle,
            profile=self.profile,
            timeline=self.timeline,
        )
        self.result = None
        self.low_battery = False
        self._period_end = self.first_cycle
        self._at_period_end = False  # the chip has been run to _period_end
        self._ahead: list[PwmCommand] = []  # commands received ahead of the physics
        self._caught_up = False  # the chip ran this step's part already (catch_up_calls)
        self._home = (0.0, 0.0)  # the take-off point, from the first row
        self._clock_ns = self.run.clock_ns

    def _run(self) -> FirmwareRun:
        if self.run is None:
            raise RuntimeError("reset the controller first")
        return self.run

    def cycle_of(self, t_ns: int) -> int:
        """The chip cycle at simulated time ``t_ns``."""
        return self.first_cycle + round(t_ns / self._clock_ns)

    def sense(self, k: int, t_ns: int, sample: SensorSample, setpoint: Setpoint, row: np.ndarray) -> None:
        run = self._run()
        if k > 0:
            run.close_period()  # the chip is at the cycle of t_k: the previous sample's period ends
        packet = sensor_packet(row, k, self.sample_period_us, self.low_battery)
        if k == 0:  # the take-off point: where the vehicle stands at t = 0 (the mission's origin)
            self._home = (float(row[ROW_FIELDS.index("x")]), float(row[ROW_FIELDS.index("y")]))
        extra = self._extra_packets(k, sample, setpoint) if self._extra else ()
        run.inject(SampleInput(k, sample.time, self.cycle_of(t_ns), packet, extra))
        self._period_end = self.cycle_of(t_ns + self.sample_period_us * 1000)
        self._at_period_end = False

    def _extra_packets(self, k: int, sample: SensorSample, setpoint: Setpoint) -> tuple[tuple[str, bytes], ...]:
        """The position packet of sample ``k``: its fix, and the mission's setpoint in the world frame
        (over the take-off point at the setpoint's height before the mission starts, or without one)."""
        fix = sample.position_fix
        assert fix is not None  # the sensor is on (checked in __init__)
        x0, y0 = self._home
        relative = mission.position_setpoint(self.scenario.flight, self.vehicle.rest_height, sample.time)
        if relative is None:
            target = ((x0, y0, setpoint.height), (0.0, 0.0, setpoint.height_rate), (0.0, 0.0, setpoint.height_accel))
        else:
            (x, y, z), velocity, accel = relative
            target = ((x0 + x, y0 + y, z), velocity, accel)
        return (("position", position_packet(fix, target, k, sample.time, setpoint.armed)),)

    def catch_up_calls(self) -> StepCalls[None]:
        """What the next :meth:`advance` runs of the chip, as the chip loop calls it makes
        (:mod:`robosoc.chip.step_calls`; a fleet runs its chips' at once); that :meth:`advance`
        then only hands out the commands."""
        run = self._run()
        if run.cycle < self._period_end:
            self._ahead.extend((yield from run.run_to_calls(self._period_end)))
        self._caught_up = True

    def advance(self, t_ns: int) -> Pwm | None:
        # Nothing reaches the chip between two samples, so the chip runs to the next sample in one go
        # (one kernel call instead of one per physics step) and each command is handed out at the
        # step it arrived in, exactly as if the chip had been run step by step.
        if self._caught_up:
            self._caught_up = False
        elif not self._at_period_end:  # (once there, the chip stays: only sense moves the period's end)
            run = self._run()
            if run.cycle < self._period_end:
                self._ahead.extend(run.run_to(self._period_end))
            self._at_period_end = run.cycle >= self._period_end
        if not self._ahead:  # most physics steps: no command waits
            return None
        until = self.cycle_of(t_ns)
        due = 0
        while due < len(self._ahead) and self._ahead[due].cycle < until:
            due += 1
        if not due:
            return None
        pwm = self._ahead[due - 1].pwm
        del self._ahead[:due]
        return pwm

    def finish(self) -> None:
        run = self._run()
        if run.samples:
            run.close_period()
        self.result = run.result()

    def energy_j(self) -> float:
        """The chip's energy so far (tiles and NoC, :meth:`FirmwareRun.energy_pj`) [J]."""
        return sum(self._run().energy_pj().values()) * 1e-12

    def warn_low_battery(self) -> None:
        """Set :data:`packets.FLAG_LOW_BATTERY` in every sensor packet from now on (the firmware of a
        battery flight lands on it: docs/power.md)."""
        self.low_battery = True

    def result_so_far(self) -> ReplayResult | None:
        """The job records and totals up to where the flight stopped (an interrupted or crashed
        flight): :attr:`result` if it finished, None if it never started."""
        if self.result is not None or self.run is None:
            return self.result
        if self.run.period_open:
            self.run.close_period()
        return self.run.result()

    @property
    def estimate(self) -> Estimate:
        """The newest estimate the firmware published (its telemetry of the estimate's names,
        :func:`robosoc.host.telemetry.estimate_of`), NaN where it publishes none."""
        if self.run is None or not self.run.latest:
            return UNKNOWN_ESTIMATE
        reads = len(self.run.telemetry)  # the newest values change only with a telemetry read
        if self._estimate is None or self._estimate[0] != reads or self._estimate[1] is not self.run:
            self._estimate = (reads, self.run, estimate_of(self.run.latest))
        return self._estimate[2]

    def telemetry_values(self) -> tuple[float, ...]:
        """The newest value of each of :attr:`telemetry_names` read so far (NaN before the first),
        as the estimate: in row k, those read at or before the close of period k-1."""
        latest = self.run.latest if self.run is not None else {}
        return tuple(latest.get(name, math.nan) for name in self.telemetry_names)


def fly_lockstep(
    scenario: ScenarioConfig,
    vehicle: VehicleConfig,
    controller: LockstepController,
    on_row: Callable[[np.ndarray], None] | None = None,
    on_sample: Callable[[World, int], None] | None = None,
) -> np.ndarray:
    """Fly ``scenario`` with ``controller`` in lockstep; the flight with the columns :data:`ROW_FIELDS`.

    Args:
        scenario, vehicle: as :func:`robosoc.control.flight.fly`.
        controller: the controller, run in simulated time.
        on_row: called with each row as soon as it is complete (logging).
        on_sample: called with the world (at the sample's time) and the sample index (progress, video).
    """
    rows_of = None if on_row is None else (lambda _i, row: on_row(row))
    return fly_lockstep_fleet(scenario, [vehicle], [controller], on_row=rows_of, on_sample=on_sample)[0]


def fly_lockstep_fleet(
    scenario: ScenarioConfig,
    vehicles: Sequence[VehicleConfig],
    controllers: Sequence[LockstepController],
    on_row: Callable[[int, np.ndarray], None] | None = None,
    on_sample: Callable[[World, int], None] | None = None,
    on_power: Callable[[int, PowerSample], None] | None = None,
    threads: int | None = None,
) -> list[np.ndarray]:
    """Fly ``scenario`` with several vehicles in one world, vehicle i flown by ``controllers[i]``,
    all under one clock; the flight of each vehicle (columns :data:`ROW_FIELDS`).

    Per sample and per physics step the vehicles are served in their order: every controller is
    given its sample, then every controller is run to the end of each step before the world takes
    it.  Each vehicle's sensors draw from their own random stream (:meth:`World.reset`).

    A vehicle on a battery (:mod:`robosoc.physics.power`) is charged its controller's energy over
    each sample period as the chip's power in that period's steps (the chip has run the period
    when its first step is taken).

    Args:
        on_row: called with (vehicle index, row) as soon as a row is complete (logging).
        on_sample: called once per sample with the world and the sample index.
        on_power: for a vehicle on a battery, called with (vehicle index, its power system's state)
            just before each of its rows, and once more after the last step (the flight's totals).
        threads: how many host threads run the chips of several chip controllers at once
            (:class:`robosoc.chip.step_calls.ChipThreads`; default: one per host core, at most one
            per chip; 1: one chip after the other).  The flight is the same whatever the number.
            With a failing chip the others have run to the end of the same sample period.

    Raises:
        ValueError: not one controller per vehicle.
    """
    if len(controllers) != len(vehicles):
        raise ValueError(f"controllers: one per vehicle, got {len(controllers)} for {len(vehicles)} vehicles")
    chips = [c for c in controllers if isinstance(c, ChipController)]
    count = min(len(chips), host_cores() if threads is None else threads)
    with ChipThreads(max(count, 1)) as pool, _long_lived_frozen():
        together = chips if count > 1 else []
        return _fly_fleet(scenario, vehicles, controllers, on_row, on_sample, on_power, together, pool)


@contextlib.contextmanager
def _long_lived_frozen() -> Iterator[None]:
    """Keep what exists before a flight (modules, compiled kernels, the built firmware: some 150,000
    objects) out of the cyclic garbage collector's scans during it, and give it back after: a full
    collection in a 10 s flight scanned them all for about 40 ms, a twentieth of the flight."""
    gc.freeze()
    try:
        yield
    finally:
        gc.unfreeze()


def _fly_fleet(
    scenario: ScenarioConfig,
    vehicles: Sequence[VehicleConfig],
    controllers: Sequence[LockstepController],
    on_row: Callable[[int, np.ndarray], None] | None,
    on_sample: Callable[[World, int], None] | None,
    on_power: Callable[[int, PowerSample], None] | None,
    together: list[ChipController],
    pool: ChipThreads,
) -> list[np.ndarray]:
    """:func:`fly_lockstep_fleet`'s loop; the chips of ``together`` run their sample periods on ``pool`` at once."""
    clock = FlightClock.of(scenario)
    world = World(list(vehicles), scenario.sensors, scenario.wind)
    world.reset(scenario.seed)
    quads = world.quadrotors
    for controller in controllers:
        controller.reset()
    flights = [np.empty((clock.sample_count, len(ROW_FIELDS))) for _ in vehicles]
    rests = [v.rest_height for v in vehicles]
    pending: list[np.ndarray] = []
    period_s = clock.sample_period_ns * 1e-9
    chip_j = [0.0 for _ in vehicles]  # each controller's energy at the last period's end
    for k in clock.samples():
        if world.steps != clock.first_step(k):
            raise AssertionError("the world is not at the sample's step")
        t_ns = clock.sample_ns(k)
        wind = world.wind.velocity
        pending.clear()
        for quad, controller, rest in zip(quads, controllers, rests, strict=True):
            if quad.power is not None and quad.power.low_at_s is not None:
                controller.warn_low_battery()  # below the reserve: the firmware's failsafe lands
            sample = quad.sensors()
            setpoint = setpoint_at(scenario.flight, rest, sample.time)
            truth = quad.truth()
            given = flight_row(sample, truth, UNKNOWN_ESTIMATE, setpoint, quad.pwm, wind)
            controller.sense(k, t_ns, sample, setpoint, given)
            pending.append(flight_row(sample, truth, controller.estimate, setpoint, quad.pwm, wind))
        for s, t_end in clock.steps(k):
            if s == 0 and together:  # each chip runs the sample's period in the first step's advance
                pool.run_together([c.catch_up_calls() for c in together])
            for quad, controller in zip(quads, controllers, strict=True):
                pwm = controller.advance(t_end)
                if pwm is not None:
                    quad.apply_pwm(pwm)
            if s == 0:
                for i, (quad, row) in enumerate(zip(quads, pending, strict=True)):
                    if quad.power is not None:  # the chip has run this period: its power over it
                        spent = controllers[i].energy_j()
                        quad.power.chip_w = (spent - chip_j[i]) / period_s
                        chip_j[i] = spent
                        if on_power is not None:
                            on_power(i, quad.power.sample())
                    row[PWM_COLUMNS] = quad.pwm
                    flights[i][k] = row
                    if on_row is not None:
                        on_row(i, row)
                if on_sample is not None:
                    on_sample(world, k)
            world.step()
    for controller in controllers:
        controller.finish()
    if on_power is not None:
        for i, quad in enumerate(quads):
            if quad.power is not None:
                on_power(i, quad.power.sample())
    return flights


class HostLockstepController:
    """The float64 host controller behind the lockstep seam: it has no compute latency, so its
    command for a sample arrives in the sample's first physics step (a flight identical to
    :func:`robosoc.control.flight.fly`)."""

    def __init__(self, host: HostController) -> None:
        self.host = host
        self._fresh: Pwm | None = None

    def reset(self) -> None:
        self.host.reset()
        self._fresh = None

    def sense(self, k: int, t_ns: int, sample: SensorSample, setpoint: Setpoint, row: np.ndarray) -> None:
        m0, m1, m2, m3 = (int(v) for v in self.host.step(sample, setpoint))
        self._fresh = (m0, m1, m2, m3)

    def advance(self, t_ns: int) -> Pwm | None:
        fresh, self._fresh = self._fresh, None
        return fresh

    def finish(self) -> None:
        pass

    def energy_j(self) -> float:
        return 0.0  # the host controller is not a simulated computer

    def warn_low_battery(self) -> None:
        pass  # the failsafe is the firmware's: the host controller has none

    @property
    def estimate(self) -> Estimate:
        return self.host.estimate


@dataclass(frozen=True)
class ChipFlight:
    """A flight of the firmware on the chip: the rows, the firmware run, and its pace."""

    rows: np.ndarray
    run: ReplayResult
    simulated_s: float
    host_s: float

    @property
    def real_time_factor(self) -> float:
        """Simulated seconds per host second."""
        return self.simulated_s / self.host_s if self.host_s > 0 else math.inf


def fly_chip(
    scenario: ScenarioConfig,
    vehicle: VehicleConfig,
    *,
    on_row: Callable[[np.ndarray], None] | None = None,
    on_sample: Callable[[World, int], None] | None = None,
) -> ChipFlight:
    """Fly ``scenario`` with its firmware on its chip in lockstep (the firmware is built first,
    outside the timed flight)."""
    controller = ChipController(scenario, vehicle)
    start = time.perf_counter()
    rows = fly_lockstep(scenario, vehicle, controller, on_row=on_row, on_sample=on_sample)
    host_s = time.perf_counter() - start
    assert controller.result is not None
    simulated = FlightClock.of(scenario).simulated_s(len(rows))
    return ChipFlight(rows, controller.result, simulated, host_s)


def arrival_step(cycle: int, first_cycle: int, clock_ns: float) -> int:
    """Index of the physics step whose span holds chip cycle ``cycle``."""
    return math.floor((cycle - first_cycle) * clock_ns / PHYSICS_STEP_NS)


__all__ = [
    "UNKNOWN_ESTIMATE",
    "ChipController",
    "ChipFlight",
    "HostLockstepController",
    "LockstepController",
    "arrival_step",
    "fly_chip",
    "fly_lockstep",
    "fly_lockstep_fleet",
]
