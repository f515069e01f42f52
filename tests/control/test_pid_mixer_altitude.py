"""PID (equations 1–2), mixer (equation 3) and altitude filter against hand-checked values."""

import math

import numpy as np
import pytest

from robosoc.config.vehicle import MotorConfig
from robosoc.control.altitude import AltitudeFilter
from robosoc.control.mixer import Mixer, thrust_to_voltage, yaw_coefficient
from robosoc.control.pid import Pid, PidGains, euler_rates, height_thrust, wrap_angle
from robosoc.physics.propulsion import steady_state

MOTOR = MotorConfig()


def test_pid_hand_checked() -> None:
    pid = Pid(PidGains(kp=2.0, ki=0.5, kd=0.1, integral_limit=10.0, output_limit=10.0))
    # I = 1·0.01; u = 2·1 + 0.5·0.01 + 0.1·(−0.2) = 1.985
    assert pid.step(1.0, -0.2, 0.01) == pytest.approx(1.985, abs=1e-15)
    # I = 0.01 + 0.5·0.01 = 0.015; u = 1 + 0.0075 + 0 = 1.0075
    assert pid.step(0.5, 0.0, 0.01) == pytest.approx(1.0075, abs=1e-15)


def test_pid_clamps_integral_and_output() -> None:
    pid = Pid(PidGains(kp=1.0, ki=1.0, kd=0.0, integral_limit=0.05, output_limit=1.5))
    for _ in range(100):
        out = pid.step(1.0, 0.0, 0.01)
    assert pid.integral == 0.05
    assert out == 1.05
    assert pid.step(10.0, 0.0, 0.01) == 1.5
    assert pid.step(-10.0, 0.0, 0.01) == -1.5


def test_height_thrust_equation_2() -> None:
    gains = PidGains(kp=10.0, ki=0.0, kd=5.0, integral_limit=1.0, output_limit=20.0)
    # Level: u_z = 10·0.1 + 5·(−0.2) + 14.4844 = 14.4844
    assert height_thrust(Pid(gains), 0.1, -0.2, 0.01, 14.4844, 0.0, 0.0, 1.5) == pytest.approx(14.4844)
    # Rolled 20°, pitched 10°: divided by cos α·cos β.
    expected = 14.4844 / (math.cos(math.radians(20)) * math.cos(math.radians(10)))
    value = height_thrust(Pid(gains), 0.0, 0.0, 0.01, 14.4844, math.radians(20), math.radians(10), 1.5)
    assert value == pytest.approx(expected, rel=1e-12)
    # At 60° roll 1/cos = 2 is limited to 1.5.
    assert height_thrust(Pid(gains), 0.0, 0.0, 0.01, 10.0, math.radians(60), 0.0, 1.5) == pytest.approx(15.0)


def test_euler_rates_and_wrap() -> None:
    assert euler_rates(0.0, 0.0, (0.1, 0.2, 0.3)) == pytest.approx((0.1, 0.2, 0.3))
    # Rolled 90°: a body pitch rate q turns the heading (θ̇ = q·sin α / cos β), β̇ = q·cos α = 0.
    rates = euler_rates(math.pi / 2, 0.0, (0.0, 0.5, 0.0))
    assert rates == pytest.approx((0.0, 0.0, 0.5), abs=1e-12)
    assert wrap_angle(math.radians(350)) == pytest.approx(math.radians(-10))
    assert wrap_angle(-math.pi) == pytest.approx(-math.pi)


def test_thrust_to_voltage_inverts_the_physics_motor_model() -> None:
    for pwm in (30.0, 80.0, 121.2, 200.0, 250.0):
        _, force, _ = steady_state(MOTOR, pwm)
        volts = thrust_to_voltage(MOTOR, force)
        assert volts * 255 / 14.8 == pytest.approx(pwm, rel=1e-6)
    assert thrust_to_voltage(MOTOR, 0.0) == 0.0
    assert thrust_to_voltage(MOTOR, 1.0) == 0.0  # below the idle thrust no voltage is needed


def test_mixer_hover_and_equation_3() -> None:
    hover = 1.478 * 9.8
    mixer = Mixer(MOTOR, 0.275, hover / 4)
    np.testing.assert_array_equal(mixer.pwm(hover, 0.0, 0.0, 0.0), [121, 121, 121, 121])
    f = mixer.forces(hover, 0.2, -0.1, 0.05)
    assert (f[3] - f[1]) * 0.275 == pytest.approx(0.2)
    assert (f[2] - f[0]) * 0.275 == pytest.approx(-0.1)
    assert mixer.yaw_k * (f[0] + f[2] - f[1] - f[3]) == pytest.approx(0.05)
    assert f.sum() == pytest.approx(hover)
    # k = k_t + k_m/(2·CT0s·ω_h), ω_h = sqrt(F_h/CT0s)
    omega_h = math.sqrt(hover / 4 / MOTOR.ct0s)
    assert yaw_coefficient(MOTOR, hover / 4) == pytest.approx(MOTOR.k_t + MOTOR.k_m / (2 * MOTOR.ct0s * omega_h))


def test_mixer_saturates_to_bytes() -> None:
    mixer = Mixer(MOTOR, 0.275, 3.62)
    np.testing.assert_array_equal(mixer.pwm(1000.0, 0.0, 0.0, 0.0), [255] * 4)
    np.testing.assert_array_equal(mixer.pwm(-5.0, 0.0, 0.0, 0.0), [0] * 4)
    out = mixer.pwm(14.5, 5.0, 0.0, 0.0)  # huge roll torque: left motor full, right motor off
    assert out[3] == 255 and out[1] == 0 and out.dtype == np.uint8


def test_altitude_filter_hand_checked_and_tracks_a_climb() -> None:
    alt = AltitudeFilter()
    alt.reset(baro_ground=12.0, rest_height=0.2)
    assert alt.reference == pytest.approx(11.8)
    level = np.eye(3)
    # Consistent data (at rest, baro = ground reading): nothing moves.
    assert alt.step(level, np.array([0.0, 0.0, 9.8]), 12.0, 0.01) == pytest.approx(0.2, abs=1e-12)
    # Constant 1 m/s² climb, noise-free: h = 0.2 + ½·t².
    for k in range(1, 301):
        t = 0.01 * k
        alt.step(level, np.array([0.0, 0.0, 10.8]), 11.8 + 0.2 + 0.5 * t * t, 0.01)
    assert alt.height == pytest.approx(0.2 + 0.5 * 9.0, abs=0.01)
    assert alt.velocity == pytest.approx(3.0, abs=0.02)
