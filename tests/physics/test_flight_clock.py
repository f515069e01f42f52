"""The flight clock alone (``robosoc.physics.clock``): the schedule every flight walks, checked against
times worked out by hand, and the three flights that use it walking the world in step with it."""

from __future__ import annotations

import dataclasses

import pytest

from robosoc.config.scenario import FlightPlan, ScenarioConfig, SensorConfig
from robosoc.physics.clock import NS_PER_S, PHYSICS_STEP_NS, FlightClock


def test_a_step_is_one_millisecond_in_integer_nanoseconds() -> None:
    assert PHYSICS_STEP_NS == 1_000_000 and isinstance(PHYSICS_STEP_NS, int)
    assert NS_PER_S == 10**9


def test_the_schedule_of_three_samples_of_ten_steps() -> None:
    clock = FlightClock(steps_per_sample=10, sample_count=3)
    assert clock.sample_period_ns == 10_000_000  # 10 ms: 100 Hz
    assert clock.duration_ns == 30_000_000
    assert list(clock.samples()) == [0, 1, 2]
    assert [clock.sample_ns(k) for k in clock.samples()] == [0, 10_000_000, 20_000_000]
    assert [clock.first_step(k) for k in clock.samples()] == [0, 10, 20]
    steps = list(clock.steps(1))
    assert steps[0] == (0, 11_000_000) and steps[-1] == (9, 20_000_000) and len(steps) == 10
    assert [end for _, end in steps] == list(range(11_000_000, 20_000_001, 1_000_000))
    assert clock.simulated_s(3) == 0.03 and clock.simulated_s(0) == 0.0


def test_consecutive_samples_tile_time_without_gap_or_drift() -> None:
    """After a million samples the clock is still exactly on its grid (floats would have drifted)."""
    clock = FlightClock(steps_per_sample=4, sample_count=1_000_000)
    k = clock.sample_count - 1
    assert clock.sample_ns(k) == k * 4_000_000
    last_end = list(clock.steps(k - 1))[-1][1]
    assert last_end == clock.sample_ns(k)
    assert list(clock.steps(k))[-1][1] == clock.duration_ns


def test_the_clock_of_a_scenario() -> None:
    clock = FlightClock.of(ScenarioConfig(duration_s=0.5))
    assert (clock.steps_per_sample, clock.sample_count) == (10, 50)
    fast = FlightClock.of(ScenarioConfig(duration_s=0.5, sensors=SensorConfig(rate_hz=250.0)))
    assert (fast.steps_per_sample, fast.sample_count) == (4, 125)


def test_the_smallest_schedule_is_one_sample_of_one_step() -> None:
    clock = FlightClock(steps_per_sample=1, sample_count=1)
    assert list(clock.samples()) == [0] and list(clock.steps(0)) == [(0, PHYSICS_STEP_NS)]
    assert clock.duration_ns == clock.sample_period_ns == PHYSICS_STEP_NS


@pytest.mark.parametrize(("steps", "count", "field"), [(0, 3, "steps_per_sample"), (10, 0, "sample_count")])
def test_an_empty_schedule_is_refused(steps: int, count: int, field: str) -> None:
    with pytest.raises(ValueError, match=f"^{field}: must be at least 1"):
        FlightClock(steps, count)


def test_the_flights_walk_the_world_on_the_clock() -> None:
    """The host flight, the lockstep flight and the decoupled physics side's schedule: each row's
    time is its sample's time on the clock, and the world ends at the clock's duration."""
    from robosoc.config.vehicle import vehicle_preset
    from robosoc.control.flight import ROW_FIELDS, fly
    from robosoc.control.host import HostController
    from robosoc.cosim.lockstep import HostLockstepController, fly_lockstep

    scenario = ScenarioConfig(duration_s=0.2, flight=FlightPlan(takeoff_s=0.1, steps=()), seed=3)
    scenario = dataclasses.replace(scenario, sensors=SensorConfig(rate_hz=50.0))
    clock = FlightClock.of(scenario)
    vehicle = vehicle_preset(scenario.vehicle)
    host = fly(scenario, vehicle, HostController.for_scenario(scenario, vehicle))
    lockstep = fly_lockstep(scenario, vehicle, HostLockstepController(HostController.for_scenario(scenario, vehicle)))
    t = ROW_FIELDS.index("t")
    expected = [clock.sample_ns(k) / NS_PER_S for k in clock.samples()]
    assert list(host[:, t]) == expected and list(lockstep[:, t]) == expected
    assert (host == lockstep).all()
