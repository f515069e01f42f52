"""Sensor models of the hector quadrotor (IMU, magnetometer, barometer) and ground truth records.

Every sample is taken at the end of a sensor period T (10 ms at 100 Hz) from the state at that
instant and the state one period earlier:

- accelerometer: specific force in the body frame, averaged over the window,
  ``Rᵀ(t)·((v(t) − v(t−T))/T + [0, 0, g])``: +9.8 on z at rest, 0 in free fall;
- gyroscope: body rate averaged over the window, the rotation vector of ``q(t−T)⁻¹ ⊗ q(t)``
  divided by T;
- magnetometer: ``Rᵀ(t)·[0.5, 0, −0.866]`` (unit field, 60° inclination, no declination);
- barometer: altitude ``h = z + bias + noise`` and pressure ``1013.25·(1 − h/44330)^5.263157`` hPa.

Each of the ten axes (3 accel, 3 gyro, 3 mag, 1 baro) adds ``bias + N(0, σ)``.  The bias is
drawn once at reset from ``N(0, σ_bias)`` and then decays with a one-hour time constant,
``b ← φ·b`` per sample with φ = exp(−T/τ) (quadrotor.md: "drawn once ... slowly decaying").  A
stationary Gauss–Markov bias with the same spread would instead wander by σ_bias·sqrt(2T/τ) per
sample, 0.24 m/√s for the barometer, which no altitude hold could follow.  All draws come from
one generator per vehicle, in a fixed order (10 normals per sample: accel, gyro, mag, baro), so
a seed fixes the stream bit for bit.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from robosoc.config.scenario import SensorConfig
from robosoc.physics.frames import euler_from_quat, quat_conjugate, quat_multiply, rotation_vector
from robosoc.physics.mjcf import GRAVITY

MAGNETIC_FIELD = np.array([0.5, 0.0, -0.866])
"""Earth field in the world frame (unit magnitude, inclination 60° down, declination 0)."""

SEA_LEVEL_HPA = 1013.25
"""Pressure at altitude 0 [hPa] (QNH of the barometer model)."""


def pressure_hpa(altitude: float) -> float:
    """International barometric formula [hPa] at ``altitude`` [m]."""
    return SEA_LEVEL_HPA * (1.0 - altitude / 44330.0) ** 5.263157


@dataclass(frozen=True, slots=True)
class SensorSample:
    """One reading of every sensor of a vehicle, taken at ``time`` [s].

    ``accel`` [m/s²] and ``gyro`` [rad/s] and ``mag`` [unit field] are body-frame (FLU) vectors;
    ``baro_altitude`` [m] and ``baro_pressure`` [hPa] come from the barometer.
    """

    time: float
    accel: np.ndarray
    gyro: np.ndarray
    mag: np.ndarray
    baro_altitude: float
    baro_pressure: float

    def as_array(self) -> np.ndarray:
        """The sample as 12 floats: time, accel, gyro, mag, baro altitude, baro pressure."""
        return np.concatenate(
            ([self.time], self.accel, self.gyro, self.mag, [self.baro_altitude, self.baro_pressure])
        )


@dataclass(frozen=True, slots=True)
class Truth:
    """Ground-truth pose and twist of a vehicle at ``time`` [s].

    ``position`` of the body origin [m] and ``velocity`` [m/s] in the world frame; ``quaternion``
    (w, x, y, z) body→world; ``angular_velocity`` [rad/s] in the body frame.
    """

    time: float
    position: np.ndarray
    quaternion: np.ndarray
    velocity: np.ndarray
    angular_velocity: np.ndarray

    @property
    def euler(self) -> np.ndarray:
        """Roll, pitch, yaw [rad] (Z-Y-X)."""
        return euler_from_quat(self.quaternion)


class SensorModel:
    """Noise, bias and window state of one vehicle's sensors."""

    def __init__(self, config: SensorConfig, dt: float) -> None:
        self.config = config
        self.period = config.period_steps * dt
        phi = math.exp(-self.period / config.bias_tau_s)
        self._phi = phi
        bias_sigma = np.array([config.accel_bias] * 3 + [config.gyro_bias] * 3 + [config.mag_bias] * 3 + [config.baro_bias])
        self._bias_sigma = bias_sigma
        self._white_sigma = np.array(
            [*config.accel_sigma, *config.gyro_sigma, *([config.mag_sigma] * 3), config.baro_sigma]
        )
        self._rng = np.random.default_rng(0)
        self.bias = np.zeros(10)
        self._prev_velocity = np.zeros(3)
        self._prev_quat = np.array([1.0, 0.0, 0.0, 0.0])

    def reset(self, rng: np.random.Generator, velocity: np.ndarray, quaternion: np.ndarray) -> None:
        """Draw the initial biases and start a window at the current state."""
        self._rng = rng
        if self.config.noise:
            self.bias = self._bias_sigma * rng.standard_normal(10)
        else:
            self.bias = np.zeros(10)
        self._prev_velocity = np.array(velocity, dtype=float)
        self._prev_quat = np.array(quaternion, dtype=float)

    def sample(
        self, time: float, position: np.ndarray, quaternion: np.ndarray, velocity: np.ndarray, window: float
    ) -> SensorSample:
        """Read every sensor at ``time`` and start the next window.

        Args:
            time: sample time [s].
            position, quaternion, velocity: the vehicle's state now (world frame, w-x-y-z).
            window: length of the averaging window [s]; 0 means "at rest" (the sample taken at reset).
        """
        w, x, y, z = quaternion
        rot = np.array(
            [
                [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
            ]
        )
        if window > 0:
            accel_world = (velocity - self._prev_velocity) / window
            rate = rotation_vector(quat_multiply(quat_conjugate(self._prev_quat), quaternion)) / window
        else:
            accel_world = np.zeros(3)
            rate = np.zeros(3)
        specific_force = rot.T @ (accel_world + np.array([0.0, 0.0, GRAVITY]))
        field = rot.T @ MAGNETIC_FIELD
        clean = np.concatenate((specific_force, rate, field, [float(position[2])]))
        if self.config.noise:
            reading = clean + self.bias + self._white_sigma * self._rng.standard_normal(10)
            self.bias = self._phi * self.bias
        else:
            reading = clean
        self._prev_velocity = np.array(velocity, dtype=float)
        self._prev_quat = np.array(quaternion, dtype=float)
        altitude = float(reading[9])
        return SensorSample(
            time=time,
            accel=reading[0:3],
            gyro=reading[3:6],
            mag=reading[6:9],
            baro_altitude=altitude,
            baro_pressure=pressure_hpa(altitude),
        )
