"""The gyroscope at non-trivial attitudes, and the independence of the seeded noise streams.

Gyro: the expected body rate is computed here from the truth quaternions with a Hamilton product
written in this file, ω_body = 2·vec(q⁻¹ ⊗ q̇) (body frame: the inverse on the left).  At the identity
attitude the world-frame rate 2·vec(q̇ ⊗ q⁻¹) is the same vector, so every case starts tilted.

Noise: world.py spawns one stream of ``SeedSequence(seed)`` for the wind and one per vehicle; the
white-noise draws of each vehicle and the wind's driving noise are recovered exactly from two runs
(noise on and off, same seed) and compared.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from robosoc.config.scenario import SensorConfig, WindConfig
from robosoc.config.vehicle import VehicleConfig, default_vehicle
from robosoc.physics import World
from robosoc.physics.sensors import SensorModel

Quat = tuple[float, float, float, float]


def _quat(values: np.ndarray) -> Quat:
    w, x, y, z = (float(v) for v in values)
    return (w, x, y, z)


def qmul(a: Quat, b: Quat) -> Quat:
    """Hamilton product a ⊗ b of (w, x, y, z) quaternions."""
    aw, ax, ay, az = a
    bw, bx, by, bz = b
    return (
        aw * bw - ax * bx - ay * by - az * bz,
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
    )


def qconj(q: Quat) -> Quat:
    return (q[0], -q[1], -q[2], -q[3])


def qexp(rotation: np.ndarray) -> Quat:
    """Unit quaternion of the rotation vector ``rotation`` (angle × axis)."""
    angle = float(np.linalg.norm(rotation))
    if angle == 0.0:
        return (1.0, 0.0, 0.0, 0.0)
    s = math.sin(angle / 2) / angle
    return (math.cos(angle / 2), *(float(v) * s for v in rotation))


def from_euler(roll: float, pitch: float, yaw: float) -> Quat:
    """Body→world quaternion of Z-Y-X Euler angles (yaw, then pitch, then roll, about body axes)."""
    return qmul(qmul(qexp(np.array([0, 0, yaw])), qexp(np.array([0, pitch, 0]))), qexp(np.array([roll, 0, 0])))


def _qdot(q0: Quat, q1: Quat, dt: float) -> Quat:
    w, x, y, z = ((b - a) / dt for a, b in zip(q0, q1, strict=True))
    return (w, x, y, z)


def body_rate(q0: Quat, q1: Quat, dt: float) -> np.ndarray:
    """2·vec(q⁻¹ ⊗ q̇) with q̇ = (q1 − q0)/dt taken at q0: the body rate over one short step."""
    return 2.0 * np.array(qmul(qconj(q0), _qdot(q0, q1, dt))[1:])


def world_rate(q0: Quat, q1: Quat, dt: float) -> np.ndarray:
    """2·vec(q̇ ⊗ q⁻¹): the same rotation expressed in the world frame (the wrong order for a gyro)."""
    return 2.0 * np.array(qmul(_qdot(q0, q1, dt), qconj(q0))[1:])


ATTITUDES = [  # roll, pitch, yaw in degrees: none of them the identity
    (40.0, 0.0, 0.0),
    (0.0, -35.0, 0.0),
    (0.0, 0.0, 120.0),
    (30.0, 20.0, -60.0),
    (-70.0, 45.0, 170.0),
    (180.0, 0.0, 0.0),
]
RATE = np.array([0.7, -1.3, 2.1])  # body frame [rad/s]


@pytest.mark.parametrize("attitude", ATTITUDES)
def test_gyro_reads_the_body_rate_at_tilted_attitudes(attitude: tuple[float, float, float]) -> None:
    """A constant body rate ω from attitude q0: q(t) = q0 ⊗ exp(ωt/2); the gyro must read ω."""
    q0 = from_euler(*(math.radians(a) for a in attitude))
    model = SensorModel(SensorConfig(noise=False), 0.001)
    model.reset(np.random.default_rng(0), (0.0, 0.0, 0.0), q0)
    period = model.period
    q1 = qmul(q0, qexp(RATE * period))
    # the expectation from the derivative of the truth path, over 1000 sub-steps of the window
    steps = 1000
    path = [qmul(q0, qexp(RATE * period * k / steps)) for k in range(steps + 1)]
    expected = np.mean([body_rate(path[k], path[k + 1], period / steps) for k in range(steps)], axis=0)
    np.testing.assert_allclose(expected, RATE, atol=1e-3)  # the derivative formula itself
    sample = model.sample(period, 1.0, q1, (0.0, 0.0, 0.0), period)
    np.testing.assert_allclose(sample.gyro, expected, atol=1e-3)
    np.testing.assert_allclose(sample.gyro, RATE, atol=1e-9)
    # the world-frame rate (the product in the other order) is far off at these attitudes
    assert np.linalg.norm(world_rate(q0, q1, period) - RATE) > 0.5


@pytest.mark.parametrize("attitude", ATTITUDES[3:])
def test_gyro_follows_truth_of_a_tumbling_vehicle_at_tilted_attitudes(attitude: tuple[float, float, float]) -> None:
    """MuJoCo free flight from a tilted attitude: every gyro sample against the mean of the body rate
    differentiated from the truth quaternions of the window's physics steps."""
    world = World([default_vehicle(spawn_position=(0.0, 0.0, 50.0))], SensorConfig(noise=False))
    world.reset(0)
    quad = world.quadrotors[0]
    world.data.qpos[3:7] = from_euler(*(math.radians(a) for a in attitude))
    world.data.qvel[3:6] = [1.5, -2.0, 3.0]
    steps = world.sensor_steps
    world.advance(world.sensor_period)  # the first window started at the reset attitude: skip it
    for _ in range(20):
        quats: list[Quat] = [_quat(quad.truth().quaternion)]
        omega = []
        for _ in range(steps):
            world.step()
            quats.append(_quat(quad.truth().quaternion))
            omega.append(quad.truth().angular_velocity)
        expected = np.mean([body_rate(quats[k], quats[k + 1], world.dt) for k in range(steps)], axis=0)
        np.testing.assert_allclose(quad.sensors().gyro, expected, atol=2e-3)
        # MuJoCo's own body-frame velocity agrees (it integrates q ← q ⊗ exp(ω·dt/2) with the new ω)
        np.testing.assert_allclose(np.mean(omega, axis=0), expected, atol=2e-3)
        wrong = np.mean([world_rate(quats[k], quats[k + 1], world.dt) for k in range(steps)], axis=0)
        assert np.linalg.norm(wrong - expected) > 0.5  # the other product order would be noticed


# --- noise streams -----------------------------------------------------------------------------

SIGMA = np.array([0.35, 0.35, 0.3, 0.05, 0.05, 0.015, 0.013, 0.013, 0.013, 0.1])
NO_BIAS = SensorConfig(accel_bias=0.0, gyro_bias=0.0, baro_bias=0.0)
GUSTS = WindConfig(gust_sigma=1.5, gust_tau_s=0.5)
SECONDS = 2.0


def _vehicles(n: int) -> list[VehicleConfig]:
    return [default_vehicle(f"q{k}", spawn_position=(4.0 * k, 0.0, 0.3)) for k in range(n)]


def _readings(world: World, seconds: float) -> tuple[list[np.ndarray], np.ndarray]:
    """Per vehicle the 10 sensor axes of every sample; the wind after every update."""
    world.reset(7)
    per_vehicle: list[list[np.ndarray]] = [[] for _ in world.quadrotors]
    wind = [world.wind.velocity]
    for _ in range(round(seconds / world.sensor_period)):
        world.advance(world.time + world.sensor_period)
        wind.append(world.wind.velocity)
        for k, quad in enumerate(world.quadrotors):
            s = quad.sensors()
            per_vehicle[k].append(np.concatenate((s.accel, s.gyro, s.mag, [s.baro_altitude])))
    return [np.array(v) for v in per_vehicle], np.array(wind)


def vehicle_draws(n_vehicles: int, wind: WindConfig, seconds: float = SECONDS) -> list[np.ndarray]:
    """Each vehicle's white-noise draws in stream order: (noisy − noise-free reading) / σ."""
    noisy, _ = _readings(World(_vehicles(n_vehicles), NO_BIAS, wind), seconds)
    quiet, _ = _readings(World(_vehicles(n_vehicles), SensorConfig(noise=False), wind), seconds)
    return [((a - b) / SIGMA).ravel() for a, b in zip(noisy, quiet, strict=True)]


def wind_draws(wind: WindConfig, seconds: float = SECONDS) -> np.ndarray:
    """The wind's normal draws in stream order: g0 = σ·n, then g ← φ·g + σ·sqrt(1 − φ²)·n per update."""
    _, velocity = _readings(World(_vehicles(1), SensorConfig(noise=False), wind), seconds)
    phi = math.exp(-wind.update_s / wind.gust_tau_s)
    drive = wind.gust_sigma * math.sqrt(1 - phi * phi)
    first = velocity[0] / wind.gust_sigma
    return np.concatenate((first, ((velocity[1:] - phi * velocity[:-1]) / drive).ravel()))


def _corr(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.corrcoef(a, b)[0, 1])


@pytest.fixture(scope="module")
def streams() -> tuple[list[np.ndarray], np.ndarray]:
    return vehicle_draws(2, GUSTS), wind_draws(GUSTS)


def test_recovered_draws_are_standard_normal(streams: tuple[list[np.ndarray], np.ndarray]) -> None:
    vehicles, wind = streams
    for draws in [*vehicles, wind]:
        n = draws.size
        assert abs(draws.mean()) < 4 / math.sqrt(n) and abs(draws.std() - 1) < 4 / math.sqrt(2 * n)


def test_two_vehicles_draw_from_different_uncorrelated_streams(
    streams: tuple[list[np.ndarray], np.ndarray],
) -> None:
    (v0, v1), _ = streams
    assert not np.allclose(v0, v1)
    bound = 4.5 / math.sqrt(v0.size)
    for lag in range(0, 31):  # also shifted: one stream must not be the other one offset
        assert abs(_corr(v0[lag:], v1[: v1.size - lag])) < bound, lag
        assert abs(_corr(v1[lag:], v0[: v0.size - lag])) < bound, lag


def test_vehicle_noise_is_uncorrelated_with_the_wind(streams: tuple[list[np.ndarray], np.ndarray]) -> None:
    vehicles, wind = streams
    # draw i here is index 20 + i of a vehicle's generator (10 bias draws and the reset sample's 10
    # come first) and index i of the wind's
    for draws in vehicles:
        aligned = np.concatenate((np.full(20, np.nan), draws))[: wind.size]
        for lag in range(0, 31):
            a, b = aligned[lag:], wind[: wind.size - lag]
            ok = ~np.isnan(a)
            assert abs(_corr(a[ok], b[ok])) < 4.5 / math.sqrt(ok.sum()), lag
            a, b = wind[lag:], aligned[: aligned.size - lag]
            ok = ~np.isnan(b)
            assert abs(_corr(a[ok], b[ok])) < 4.5 / math.sqrt(ok.sum()), lag


def test_each_stream_depends_only_on_the_seed_and_its_own_position() -> None:
    """Adding a vehicle or turning the gusts off changes no other stream (world.py: one spawned stream
    each), and each vehicle's stream is the documented one: child k + 1 of SeedSequence(seed)."""
    alone = vehicle_draws(1, WindConfig(), seconds=0.5)[0]
    pair = vehicle_draws(2, GUSTS, seconds=0.5)
    np.testing.assert_allclose(pair[0], alone, atol=1e-9)
    for k, draws in enumerate(pair):
        child = np.random.SeedSequence(7).spawn(3)[k + 1]
        reference = np.random.default_rng(child).standard_normal(20 + draws.size)[20:]
        np.testing.assert_allclose(draws, reference, atol=1e-9)
    np.testing.assert_allclose(
        wind_draws(GUSTS, seconds=0.5),
        np.random.default_rng(np.random.SeedSequence(7).spawn(2)[0]).standard_normal(3 + 3 * 50),
        atol=1e-9,
    )
