"""Two states the other physics tests never looked at: the skids' geometry as MuJoCo compiles it,
and a sensor model read before its first reset (issue 15's physics survivors)."""

from __future__ import annotations

import dataclasses
import math

import mujoco
import numpy as np
import pytest

from robosoc.config.scenario import SensorConfig
from robosoc.config.vehicle import default_vehicle
from robosoc.physics.mjcf import GRAVITY, world_xml
from robosoc.physics.sensors import MAGNETIC_FIELD_WORLD, SensorModel

LEVEL = (1.0, 0.0, 0.0, 0.0)


@pytest.mark.parametrize(("bottom", "radius"), [(-0.1825, 0.005), (-0.2, 0.03)])
def test_the_skids_lowest_point_is_skid_bottom_z(bottom: float, radius: float) -> None:
    """Each skid is a capsule of radius r along x: its lowest point is r below its axis, at skid_bottom_z
    in the body frame, whatever the radius (MuJoCo compiles the model; the test reads its geoms)."""
    vehicle = dataclasses.replace(default_vehicle(), skid_bottom_z=bottom, skid_radius=radius)
    model = mujoco.MjModel.from_xml_string(world_xml([vehicle]))
    skids = [
        i
        for i in range(model.ngeom)
        if (mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_GEOM, i) or "").split("/")[-1].startswith("skid_")
    ]
    assert len(skids) == 2
    for i in skids:
        assert model.geom_type[i] == mujoco.mjtGeom.mjGEOM_CAPSULE
        assert model.geom_size[i][0] == pytest.approx(radius)
        assert model.geom_pos[i][2] - model.geom_size[i][0] == pytest.approx(bottom, abs=1e-12)
        assert model.geom_size[i][1] == pytest.approx(vehicle.skid_half_length)  # the half length along x
    offsets = sorted(model.geom_pos[i][1] for i in skids)
    assert offsets == pytest.approx([-vehicle.skid_offset_y, vehicle.skid_offset_y])


def _truth_reading(quaternion: tuple[float, float, float, float]) -> np.ndarray:
    """At rest: the accelerometer reads +g up and the magnetometer the field, both in the body frame."""
    w, x, y, z = quaternion
    rot = np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )
    return np.concatenate((rot.T @ [0.0, 0.0, GRAVITY], [0.0, 0.0, 0.0], rot.T @ MAGNETIC_FIELD_WORLD))


def test_a_model_never_reset_starts_its_window_level_at_rest_without_bias() -> None:
    """Before its first reset a model reads a level body at rest as at rest (its first window starts
    level, still), with no bias; white noise still comes, from a fixed seed (the same for every model)."""
    quiet = SensorModel(SensorConfig(noise=False), 0.001)
    sample = quiet.sample(0.01, 1.5, LEVEL, (0.0, 0.0, 0.0), 0.01)
    got = np.concatenate((sample.accel, sample.gyro, sample.mag))
    np.testing.assert_allclose(got, _truth_reading(LEVEL), atol=1e-12)
    assert sample.baro_altitude == 1.5
    # white noise switched off by zero sigmas, biases left at their (large) defaults: a model never reset
    # has drawn no bias yet, so it reads the truth exactly
    biased = SensorConfig(accel_sigma=(0.0, 0.0, 0.0), gyro_sigma=(0.0, 0.0, 0.0), mag_sigma=0.0, baro_sigma=0.0,
                          mag_bias=0.3)  # fmt: skip
    fresh = SensorModel(biased, 0.001)
    sample = fresh.sample(0.01, 1.5, LEVEL, (0.0, 0.0, 0.0), 0.01)
    np.testing.assert_allclose(
        np.concatenate((sample.accel, sample.gyro, sample.mag)), _truth_reading(LEVEL), atol=1e-12
    )
    assert sample.baro_altitude == 1.5
    # after a reset the same configuration reads its drawn biases
    fresh.reset(np.random.default_rng(3), (0.0, 0.0, 0.0), LEVEL)
    later = fresh.sample(0.02, 1.5, LEVEL, (0.0, 0.0, 0.0), 0.01)
    assert abs(later.baro_altitude - 1.5) > 1e-6
    # the same fixed seed for every model never reset: two of them read the same noise
    a, b = (SensorModel(SensorConfig(), 0.001) for _ in range(2))
    for k in range(3):
        sa = a.sample(0.01 * (k + 1), 1.0, LEVEL, (0.0, 0.0, 0.0), 0.01)
        sb = b.sample(0.01 * (k + 1), 1.0, LEVEL, (0.0, 0.0, 0.0), 0.01)
        np.testing.assert_array_equal(sa.accel, sb.accel)
        assert sa.baro_altitude == sb.baro_altitude != 1.0


def test_a_model_never_reset_measures_its_first_window_from_rest() -> None:
    """The first window of a model never reset starts level and still: a body now moving at v after the
    window T reads the acceleration v/T, and a body now yawed by a reads the rate a/T about z."""
    model = SensorModel(SensorConfig(noise=False), 0.001)
    sample = model.sample(0.01, 1.0, LEVEL, (0.1, -0.2, 0.05), 0.01)
    np.testing.assert_allclose(sample.accel, [10.0, -20.0, 5.0 + GRAVITY], atol=1e-9)
    yaw = 0.02
    turned = SensorModel(SensorConfig(noise=False), 0.001)
    sample = turned.sample(0.01, 1.0, (math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2)), (0.0, 0.0, 0.0), 0.01)
    np.testing.assert_allclose(sample.gyro, [0.0, 0.0, yaw / 0.01], atol=1e-9)
