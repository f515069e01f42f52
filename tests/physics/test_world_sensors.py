"""The stepping API, the wrench conversion, drag/wind and the sensor models against hand-derived values."""

import math

import numpy as np
import pytest

from robosoc.config.scenario import GustConfig, SensorConfig, WindConfig
from robosoc.config.vehicle import default_vehicle, laser_vehicle
from robosoc.physics import World
from robosoc.physics.sensors import SensorModel, pressure_hpa
from robosoc.physics.wind import gust_profile

QUIET = SensorConfig(noise=False)


def _rest(world: World, seconds: float = 0.6) -> None:
    world.reset(0)
    world.advance(seconds)


def test_accelerometer_reads_plus_g_on_z_at_rest_and_gyro_zero() -> None:
    world = World([default_vehicle()], QUIET)
    _rest(world)
    sample = world.quadrotors[0].sensors()
    assert sample.time == pytest.approx(0.6)
    np.testing.assert_allclose(sample.accel, [0.0, 0.0, 9.8], atol=1e-4)  # contacts settle to µm/s
    np.testing.assert_allclose(sample.gyro, [0.0, 0.0, 0.0], atol=1e-9)


def test_accelerometer_reads_zero_in_free_fall() -> None:
    world = World([default_vehicle(spawn_position=(0.0, 0.0, 3.0))], QUIET)
    world.reset(0)
    world.advance(0.05)
    # Only drag acts besides gravity: at 0.49 m/s it is 0.1·0.49² N upwards, 0.016 m/s² on 1.478 kg.
    accel = world.quadrotors[0].sensors().accel
    np.testing.assert_allclose(accel[:2], [0.0, 0.0], atol=1e-12)
    assert 0.0 < accel[2] < 0.1 * 0.49**2 / 1.478


def test_magnetometer_is_the_field_in_the_body_frame() -> None:
    # Yawed 90° left: body x points world y (West), so the North field lies along −y_body.
    vehicle = default_vehicle()
    vehicle = type(vehicle)(spawn_yaw_deg=90.0)
    world = World([vehicle], QUIET)
    _rest(world)
    np.testing.assert_allclose(world.quadrotors[0].sensors().mag, [0.0, -0.5, -0.866], atol=1e-9)


def test_magnetometer_and_accelerometer_match_rt_of_truth_when_tumbling() -> None:
    world = World([default_vehicle(spawn_position=(0.0, 0.0, 5.0))], QUIET)
    world.reset(0)
    world.data.qvel[3:6] = [1.0, -2.0, 0.5]  # tumble in free fall (no torque acts: rates stay)
    world.advance(0.2)
    quad = world.quadrotors[0]
    truth, sample = quad.truth(), quad.sensors()
    w, x, y, z = truth.quaternion
    rot = np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )
    np.testing.assert_allclose(sample.mag, rot.T @ [0.5, 0.0, -0.866], atol=1e-12)
    # Free body, no torque: the window-averaged rate is the body rate (to the drag's small effect).
    np.testing.assert_allclose(sample.gyro, truth.angular_velocity, atol=0.02)


def test_barometer_altitude_and_pressure() -> None:
    world = World([default_vehicle()], QUIET)
    _rest(world)
    sample = world.quadrotors[0].sensors()
    height = world.quadrotors[0].truth().position[2]
    assert sample.baro_altitude == height
    assert sample.baro_pressure == pytest.approx(1013.25 * (1 - height / 44330) ** 5.263157, rel=1e-12)
    assert pressure_hpa(0.0) == 1013.25
    # Hand-evaluated: 1013.25 · (1 − 1000/44330)^5.263157 = 898.594 hPa.
    assert pressure_hpa(1000.0) == pytest.approx(898.594, abs=0.001)


def test_sensor_rate_must_be_whole_physics_steps() -> None:
    with pytest.raises(ValueError, match="rate_hz"):
        SensorConfig(rate_hz=300.0)
    world = World([default_vehicle()], SensorConfig(rate_hz=250.0, noise=False))
    world.reset(0)
    world.advance(0.1)
    assert world.quadrotors[0].sensors().time == pytest.approx(0.1)
    world.advance(0.103)
    assert world.quadrotors[0].sensors().time == pytest.approx(0.1)  # next sample at 0.104
    world.advance(0.104)
    assert world.quadrotors[0].sensors().time == pytest.approx(0.104)


def _noise_stream(seed: int, samples: int, config: SensorConfig) -> np.ndarray:
    model = SensorModel(config, 0.001)
    rng = np.random.default_rng(np.random.SeedSequence(seed))
    model.reset(rng, (0.0, 0.0, 0.0), (1.0, 0.0, 0.0, 0.0))
    out = []
    for k in range(samples):
        s = model.sample(0.01 * (k + 1), 1.0, (1.0, 0.0, 0.0, 0.0), (0.0, 0.0, 0.0), 0.01)
        out.append(np.concatenate((s.accel, s.gyro, s.mag, [s.baro_altitude])))
    return np.array(out)


def test_white_noise_sigma_within_sampling_error() -> None:
    # Biases off: over 200 s a decaying 10 m baro bias would drift by half a metre.
    config = SensorConfig(accel_bias=0.0, gyro_bias=0.0, baro_bias=0.0)
    n = 20000
    data = _noise_stream(3, n, config)
    expected = np.array([0.35, 0.35, 0.3, 0.05, 0.05, 0.015, 0.013, 0.013, 0.013, 0.1])
    sigma = data.std(axis=0, ddof=1)
    # Standard error of a sample σ is σ/sqrt(2(n-1)); allow 4 of them.
    np.testing.assert_array_less(np.abs(sigma - expected), 4 * expected / math.sqrt(2 * (n - 1)))


def test_bias_spread_over_seeds_and_mean_within_sampling_error() -> None:
    config = SensorConfig(accel_sigma=(0, 0, 0), gyro_sigma=(0, 0, 0), mag_sigma=0.0, baro_sigma=0.0)
    seeds = 600
    biases = np.array([_noise_stream(s, 1, config)[0] for s in range(seeds)])
    biases -= np.array([0.0, 0.0, 9.8, 0, 0, 0, 0.5, 0.0, -0.866, 1.0])
    expected = np.array([0.1] * 6 + [0.0] * 3 + [10.0])
    sigma = biases.std(axis=0, ddof=1)
    np.testing.assert_array_less(np.abs(sigma - expected), 4 * expected / math.sqrt(2 * (seeds - 1)) + 1e-15)
    np.testing.assert_array_less(np.abs(biases.mean(axis=0)), 4 * expected / math.sqrt(seeds) + 1e-15)


def test_bias_decays_with_one_hour_time_constant() -> None:
    config = SensorConfig(accel_sigma=(0, 0, 0), gyro_sigma=(0, 0, 0), mag_sigma=0.0, baro_sigma=0.0)
    data = _noise_stream(5, 1001, config)
    first, last = data[0, 9] - 1.0, data[1000, 9] - 1.0
    assert last == pytest.approx(first * math.exp(-10.0 / 3600.0), rel=1e-9)


def test_noise_off_gives_exact_readings() -> None:
    data = _noise_stream(1, 5, QUIET)
    np.testing.assert_array_equal(data[:, :3], [[0.0, 0.0, 9.8]] * 5)


def test_same_seed_gives_bit_identical_streams_and_other_seeds_differ() -> None:
    wind = WindConfig(gust_sigma=1.0, gusts=(GustConfig(start_s=0.2, duration_s=0.5),))

    def stream(seed: int) -> np.ndarray:
        world = World([default_vehicle()], SensorConfig(), wind)
        world.reset(seed)
        quad = world.quadrotors[0]
        quad.apply_pwm([140, 130, 135, 120])
        rows = []
        for k in range(1, 101):
            world.advance(0.01 * k)
            rows.append(np.concatenate((quad.sensors().as_array(), quad.truth().position, world.wind.velocity)))
        return np.array(rows)

    a, b, c = stream(7), stream(7), stream(8)
    assert np.array_equal(a, b)
    assert not np.array_equal(a, c)


def test_drag_in_the_world_frame_points_along_the_wind() -> None:
    # Stationary vehicle rolled 90°: air flows along world +y.  With Rᵀ (correct) the body sees
    # the air along its z axis and the world-frame drag is +y with C_wz·|v|²; using R instead
    # would push it along −y.
    world = World([default_vehicle(spawn_position=(0.0, 0.0, 5.0))], QUIET, WindConfig(constant=(0.0, 5.0, 0.0)))
    world.reset(0)
    world.data.qpos[3:7] = [math.cos(math.pi / 4), math.sin(math.pi / 4), 0.0, 0.0]
    world.step()
    body = world.quadrotors[0].body_id
    np.testing.assert_allclose(world.data.xfrc_applied[body, :3], [0.0, 0.1 * 25.0, 0.0], atol=1e-12)
    np.testing.assert_allclose(world.data.xfrc_applied[body, 3:], 0.0, atol=1e-12)


def test_com_offset_turns_drag_into_a_torque_about_the_com() -> None:
    # Laser variant: CoM 15 mm below the origin.  Air along +x → 3 N drag at the origin along +x,
    # which about the CoM is τ = −c × F = (0, 0.045, 0) N·m.
    world = World([laser_vehicle(spawn_position=(0.0, 0.0, 5.0))], QUIET, WindConfig(constant=(5.0, 0.0, 0.0)))
    world.reset(0)
    world.step()
    body = world.quadrotors[0].body_id
    np.testing.assert_allclose(world.data.xfrc_applied[body], [3.0, 0.0, 0.0, 0.0, 0.045, 0.0], atol=1e-12)


def test_rotor_thrust_acts_along_body_z_in_world_frame() -> None:
    world = World([default_vehicle(spawn_position=(0.0, 0.0, 5.0))], QUIET)
    world.reset(0)
    world.data.qpos[3:7] = [math.cos(math.pi / 8), 0.0, math.sin(math.pi / 8), 0.0]  # pitch 45°
    quad = world.quadrotors[0]
    quad.propulsion.reset([485.0] * 4)
    world.step()
    force = world.data.xfrc_applied[quad.body_id, :3]
    total = sum(quad.propulsion.forces)
    np.testing.assert_allclose(force, [total * math.sqrt(0.5), 0.0, total * math.sqrt(0.5)], rtol=1e-12)


def test_gust_profile_half_cosine() -> None:
    gust = GustConfig(start_s=1.0, duration_s=2.0, rise_s=0.5, velocity=(4.0, 0.0, 0.0))
    assert gust_profile(gust, 0.9) == 0.0
    assert gust_profile(gust, 1.25) == pytest.approx(0.5)
    assert gust_profile(gust, 2.0) == 1.0
    assert gust_profile(gust, 2.75) == pytest.approx(0.5)
    assert gust_profile(gust, 3.1) == 0.0


def test_several_vehicles_share_a_world_independently() -> None:
    a = default_vehicle("a", spawn_position=(0.0, 0.0, 0.3))
    b = laser_vehicle("b", spawn_position=(3.0, 0.0, 0.3))
    world = World([a, b], QUIET)
    world.reset(0)
    world.quadrotor("a").apply_pwm([200] * 4)
    world.advance(1.0)
    za = world.quadrotor("a").truth().position[2]
    zb = world.quadrotor("b").truth().position[2]
    assert za > 0.5  # climbing at full-ish thrust
    assert zb == pytest.approx(b.rest_height, abs=0.01)  # still on its skids
    assert world.quadrotor("b").truth().position[0] == pytest.approx(3.0, abs=1e-6)
    with pytest.raises(ValueError, match="name"):
        World([a, default_vehicle("a")])
    with pytest.raises(KeyError):
        world.quadrotor("c")


def test_model_mass_inertia_and_com_come_from_the_config() -> None:
    world = World([laser_vehicle()], QUIET)
    body = world.model.body("quad/body")
    assert body.mass[0] == pytest.approx(1.748)
    np.testing.assert_allclose(body.inertia, [0.013931, 0.013957, 0.021988])
    np.testing.assert_allclose(body.ipos, [0.0, 0.0, -0.015])
    assert world.model.opt.timestep == 0.001
    np.testing.assert_allclose(world.model.opt.gravity, [0.0, 0.0, -9.8])


def test_hover_pwm_holds_height_in_the_air() -> None:
    # At pwm 121 (99.6 % of the weight) from hover speed the vehicle sinks slowly: the
    # acceleration equals the thrust deficit, a physics check of the whole wrench path.
    from robosoc.physics.propulsion import steady_state

    vehicle = default_vehicle(spawn_position=(0.0, 0.0, 3.0))
    world = World([vehicle], QUIET)
    world.reset(0)
    quad = world.quadrotors[0]
    omega, force, _ = steady_state(vehicle.motor, 121)
    quad.propulsion.reset([omega] * 4)
    quad.apply_pwm([121] * 4)
    world.advance(1.0)
    expected_accel = 4 * force / vehicle.mass - 9.8
    z = quad.truth().position[2]
    assert z - 3.0 == pytest.approx(0.5 * expected_accel, abs=0.002)
