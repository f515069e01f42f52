"""Rotations against SciPy, the wrench of a step at a general state, truth records and gust edges.

SciPy's ``Rotation`` is the third-party reference for quaternions, matrices and Z-Y-X Euler angles
(its quaternions are scalar-last, MuJoCo's scalar-first).
"""

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from robosoc.config.scenario import GustConfig, SensorConfig, WindConfig
from robosoc.config.vehicle import default_vehicle, laser_vehicle
from robosoc.physics import World
from robosoc.physics.frames import euler_from_quat, quat_to_matrix
from robosoc.physics.propulsion import Propulsion
from robosoc.physics.sensors import SensorModel
from robosoc.physics.wind import gust_profile

QUIET = SensorConfig(noise=False)
# roll, pitch, yaw [rad]: every quaternion component non-zero, signs mixed, beyond ±90° in roll/yaw
ATTITUDES = [(0.3, -0.2, 0.9), (-1.1, 0.7, -2.5), (2.6, 1.2, 0.4), (-0.05, -1.4, 3.0), (0.0, 0.0, -1.7)]


def _wxyz(rotation: Rotation) -> np.ndarray:
    x, y, z, w = rotation.as_quat()
    return np.array([w, x, y, z])


def _zyx(roll: float, pitch: float, yaw: float) -> Rotation:
    return Rotation.from_euler("ZYX", [yaw, pitch, roll])  # R = Rz(yaw)·Ry(pitch)·Rx(roll)


@pytest.mark.parametrize("angles", ATTITUDES)
def test_matrix_and_euler_angles_match_scipy(angles: tuple[float, float, float]) -> None:
    rotation = _zyx(*angles)
    q = _wxyz(rotation)
    np.testing.assert_allclose(np.reshape(quat_to_matrix(*q), (3, 3)), rotation.as_matrix(), atol=1e-12)
    np.testing.assert_allclose(euler_from_quat(q), angles, atol=1e-12)
    np.testing.assert_allclose(euler_from_quat(-q), angles, atol=1e-12)  # q and −q: the same rotation


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_pitch_of_plus_minus_90_degrees_survives_rounding(sign: float) -> None:
    # (cos 45°, 0, ±sin 45°, 0): 2·(w·y) rounds to 1 + 2⁻⁵², outside asin's domain unless clamped.
    h = math.sqrt(0.5)
    q = np.array([h, 0.0, sign * h, 0.0])
    assert abs(2.0 * q[0] * q[2]) > 1.0
    assert euler_from_quat(q)[1] == sign * math.pi / 2


def test_wrench_of_a_step_at_a_general_state_is_thrust_plus_drag_rotated_to_the_world_at_the_com() -> None:
    vehicle = laser_vehicle(spawn_position=(0.0, 0.0, 5.0))  # CoM 15 mm below the origin
    wind = (2.0, 1.0, -0.5)
    world = World([vehicle], QUIET, WindConfig(constant=wind))
    world.reset(0)
    quad = world.quadrotors[0]
    rotation = _zyx(0.4, -0.3, 2.2)
    world.data.qpos[3:7] = _wxyz(rotation)
    world.data.qvel[:] = [1.5, -2.0, 0.7, 0.6, -0.8, 0.5]
    omega = [450.0, 470.0, 490.0, 510.0]
    quad.propulsion.reset(omega)
    quad.apply_pwm([120, 130, 140, 150])
    velocity, rates = world.data.qvel[:3].copy(), world.data.qvel[3:].copy()
    world.step()

    # Independently: body-frame quantities through SciPy's matrix R (body→world).
    r = rotation.as_matrix()
    reference = Propulsion(vehicle.motor, vehicle.arm_length, world.dt)
    reference.reset(omega)
    reference.set_pwm([120, 130, 140, 150])
    fz, tx, ty, tz = reference.step(float((r.T @ velocity)[2]), float(rates[0]), float(rates[1]))
    air = r.T @ (velocity - np.array(wind))
    drag = vehicle.drag
    force = -np.array([drag.c_wxy, drag.c_wxy, drag.c_wz]) * np.linalg.norm(air) * air + [0.0, 0.0, fz]
    torque = -np.array([drag.c_mxy, drag.c_mxy, drag.c_mz]) * np.linalg.norm(rates) * rates + [tx, ty, tz]
    torque_at_com = torque - np.cross(vehicle.com, force)
    expected = np.concatenate((r @ force, r @ torque_at_com))
    np.testing.assert_allclose(world.data.xfrc_applied[quad.body_id], expected, rtol=1e-9, atol=1e-12)


def test_truth_of_each_vehicle_is_its_own_slice_of_the_state() -> None:
    world = World([default_vehicle("a"), default_vehicle("b", spawn_position=(2.0, 0.0, 0.3))], QUIET)
    world.reset(0)
    world.advance(0.004)
    state = {
        "a": ([0.1, 0.2, 0.3], _wxyz(_zyx(0.1, 0.2, 0.3)), [1.0, 2.0, 3.0], [4.0, 5.0, 6.0]),
        "b": ([7.0, 8.0, 9.0], _wxyz(_zyx(-0.4, 0.5, -0.6)), [-1.0, -2.0, -3.0], [-4.0, -5.0, -6.0]),
    }
    for k, (position, quaternion, velocity, rates) in enumerate(state.values()):
        world.data.qpos[7 * k : 7 * k + 7] = [*position, *quaternion]
        world.data.qvel[6 * k : 6 * k + 6] = [*velocity, *rates]
    for name, (position, quaternion, velocity, rates) in state.items():
        truth = world.quadrotor(name).truth()
        assert truth.time == pytest.approx(0.004)
        np.testing.assert_array_equal(truth.position, position)
        np.testing.assert_array_equal(truth.quaternion, quaternion)
        np.testing.assert_array_equal(truth.velocity, velocity)
        np.testing.assert_array_equal(truth.angular_velocity, rates)
    with pytest.raises(KeyError, match=r"no vehicle named 'c' \(have: a, b\)"):
        world.quadrotor("c")


def test_reset_stops_the_commands_and_samples_at_time_zero() -> None:
    vehicle = default_vehicle()
    world = World([vehicle], QUIET)
    quad = world.quadrotors[0]
    assert quad.config is vehicle and quad.pwm == (0, 0, 0, 0)
    with pytest.raises(AssertionError, match="reset the world first"):
        quad.sensors()
    world.reset()
    assert world.seed == 0
    world.reset(5)
    assert world.seed == 5
    quad.apply_pwm([200, 201, 202, 203])
    world.advance(0.05)
    assert quad.pwm == (200, 201, 202, 203)
    world.reset(0)
    assert world.steps == 0 and world.time == 0.0
    assert quad.pwm == (0, 0, 0, 0)
    assert quad.propulsion.voltages == [0.0] * 4
    assert quad.sensors().time == 0.0


def test_gust_without_ramp_is_a_step_on_the_open_interval() -> None:
    gust = GustConfig(start_s=1.0, duration_s=2.0, rise_s=0.0)
    assert [gust_profile(gust, t) for t in (0.999, 1.0, 1.001, 2.0, 2.999, 3.0, 3.001)] == [0, 0, 1, 1, 1, 0, 0]


def test_gust_ramps_follow_the_half_cosine_off_its_midpoint() -> None:
    # At a quarter of the ramp: 0.5·(1 − cos(π/4)) = 0.1464…; three quarters: 0.8536…
    gust = GustConfig(start_s=1.0, duration_s=2.0, rise_s=0.4)
    low, high = 0.5 * (1 - math.sqrt(0.5)), 0.5 * (1 + math.sqrt(0.5))
    assert gust_profile(gust, 1.1) == pytest.approx(low, rel=1e-12)
    assert gust_profile(gust, 1.3) == pytest.approx(high, rel=1e-12)
    assert gust_profile(gust, 2.7) == pytest.approx(high, rel=1e-12)
    assert gust_profile(gust, 2.9) == pytest.approx(low, rel=1e-12)


def test_wind_is_constant_plus_ou_gusts_from_its_own_stream_plus_the_scheduled_gust() -> None:
    # docs: SeedSequence(seed).spawn(1 + vehicles)[0] drives the wind; the OU state starts at σ·n and
    # advances as g ← φ·g + σ·sqrt(1 − φ²)·n every update period, φ = exp(−Δt/τ).
    constant = np.array([1.0, -2.0, 0.5])
    sigma, tau, period = 0.8, 2.0, 0.02
    gust = GustConfig(start_s=0.2, duration_s=0.6, rise_s=0.1, velocity=(3.0, -1.0, 2.0))
    config = WindConfig(constant=tuple(constant), gust_sigma=sigma, gust_tau_s=tau, update_s=period, gusts=(gust,))
    world = World([default_vehicle()], QUIET, config)
    world.reset(11)
    rng = np.random.default_rng(np.random.SeedSequence(11).spawn(2)[0])
    g = sigma * rng.standard_normal(3)
    np.testing.assert_allclose(world.wind.velocity, constant + g, rtol=1e-12)
    phi = math.exp(-period / tau)
    for k in range(1, 51):
        world.advance(k * period - 0.001)  # held between updates
        assert world.wind.velocity == pytest.approx(
            tuple(constant + g + gust_profile(gust, (k - 1) * period) * np.array(gust.velocity)), rel=1e-12
        )
        world.advance(k * period)
        g = phi * g + sigma * math.sqrt(1.0 - phi * phi) * rng.standard_normal(3)
        expected = constant + g + gust_profile(gust, k * period) * np.array(gust.velocity)
        np.testing.assert_allclose(world.wind.velocity, expected, rtol=1e-12)


@pytest.mark.parametrize("flip", [1.0, -1.0])
def test_sensor_sample_of_a_moving_tilted_body_matches_scipy(flip: float) -> None:
    # accel = Rᵀ(t)·((v(t) − v(t−T))/T + g·z), gyro = rotation vector of R(t−T)ᵀ·R(t) over T,
    # mag = Rᵀ(t)·field; −q is the same attitude as q.
    model = SensorModel(QUIET, 0.001)
    before, after = _zyx(0.2, -0.1, 0.5), _zyx(0.26, -0.05, 0.43)
    v0, v1, window = np.array([0.5, -1.0, 0.2]), np.array([0.9, -0.7, -0.1]), 0.01
    model.reset(np.random.default_rng(0), v0, _wxyz(before))
    sample = model.sample(0.01, 2.0, flip * _wxyz(after), v1, window)
    r = after.as_matrix()
    np.testing.assert_allclose(sample.accel, r.T @ ((v1 - v0) / window + [0.0, 0.0, 9.8]), rtol=1e-9)
    np.testing.assert_allclose(sample.gyro, (before.inv() * after).as_rotvec() / window, rtol=1e-9)
    np.testing.assert_allclose(sample.mag, r.T @ [0.5, 0.0, -0.866], rtol=1e-12)
    assert sample.baro_altitude == 2.0
