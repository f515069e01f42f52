"""HostController's life cycle: its parts, calibration on the ground, arming and a new flight."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from robosoc.config.scenario import FlightPlan, ScenarioConfig, SensorConfig
from robosoc.config.vehicle import vehicle_preset
from robosoc.control.altitude import AltitudeParams
from robosoc.control.ekf import EkfParams
from robosoc.control.host import GRAVITY, MOTION_ACCEL, MOTORS_OFF, HostController
from robosoc.control.mixer import Mixer
from robosoc.control.setpoint import Setpoint
from robosoc.physics.sensors import SensorSample

VEHICLE = vehicle_preset("default")
REST = VEHICLE.rest_height


def sample(accel=(0.0, 0.0, GRAVITY), gyro=(0.01, -0.02, 0.005), mag=(0.5, 0.0, -0.866), baro=100.0) -> SensorSample:
    return SensorSample(0.0, np.array(accel), np.array(gyro), np.array(mag), baro, 1000.0)


def test_parts_are_built_from_the_vehicle_and_the_options() -> None:
    hc = HostController(VEHICLE, 0.01, ekf=EkfParams(accel_noise=2.0), altitude=AltitudeParams(baro_noise=0.3))
    hover = VEHICLE.mass * GRAVITY / 4
    reference = Mixer(VEHICLE.motor, VEHICLE.arm_length, hover, VEHICLE.idle_pwm)
    assert (hc.mixer.yaw_k, hc.mixer.min_force, hc.mixer.max_force) == (
        reference.yaw_k, reference.min_force, reference.max_force
    )  # fmt: skip
    assert hc.ekf.params.accel_noise == 2.0 and hc.altitude.params.baro_noise == 0.3
    assert HostController(VEHICLE, 0.01).ekf.params == EkfParams()
    assert HostController(VEHICLE, 0.01).altitude.params == AltitudeParams()
    scenario = ScenarioConfig(
        sensors=SensorConfig(rate_hz=200.0), flight=FlightPlan(climb_rate_mps=3.0, descent_rate_mps=0.5)
    )
    fs = HostController.for_scenario(scenario, VEHICLE)
    assert fs.dt == pytest.approx(0.005)
    assert (fs.height_loop.climb_rate, fs.height_loop.descent_rate) == (3.0, 0.5)


def test_a_new_controller_knows_nothing() -> None:
    hc = HostController(VEHICLE, 0.01)
    e = hc.estimate
    np.testing.assert_array_equal(e.quaternion, [1.0, 0.0, 0.0, 0.0])
    assert e.height == REST and e.vertical_velocity == 0.0
    assert hc.last_pwm == MOTORS_OFF and hc.accel_bias.shape == (3,) and not hc.accel_bias.any()
    assert hc.altitude.reference == -REST  # an uncalibrated barometer is taken to read 0 on the ground
    assert hc.height_loop.speed_command == 0.0


def test_calibration_averages_still_samples_and_restarts_on_motion() -> None:
    hc = HostController(VEHICLE, 0.01)
    off = Setpoint(height=REST, armed=False)
    for baro in (100.0, 100.2, 100.4):
        assert hc.step(sample(baro=baro), off) == MOTORS_OFF
    assert hc.altitude.reference == pytest.approx(100.2 - REST)
    assert hc.altitude.covariance[0, 0] == pytest.approx(AltitudeParams().baro_noise ** 2 / 3)
    np.testing.assert_allclose(hc.ekf.gyro_bias, [0.01, -0.02, 0.005])
    # a sample at exactly the motion threshold still counts as still; beyond it the average restarts
    edge = GRAVITY + MOTION_ACCEL
    assert abs(edge - GRAVITY) == MOTION_ACCEL
    hc.step(sample(accel=(0.0, 0.0, edge), baro=100.6), off)
    assert hc.altitude.reference == pytest.approx((100.0 + 100.2 + 100.4 + 100.6) / 4 - REST)
    hc.step(sample(accel=(0.0, 0.0, GRAVITY + 2.5), baro=90.0), off)  # moving: ignored, sums restart
    hc.step(sample(baro=101.0), off)
    assert hc.altitude.reference == pytest.approx(101.0 - REST)
    # the level calibration: what the accelerometer reads beyond [0, 0, g] at rest is its bias
    hc.step(sample(accel=(0.1, -0.1, GRAVITY + 0.3), baro=101.0), off)
    np.testing.assert_allclose(hc.accel_bias, [0.05, -0.05, 0.15])


def test_arming_keeps_the_loops_and_disarming_starts_a_new_flight() -> None:
    hc = HostController(VEHICLE, 0.01)
    off = Setpoint(height=REST, armed=False)
    for _ in range(5):
        hc.step(sample(), off)
    on = Setpoint(roll=0.1, height=1.0, armed=True)
    pwms = [hc.step(sample(), on) for _ in range(3)]
    assert all(min(p) >= VEHICLE.idle_pwm for p in pwms)
    # the roll integral keeps learning from step to step (the loops reset once, at arming)
    gains = hc.gains.roll
    assert math.isinf(gains.integral_band) or gains.integral_band > 0.1
    assert hc.pids["roll"].integral == pytest.approx(3 * 0.1 * 0.01, rel=0.05)
    # disarmed again: a new flight, calibration from scratch
    assert hc.step(sample(baro=50.0), off) == MOTORS_OFF
    assert hc.pids["roll"].integral == 0.0 and hc.altitude.reference == pytest.approx(50.0 - REST)
    assert hc.last_pwm == MOTORS_OFF


def test_reset_forgets_the_flight() -> None:
    hc = HostController(VEHICLE, 0.01)
    fresh = HostController(VEHICLE, 0.01)
    for _ in range(3):
        hc.step(sample(), Setpoint(height=REST, armed=False))
    for _ in range(3):
        hc.step(sample(), Setpoint(roll=0.2, height=1.0, armed=True))
    hc.reset()
    for a, b in ((hc.estimate.quaternion, fresh.estimate.quaternion), (hc.accel_bias, fresh.accel_bias)):
        np.testing.assert_array_equal(a, b)
    assert hc.estimate.height == fresh.estimate.height and hc.last_pwm == MOTORS_OFF
    assert hc.height_loop.speed_command == 0.0 and hc.height_loop.integral == 0.0
    assert dataclasses.astuple(hc.gains) == dataclasses.astuple(fresh.gains)
    # calibrating again averages only the new samples
    hc.step(sample(baro=80.0), Setpoint(height=REST, armed=False))
    assert hc.altitude.reference == pytest.approx(80.0 - REST)
