"""The lockstep co-simulation: the firmware on the chip flies the quadrotor under one clock."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from robosoc.config.firmware import FirmwareConfig
from robosoc.config.scenario import ScenarioConfig
from robosoc.config.vehicle import vehicle_preset
from robosoc.control.flight import ROW_FIELDS, column, fly
from robosoc.control.flight_log import CsvFlightLog
from robosoc.control.host import HostController
from robosoc.cosim.lockstep import (
    UNKNOWN_ESTIMATE,
    ChipFlight,
    arrival_step,
    fly_chip,
    fly_lockstep,
)
from robosoc.cosim.replay import replay
from robosoc.host.firmware_image import FIRST_SAMPLE_CYCLE
from robosoc.physics.clock import PHYSICS_STEP_NS

# calibration on the ground until 3 s, then the take-off climb (1 m in 1.5 s): 0.7 s of it
TAKEOFF = ScenarioConfig(duration_s=3.7)
VEHICLE = vehicle_preset(TAKEOFF.vehicle)
CYCLES_PER_SAMPLE = 2_500_000  # 10 ms at the seed's 250 MHz


@pytest.fixture(scope="module")
def flight() -> ChipFlight:
    return fly_chip(dataclasses.replace(TAKEOFF, seed=3), VEHICLE)


def test_fixed_mul_firmware_takes_off_and_follows_the_climb(flight: ChipFlight) -> None:
    rows = flight.rows
    t, z, sp = column(rows, "t"), column(rows, "z"), column(rows, "sp_height")
    armed = column(rows, "armed") > 0.5
    assert not armed[t < 2.99].any() and armed[t > 3.01].all()
    climbing = t >= 3.3
    assert z[-1] > VEHICLE.rest_height + 0.25, "it left the ground"
    assert np.abs(z[climbing] - sp[climbing]).max() < 0.1
    pwm = rows[:, [ROW_FIELDS.index(f"pwm{i}") for i in range(4)]]
    assert (pwm[~armed] == 0).all() and (pwm[t > 3.05] >= VEHICLE.idle_pwm).all()
    assert flight.run.deadline_misses == 0
    for name in ("estimator", "pid"):
        assert len(flight.run.jobs_of(name)) == len(rows)


def test_a_pwm_command_comes_back_for_every_sample_every_10_ms(flight: ChipFlight) -> None:
    commands = flight.run.commands
    assert [c.seq for c in commands] == list(range(len(flight.rows)))
    first = FIRST_SAMPLE_CYCLE
    for k, c in enumerate(commands):
        # within the sample's first physics step (1 ms = 250,000 cycles): the estimator and PID jobs
        # of fixed+mul answer within 0.85 ms on the default flight (0.72 + 0.09 ms at most)
        assert first + k * CYCLES_PER_SAMPLE < c.cycle < first + k * CYCLES_PER_SAMPLE + 250_000
        assert arrival_step(c.cycle, first, flight.run.clock_ns) == k * TAKEOFF.sensors.period_steps
    gaps = np.diff([c.cycle for c in commands])
    assert np.abs(gaps - CYCLES_PER_SAMPLE).max() < 250_000


def test_each_command_is_held_from_its_arrival_step_on(flight: ChipFlight) -> None:
    # every command arrives in its sample's first step, so row k (the command in force during that
    # step) holds command k
    chip = np.array([c.pwm for c in flight.run.commands])
    rows = flight.rows[:, [ROW_FIELDS.index(f"pwm{i}") for i in range(4)]]
    assert (rows == chip).all()


def test_rows_carry_the_chips_estimate_one_sample_behind(flight: ChipFlight) -> None:
    """Telemetry (host reads of the estimator tile): row k holds sample k - 1's estimate."""
    height = column(flight.rows, "est_height")
    assert np.isnan(height[0]) and not np.isnan(height[1:]).any()
    by_sample = {r.sample: r.values["est_height"] for r in flight.run.telemetry}
    assert [by_sample[k - 1] for k in range(1, len(height))] == list(height[1:])
    assert not np.isnan(column(flight.rows, "z")).any()


def test_lockstep_equals_replay_of_the_same_sensor_stream(flight: ChipFlight) -> None:
    replayed = replay(flight.rows, FirmwareConfig(), vehicle=VEHICLE, scenario=TAKEOFF)
    assert [(s.seq, s.cycle, s.payload) for s in replayed.samples] == [
        (s.seq, s.cycle, s.payload) for s in flight.run.samples
    ]
    assert replayed.commands == flight.run.commands
    assert replayed.jobs == flight.run.jobs
    assert replayed.cycles == flight.run.cycles


def test_two_flights_are_identical_byte_for_byte(tmp_path) -> None:
    short = ScenarioConfig(duration_s=3.2)
    logs = []
    runs = []
    for n in range(2):
        log = CsvFlightLog(tmp_path / f"{n}.csv")
        try:
            result = fly_chip(dataclasses.replace(short, seed=5), VEHICLE, on_row=log.write)
        finally:
            log.close()
        logs.append((tmp_path / f"{n}.csv").read_bytes())
        runs.append(result)
    assert logs[0] == logs[1]
    assert runs[0].rows.tobytes() == runs[1].rows.tobytes()
    assert runs[0].run.jobs == runs[1].run.jobs and runs[0].run.commands == runs[1].run.commands


class HostInLockstep:
    """The host controller behind the lockstep seam: its command ``delay_steps`` physics steps late."""

    def __init__(self, delay_steps: int) -> None:
        self.host = HostController.for_scenario(SHORT_HOST, VEHICLE)
        self.delay_ns = delay_steps * PHYSICS_STEP_NS
        self.pending: list[tuple[int, tuple[int, ...]]] = []
        self.issued: list[tuple[int, ...]] = []

    def reset(self) -> None:
        self.host.reset()
        self.pending = []
        self.issued = []

    def sense(self, k, t_ns, sample, setpoint, row) -> None:
        command = tuple(self.host.step(sample, setpoint))
        self.issued.append(command)
        self.pending.append((t_ns + self.delay_ns, command))

    def advance(self, t_ns):
        # a command "arrives" just after t_ready: in the step [t_ready, t_ready + 1 ms), ending at t_ns
        due = [pwm for ready, pwm in self.pending if ready < t_ns]
        self.pending = [(ready, pwm) for ready, pwm in self.pending if ready >= t_ns]
        return due[-1] if due else None

    def finish(self) -> None:
        pass

    @property
    def estimate(self):
        return self.host.estimate


SHORT_HOST = ScenarioConfig(duration_s=4.0)


def test_a_command_arriving_in_the_first_step_flies_like_the_host_loop() -> None:
    host = fly(SHORT_HOST, VEHICLE, HostController.for_scenario(SHORT_HOST, VEHICLE))
    lockstep = fly_lockstep(SHORT_HOST, VEHICLE, HostInLockstep(delay_steps=0))
    assert lockstep.tobytes() == host.tobytes()


def test_a_late_command_is_held_from_the_step_it_arrives_in() -> None:
    # ready 12 ms after its sample, command k arrives in the third physics step of period k + 1, so
    # the first step of period k + 1 still runs on command k - 1: row j holds command j - 2
    controller = HostInLockstep(delay_steps=12)
    rows = fly_lockstep(SHORT_HOST, VEHICLE, controller)
    pwm = rows[:, [ROW_FIELDS.index(f"pwm{i}") for i in range(4)]]
    issued = np.array(controller.issued)
    assert (pwm[:2] == 0).all()
    assert (pwm[2:] == issued[:-2]).all()
    assert (issued[-100:] > 0).all(), "the late controller flies too"


def test_unknown_estimate_is_nan() -> None:
    assert np.isnan(UNKNOWN_ESTIMATE.quaternion).all() and np.isnan(UNKNOWN_ESTIMATE.height)
