"""The position sensor (``[sensors.position]``): its noise against the documented model (white,
unbiased, σ per axis), its rate, its own random stream (turning it on changes no other reading),
and one seed fixing it bit for bit."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from robosoc.config.scenario import PositionSensorConfig, SensorConfig
from robosoc.config.vehicle import default_vehicle
from robosoc.physics import World
from robosoc.physics.sensors import PositionFixModel

ON = SensorConfig(position=PositionSensorConfig(enabled=True))


def test_the_fix_noise_is_white_unbiased_and_has_the_documented_sigma() -> None:
    config = SensorConfig(position=PositionSensorConfig(enabled=True, rate_hz=100.0, position_sigma=0.03,
                                                        velocity_sigma=0.07))  # fmt: skip
    model = PositionFixModel(config)
    model.reset(np.random.default_rng(11))
    n = 20_000
    truth_p, truth_v = (1.0, -2.0, 0.5), (0.3, 0.0, -0.1)
    errors = []
    for k in range(n):
        fix = model.sample(k * 0.01, truth_p, truth_v)
        assert fix is not None and fix.number == k and fix.time == k * 0.01
        errors.append([a - b for a, b in zip((*fix.position, *fix.velocity), (*truth_p, *truth_v), strict=True)])
    e = np.array(errors)
    sigma = np.array([0.03] * 3 + [0.07] * 3)
    # mean within 5 standard errors of 0, spread within 5 % of σ (the standard error of a sample
    # standard deviation of 20,000 normals is σ/sqrt(2n) = 0.5 % of σ)
    assert np.all(np.abs(e.mean(axis=0)) < 5 * sigma / math.sqrt(n))
    assert np.allclose(e.std(axis=0), sigma, rtol=0.05)
    # white: successive errors and the six axes uncorrelated
    lag1 = [np.corrcoef(e[:-1, i], e[1:, i])[0, 1] for i in range(6)]
    assert max(abs(c) for c in lag1) < 5 / math.sqrt(n)
    cross = np.corrcoef(e.T) - np.eye(6)
    assert np.abs(cross).max() < 5 / math.sqrt(n)
    # normal: about 4.55 % beyond 2σ
    beyond = np.mean(np.abs(e / sigma) > 2)
    assert beyond == pytest.approx(0.0455, abs=0.006)


def test_without_noise_the_fix_is_the_truth_and_it_comes_every_nth_sample() -> None:
    config = SensorConfig(noise=False, rate_hz=100.0, position=PositionSensorConfig(enabled=True, rate_hz=25.0))
    assert config.position_every == 4
    model = PositionFixModel(config)
    model.reset(np.random.default_rng(0))
    fixes = [model.sample(k * 0.01, (k, 2.0 * k, 0.5), (0.1 * k, 0.0, 0.0)) for k in range(9)]
    assert [f.number for f in fixes if f is not None] == [0, 0, 0, 0, 1, 1, 1, 1, 2]
    assert fixes[5] is not None and fixes[5].time == pytest.approx(0.04) and fixes[5].position == (4.0, 8.0, 0.5)
    assert fixes[8] is not None and fixes[8].velocity == pytest.approx((0.8, 0.0, 0.0))


def _readings(sensors: SensorConfig, seed: int, samples: int = 60) -> tuple[np.ndarray, list]:
    world = World([default_vehicle()], sensors)
    world.reset(seed)
    quad = world.quadrotors[0]
    imu, fixes = [], []
    for _ in range(samples):
        s = quad.sensors()
        imu.append(s.as_array())
        truth = quad.truth()
        fixes.append((s.position_fix, truth.position.copy(), truth.velocity.copy()))
        world.advance(world.time + world.sensor_period)
    return np.array(imu), fixes


def test_in_the_world_the_fix_has_its_own_stream_and_the_seed_fixes_it() -> None:
    imu_off, fixes_off = _readings(SensorConfig(), seed=5)
    imu_on, fixes_on = _readings(ON, seed=5)
    assert np.array_equal(imu_off, imu_on)  # every other reading unchanged, bit for bit
    assert all(fix is None for fix, _, _ in fixes_off)
    numbers = [fix.number for fix, _, _ in fixes_on]
    assert numbers == [k // 2 for k in range(60)]  # 50 Hz: with every second 100 Hz sample
    for fix, position, velocity in fixes_on[::2]:  # a fresh fix: truth at its time plus noise
        assert np.abs(np.array(fix.position) - position).max() < 5 * ON.position.position_sigma
        assert np.abs(np.array(fix.velocity) - velocity).max() < 5 * ON.position.velocity_sigma
    again = _readings(ON, seed=5)[1]
    assert [f.position for f, _, _ in again] == [f.position for f, _, _ in fixes_on]
    other = _readings(ON, seed=6)[1]
    assert [f.position for f, _, _ in other] != [f.position for f, _, _ in fixes_on]
    quiet = dataclasses.replace(ON, noise=False)
    for fix, position, velocity in _readings(quiet, seed=5)[1][::2]:
        assert fix.position == tuple(position) and fix.velocity == tuple(velocity)
