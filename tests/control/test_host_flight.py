"""Closed-loop flights of the host controller: the issue's figures, determinism, logs."""

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

from robosoc.config.scenario import FlightPlan, GustConfig, ScenarioConfig, SensorConfig, WindConfig
from robosoc.config.vehicle import VehicleConfig, vehicle_preset
from robosoc.control.flight import ROW_FIELDS, FlightMetrics, column, flight_metrics, fly
from robosoc.control.flight_log import CsvFlightLog, read_flight_log
from robosoc.control.host import HostController

SCENARIO = ScenarioConfig()


def _fly(
    scenario: ScenarioConfig = SCENARIO, seed: int = 1, variant: str = "default", vehicle: VehicleConfig | None = None
) -> np.ndarray:
    vehicle = vehicle or vehicle_preset(variant)
    scenario = dataclasses.replace(scenario, seed=seed)
    return fly(scenario, vehicle, HostController.for_scenario(scenario, vehicle))


def _metrics(rows: np.ndarray, scenario: ScenarioConfig = SCENARIO) -> FlightMetrics:
    return flight_metrics(rows, scenario.flight, vehicle_preset(scenario.vehicle).rest_height)


@pytest.fixture(scope="module")
def default_flights() -> list[np.ndarray]:
    return [_fly(seed=seed) for seed in (1, 2, 3)]


def test_hover_altitude_error_below_5_cm_rms(default_flights: list[np.ndarray]) -> None:
    for rows in default_flights:
        metrics = _metrics(rows)
        assert metrics.hover_rms < 0.05


def test_ekf_attitude_error_below_1_degree_rms(default_flights: list[np.ndarray]) -> None:
    for rows in default_flights:
        assert _metrics(rows).ekf_rms < 1.0


def test_attitude_tracks_10_degree_steps(default_flights: list[np.ndarray]) -> None:
    for rows in default_flights:
        metrics = _metrics(rows)
        assert max(metrics.tracking_rms[:2]) < 1.0 and metrics.tracking_rms[2] < 1.5
        for axis, _, rise in metrics.step_rise:
            assert rise < (1.0 if axis == "yaw" else 0.7), axis
        t = column(rows, "t")
        held = (t > 5.6) & (t < 6.0)  # roll setpoint 10° from 5.0 s to 6.0 s
        assert np.degrees(column(rows, "roll")[held]).mean() == pytest.approx(10.0, abs=1.0)
        # The loop holds the *estimated* yaw: the truth also carries the EKF's yaw error.
        assert np.degrees(column(rows, "yaw")[t > 9.0]).mean() == pytest.approx(10.0, abs=2.0)
        assert np.degrees(column(rows, "est_yaw")[t > 9.0]).mean() == pytest.approx(10.0, abs=1.0)


def test_motors_stay_off_while_calibrating_then_the_vehicle_climbs(default_flights: list[np.ndarray]) -> None:
    rows = default_flights[0]
    t = column(rows, "t")
    ground = t < SCENARIO.flight.takeoff_s
    assert np.all(rows[ground][:, [24, 25, 26, 27]] == 0)
    assert column(rows, "z")[t > 4.5].min() > 0.9
    # Once armed, no motor goes below the idle PWM.
    assert _metrics(rows).min_pwm_armed >= vehicle_preset("default").idle_pwm


def test_ekf_matches_truth_closely_without_noise() -> None:
    scenario = dataclasses.replace(SCENARIO, sensors=SensorConfig(noise=False))
    metrics = _metrics(_fly(scenario), scenario)
    assert metrics.ekf_rms < 0.2
    assert metrics.height_estimate_rms < 0.005
    assert metrics.hover_rms < 0.03


def test_laser_variant_flies_the_scenario() -> None:
    metrics = _metrics(_fly(variant="laser"))
    assert metrics.hover_rms < 0.05 and metrics.ekf_rms < 1.0


def test_same_seed_same_flight_bit_for_bit() -> None:
    short = dataclasses.replace(SCENARIO, duration_s=4.0)
    a, b, c = _fly(short, seed=9), _fly(short, seed=9), _fly(short, seed=10)
    assert np.array_equal(a, b)
    assert not np.array_equal(a, c)


def test_log_survives_an_interrupted_flight(tmp_path: Path) -> None:
    vehicle = vehicle_preset("default")
    path = tmp_path / "flight.csv"
    written = []

    class Crash(Exception):
        pass

    with CsvFlightLog(path) as log:

        def on_row(row: np.ndarray) -> None:
            log.write(row)
            written.append(row)
            if len(written) == 50:
                raise Crash

        with pytest.raises(Crash):
            fly(SCENARIO, vehicle, HostController(vehicle, 0.01), on_row=on_row)
        # Before closing: every row is already flushed to the file.
        rows = read_flight_log(path)
    assert rows.shape == (50, len(written[0]))
    np.testing.assert_array_equal(rows, np.array(written))
    assert math.isclose(rows[-1, 0], 0.49)


CLIMB_RATE = SCENARIO.flight.climb_rate_mps


@pytest.mark.parametrize("height", [1.0, 2.0, 5.0])
def test_climbs_of_any_size_keep_the_default_steps_and_do_not_overshoot(height: float) -> None:
    # Only the height changes: the default roll and pitch steps (5–6 s, 6.5–7.5 s) stay in the plan.
    # 8 s is enough to see the 5 m climb end (6.8 s) and the window after it.
    plan = dataclasses.replace(SCENARIO.flight, height_m=height)
    scenario = dataclasses.replace(SCENARIO, duration_s=8.0, flight=plan)
    rows = _fly(scenario)
    metrics = _metrics(rows, scenario)
    (climb,) = plan.height_moves(vehicle_preset("default").rest_height)
    assert climb.end_s + 1.0 <= scenario.duration_s
    t, z = column(rows, "t"), column(rows, "z")
    assert metrics.overshoot < 0.05
    assert abs(z[t >= climb.end_s + 1.0] - height).max() < 0.05  # and arrives
    # The true climb speed stays within the limit (2 m/s) the profile and controller share.
    assert np.diff(z[t >= climb.start_s]).max() / 0.01 < CLIMB_RATE * 1.05
    assert metrics.min_pwm_armed >= vehicle_preset("default").idle_pwm
    assert max(metrics.tracking_rms[:2]) < 0.35
    held = (t > 5.6) & (t < 6.0)  # roll setpoint 10°, whether or not the vehicle still climbs
    assert np.degrees(column(rows, "roll")[held]).mean() == pytest.approx(10.0, abs=1.0)


def _updraft(idle_pwm: int) -> tuple[np.ndarray, np.ndarray]:
    """Hover at 1 m with a 10° roll step at 5 s while a 10 m/s updraft (4.5–6 s) lifts the vehicle:
    its drag (0.1·10² = 10 N) leaves 4.5 N to carry, less than four idle rotors give (6.7 N)."""
    gust = GustConfig(start_s=4.5, duration_s=1.5, rise_s=0.3, velocity=(0.0, 0.0, 10.0))
    plan = FlightPlan(steps=(SCENARIO.flight.steps[0],))
    scenario = ScenarioConfig(duration_s=6.5, wind=WindConfig(gusts=(gust,)), flight=plan)
    vehicle = dataclasses.replace(vehicle_preset("default"), idle_pwm=idle_pwm)
    rows = _fly(scenario, vehicle=vehicle)
    t = column(rows, "t")
    in_gust = (t > 4.6) & (t < 6.2) & ~((t >= 5.0) & (t < 5.5))  # leaving out the step's rise
    roll_error = np.degrees(np.abs(column(rows, "roll") - column(rows, "sp_roll")))[in_gust]
    pwm = rows[:, [ROW_FIELDS.index(f"pwm{i}") for i in range(4)]][column(rows, "armed") > 0.5]
    return roll_error, pwm


def test_motors_keep_the_idle_minimum_and_attitude_authority_when_thrust_must_drop() -> None:
    roll_error, pwm = _updraft(idle_pwm=50)
    assert pwm.min() == 50  # the floor is reached ...
    assert (pwm == 50).any(axis=1).sum() > 20  # ... for a while
    assert roll_error.max() < 3.0
    # The same flight with no floor: the motors drop towards PWM 0, where this motor model gives
    # every rotor the same free-spinning thrust, and roll control loses its grip.
    roll_error, pwm = _updraft(idle_pwm=0)
    assert pwm.min() < 10
    assert roll_error.max() > 5.0


def test_a_flight_row_holds_the_sample_and_setpoint_the_controller_was_given() -> None:
    # the log must be replayable into firmware: record what the controller receives and compare
    scenario = dataclasses.replace(SCENARIO, duration_s=0.5)
    vehicle = vehicle_preset("default")
    host = HostController.for_scenario(scenario, vehicle)
    given = []

    class Recording:
        def reset(self) -> None:
            host.reset()

        def step(self, sample, setpoint):
            given.append((sample, setpoint))
            return host.step(sample, setpoint)

        @property
        def estimate(self):
            return host.estimate

    rows = fly(dataclasses.replace(scenario, seed=4), vehicle, Recording())
    assert len(given) == len(rows) == 50
    for row, (sample, setpoint) in zip(rows, given, strict=True):
        by_name = dict(zip(ROW_FIELDS, row, strict=True))
        assert [by_name[f"gyro_{a}"] for a in "xyz"] == list(sample.gyro)
        assert [by_name[f"accel_{a}"] for a in "xyz"] == list(sample.accel)
        assert [by_name[f"mag_{a}"] for a in "xyz"] == list(sample.mag)
        assert by_name["baro_altitude"] == sample.baro_altitude and by_name["t"] == sample.time
        assert (by_name["sp_height"], by_name["sp_height_rate"], by_name["sp_height_accel"]) == (
            setpoint.height, setpoint.height_rate, setpoint.height_accel,
        )  # fmt: skip
