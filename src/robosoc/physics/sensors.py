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

The position fix (``[sensors.position]``, off by default; :class:`PositionFixModel`) is a
motion-capture-like reading of the body origin's world-frame position and velocity,
``p + N(0, σ_p)`` and ``v + N(0, σ_v)`` per axis, white and unbiased, taken with every n-th sensor
sample (n = sensor rate / fix rate; the first at t = 0) and carried by every sample until the next
(with its own time and number, so a reader can tell a new fix from an old one).  Its draws (6
normals per fix: position x, y, z, then velocity x, y, z) come from a generator of its own per
vehicle, so turning it on leaves every other reading of a flight unchanged.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np

from robosoc.config.scenario import SensorConfig
from robosoc.physics.frames import euler_from_quat, quat_to_matrix
from robosoc.physics.mjcf import GRAVITY

MAGNETIC_FIELD_WORLD = (0.5, 0.0, -0.866)
"""Earth field in the world frame (unit magnitude, inclination 60° down, declination 0)."""

SEA_LEVEL_HPA = 1013.25
"""Pressure at altitude 0 [hPa] (QNH of the barometer model)."""


def pressure_hpa(altitude: float) -> float:
    """International barometric formula [hPa] at ``altitude`` [m]."""
    return SEA_LEVEL_HPA * (1.0 - altitude / 44330.0) ** 5.263157


@dataclass(frozen=True, slots=True)
class PositionFix:
    """One position fix: taken at ``time`` [s], the ``number``-th of the flight (from 0); world-frame
    ``position`` [m] and ``velocity`` [m/s] of the body origin, noise included."""

    time: float
    number: int
    position: tuple[float, float, float]
    velocity: tuple[float, float, float]


@dataclass(frozen=True, slots=True)
class SensorSample:
    """One reading of every sensor of a vehicle, taken at ``time`` [s].

    ``accel`` [m/s²] and ``gyro`` [rad/s] and ``mag`` [unit field] are body-frame (FLU) vectors;
    ``baro_altitude`` [m] and ``baro_pressure`` [hPa] come from the barometer; ``position_fix``
    is the newest position fix (None while the position sensor is off).
    """

    time: float
    accel: np.ndarray
    gyro: np.ndarray
    mag: np.ndarray
    baro_altitude: float
    baro_pressure: float
    position_fix: PositionFix | None = None

    def as_array(self) -> np.ndarray:
        """The sample as 12 floats: time, accel, gyro, mag, baro altitude, baro pressure."""
        return np.concatenate(([self.time], self.accel, self.gyro, self.mag, [self.baro_altitude, self.baro_pressure]))


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
    """Noise, bias and window state of one vehicle's sensors.

    Works on Python floats: a sample costs a few microseconds instead of tens with small numpy
    arrays, and it is taken every sensor period of every flight.
    """

    def __init__(self, config: SensorConfig, dt: float) -> None:
        self.config = config
        self.period = config.period_steps * dt
        self._phi = math.exp(-self.period / config.bias_tau_s)
        self._bias_sigma = np.array(
            [config.accel_bias] * 3 + [config.gyro_bias] * 3 + [config.mag_bias] * 3 + [config.baro_bias]
        )
        self._white_sigma = [*config.accel_sigma, *config.gyro_sigma, *([config.mag_sigma] * 3), config.baro_sigma]
        self._rng = np.random.default_rng(0)
        self.bias = [0.0] * 10
        self._prev_velocity: tuple[float, ...] = (0.0, 0.0, 0.0)
        self._prev_quat: tuple[float, ...] = (1.0, 0.0, 0.0, 0.0)

    def reset(self, rng: np.random.Generator, velocity: Iterable[float], quaternion: Iterable[float]) -> None:
        """Draw the initial biases and start a window at the current state."""
        self._rng = rng
        if self.config.noise:
            self.bias = (self._bias_sigma * rng.standard_normal(10)).tolist()
        else:
            self.bias = [0.0] * 10
        self._prev_velocity = tuple(float(v) for v in velocity)
        self._prev_quat = tuple(float(q) for q in quaternion)

    def sample(
        self,
        time: float,
        height: float,
        quaternion: Sequence[float],
        velocity: Sequence[float],
        window: float,
    ) -> SensorSample:
        """Read every sensor at ``time`` and start the next window.

        Args:
            time: sample time [s].
            height: z of the body origin [m].
            quaternion: orientation now (w, x, y, z), body→world.
            velocity: world-frame velocity of the body origin now [m/s].
            window: length of the averaging window [s]; 0 means "at rest" (the sample taken at reset).
        """
        w, x, y, z = quaternion
        r00, r01, r02, r10, r11, r12, r20, r21, r22 = quat_to_matrix(w, x, y, z)
        vx, vy, vz = velocity
        if window > 0:
            pvx, pvy, pvz = self._prev_velocity
            fx = (vx - pvx) / window
            fy = (vy - pvy) / window
            fz = (vz - pvz) / window + GRAVITY
            # q_prev⁻¹ ⊗ q: the rotation over the window, in the body frame.
            pw, px, py, pz = self._prev_quat
            rw = pw * w + px * x + py * y + pz * z
            rx = pw * x - px * w - py * z + pz * y
            ry = pw * y + px * z - py * w - pz * x
            rz = pw * z - px * y + py * x - pz * w
            if rw < 0.0:
                rw, rx, ry, rz = -rw, -rx, -ry, -rz
            s = math.sqrt(rx * rx + ry * ry + rz * rz)
            scale = (2.0 * math.atan2(s, rw) / s if s > 1e-12 else 2.0) / window
            gx, gy, gz = rx * scale, ry * scale, rz * scale
        else:
            fx, fy, fz = 0.0, 0.0, GRAVITY
            gx = gy = gz = 0.0
        mx, my, mz = MAGNETIC_FIELD_WORLD
        reading = [
            r00 * fx + r10 * fy + r20 * fz,
            r01 * fx + r11 * fy + r21 * fz,
            r02 * fx + r12 * fy + r22 * fz,
            gx,
            gy,
            gz,
            r00 * mx + r10 * my + r20 * mz,
            r01 * mx + r11 * my + r21 * mz,
            r02 * mx + r12 * my + r22 * mz,
            height,
        ]
        if self.config.noise:
            draws = self._rng.standard_normal(10).tolist()
            bias = self.bias
            sigma = self._white_sigma
            reading = [reading[i] + bias[i] + sigma[i] * draws[i] for i in range(10)]
            phi = self._phi
            self.bias = [phi * b for b in bias]
        self._prev_velocity = (vx, vy, vz)
        self._prev_quat = (w, x, y, z)
        altitude = reading[9]
        return SensorSample(
            time=time,
            accel=np.array(reading[0:3]),
            gyro=np.array(reading[3:6]),
            mag=np.array(reading[6:9]),
            baro_altitude=altitude,
            baro_pressure=pressure_hpa(altitude),
        )


class PositionFixModel:
    """The position sensor of one vehicle (``[sensors.position]``): a fix with every
    ``every``-th sensor sample, from its own generator."""

    def __init__(self, config: SensorConfig) -> None:
        self.config = config.position
        self.noise = config.noise
        self.every = config.position_every
        self._rng = np.random.default_rng(0)
        self._samples = 0
        self.fix: PositionFix | None = None

    def reset(self, rng: np.random.Generator) -> None:
        """Start a flight: no fix yet, draws from ``rng``."""
        self._rng = rng
        self._samples = 0
        self.fix = None

    def sample(self, time: float, position: Sequence[float], velocity: Sequence[float]) -> PositionFix | None:
        """The newest fix after the sensor sample at ``time`` (a new one with every ``every``-th
        sample) from the true ``position`` [m] and ``velocity`` [m/s]."""
        if self._samples % self.every == 0:
            p = [float(v) for v in position]
            v = [float(u) for u in velocity]
            if self.noise:
                d = self._rng.standard_normal(6).tolist()
                sp, sv = self.config.position_sigma, self.config.velocity_sigma
                p = [p[i] + sp * d[i] for i in range(3)]
                v = [v[i] + sv * d[3 + i] for i in range(3)]
            number = 0 if self.fix is None else self.fix.number + 1
            self.fix = PositionFix(time, number, (p[0], p[1], p[2]), (v[0], v[1], v[2]))
        self._samples += 1
        return self.fix
