"""The reference flight controller run on the host: calibration, EKF, altitude filter, PID, mixer.

Per sensor sample (the seed runs the whole chain once per sample):

1. **Calibration** while ``setpoint.armed`` is false (the vehicle rests on flat ground, motors
   off): average the gyroscope (its bias), the accelerometer (its bias: standing level, it
   should read [0, 0, g]), the magnetometer (with gravity, the initial attitude by TRIAD) and
   the barometer (its ground reference); a sample that shows motion
   (the vehicle is spawned 0.3 m up and drops onto its skids) restarts the averages.  At the first armed sample both
   filters restart from these averages, and the PID integrals are zeroed.
2. **Attitude EKF** (:mod:`robosoc.control.ekf`): predict with the gyroscope, update with the
   accelerometer and magnetometer.
3. **Altitude filter** (:mod:`robosoc.control.altitude`): predict with the accelerometer rotated
   by the EKF attitude, update with the barometer.
4. **PID** (:mod:`robosoc.control.pid`): roll, pitch, yaw torques (equation 1) and total thrust
   (equation 2 with the height profile's feed-forward and the commanded vertical-speed limit),
   derivatives from the bias-corrected gyroscope and the estimated vertical velocity.
5. **Mixer** (:mod:`robosoc.control.mixer`): equation 3 with desaturation, PWM counts in
   [idle_pwm, 255] (0 while disarmed).

Gains (see docs/physics.md for the tuning): roll/pitch are PD-dominant with K_p = 150·I_xx and
K_d = 25·I_xx (natural frequency 12.2 rad/s, damping 1.0; hector's own attitude loop has 100 and
20, 10 rad/s, which leaves longer step tails through the 66 ms motor lag); yaw K_p = 0.3,
K_d = 0.12 on I_zz = 0.0218 (about 3.7 rad/s: the yaw authority through rotor drag is small);
height K_p = 3·m·ω², K_i = m·ω³, K_d = 3·m·ω (a triple pole at ω = 2.5 rad/s), so the commanded
vertical speed is ω = 2.5 m/s per metre of height error.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from robosoc.config.scenario import (
    DEFAULT_CLIMB_RATE_MPS,
    DEFAULT_DESCENT_RATE_MPS,
    PHYSICS_DT_S,
    ScenarioConfig,
)
from robosoc.config.vehicle import VehicleConfig
from robosoc.control import quaternion as quat
from robosoc.control.altitude import GRAVITY, AltitudeFilter, AltitudeParams
from robosoc.control.ekf import AttitudeEkf, EkfParams
from robosoc.control.mixer import Mixer
from robosoc.control.pid import HeightController, Pid, PidGains, euler_rates, wrap_angle
from robosoc.control.setpoint import Setpoint

CALIBRATED_QUAT_SIGMA = 0.005
"""σ of each quaternion component after calibration (≈ 0.6° of attitude)."""
GYRO_NOISE = 0.05
"""White noise of one gyroscope sample [rad/s]: the calibrated bias is uncertain by this / √N."""
MOTION_ACCEL = 2.0
"""|‖a‖ − g| [m/s²] above which a calibration sample counts as motion (≈ 4σ of the noise)."""
MOTORS_OFF = (0, 0, 0, 0)
"""The command while disarmed."""


@dataclass(frozen=True)
class ControllerGains:
    """PID gains and limits of the four loops (torques in N·m, thrust in N)."""

    roll: PidGains
    pitch: PidGains
    yaw: PidGains
    height: PidGains
    max_tilt_gain: float = 1.5
    """Upper limit of 1/(cos α·cos β) in equation 2."""


def default_gains(vehicle: VehicleConfig) -> ControllerGains:
    """The tuned gains for ``vehicle`` (scaled by its mass and inertia)."""
    ixx, iyy, _ = vehicle.inertia
    m = vehicle.mass
    wn_z = 2.5
    return ControllerGains(
        roll=PidGains(kp=150.0 * ixx, ki=20.0 * ixx, kd=25.0 * ixx, integral_limit=0.2, output_limit=1.5),
        pitch=PidGains(kp=150.0 * iyy, ki=20.0 * iyy, kd=25.0 * iyy, integral_limit=0.2, output_limit=1.5),
        yaw=PidGains(kp=0.3, ki=0.05, kd=0.12, integral_limit=0.5, output_limit=0.3),
        height=PidGains(
            kp=3.0 * m * wn_z**2,
            ki=m * wn_z**3,
            kd=3.0 * m * wn_z,
            integral_limit=0.5,
            output_limit=10.0,
            integral_band=0.1,
        ),
    )


@dataclass(frozen=True, slots=True)
class Estimate:
    """The controller's state estimate: attitude quaternion, Euler angles [rad], height [m], vertical velocity [m/s]."""

    quaternion: np.ndarray
    euler: np.ndarray
    height: float
    vertical_velocity: float


class HostController:
    """EKF + altitude filter + PID + mixer in float64, one step per sensor sample."""

    def __init__(
        self,
        vehicle: VehicleConfig,
        sample_period: float,
        gains: ControllerGains | None = None,
        ekf: EkfParams | None = None,
        altitude: AltitudeParams | None = None,
        climb_rate: float = DEFAULT_CLIMB_RATE_MPS,
        descent_rate: float = DEFAULT_DESCENT_RATE_MPS,
    ) -> None:
        self.vehicle = vehicle
        self.dt = sample_period
        self.gains = gains or default_gains(vehicle)
        self.t_gravity = vehicle.mass * GRAVITY
        self.mixer = Mixer(vehicle.motor, vehicle.arm_length, self.t_gravity / 4.0, vehicle.idle_pwm)
        self.ekf = AttitudeEkf(ekf)
        self.altitude = AltitudeFilter(altitude)
        self.pids = {
            "roll": Pid(self.gains.roll),
            "pitch": Pid(self.gains.pitch),
            "yaw": Pid(self.gains.yaw),
        }
        self.height_loop = HeightController(
            self.gains.height, vehicle.mass, GRAVITY, climb_rate, descent_rate, self.gains.max_tilt_gain
        )
        self.reset()

    @classmethod
    def for_scenario(cls, scenario: ScenarioConfig, vehicle: VehicleConfig) -> HostController:
        """The controller for ``scenario``: its sensor period and vertical-speed limits."""
        return cls(
            vehicle,
            scenario.sensors.period_steps * PHYSICS_DT_S,
            climb_rate=scenario.flight.climb_rate_mps,
            descent_rate=scenario.flight.descent_rate_mps,
        )

    def reset(self) -> None:
        """Forget everything (a new flight)."""
        self._sums = np.zeros(10)
        self._count = 0
        self.accel_bias = np.zeros(3)
        self._armed = False
        self.ekf.reset(np.array([1.0, 0.0, 0.0, 0.0]))
        self.altitude.reset(0.0, self.vehicle.rest_height)
        self._reset_loops()
        self.last_pwm: tuple[int, int, int, int] = MOTORS_OFF

    def _reset_loops(self) -> None:
        for pid in self.pids.values():
            pid.reset()
        self.height_loop.reset()

    @property
    def estimate(self) -> Estimate:
        """The current estimate (after the last :meth:`step`)."""
        q = self.ekf.quaternion
        return Estimate(q, quat.to_euler(q), self.altitude.height, self.altitude.velocity)

    def _calibrate(self, sample) -> None:
        moving = abs(float(np.linalg.norm(sample.accel)) - GRAVITY) > MOTION_ACCEL
        if moving:
            # The vehicle is still settling (it is spawned above the ground): start averaging again.
            self._sums[:] = 0.0
            self._count = 0
            return
        self._sums += np.concatenate((sample.gyro, sample.accel, sample.mag, [sample.baro_altitude]))
        self._count += 1
        mean = self._sums / self._count
        # Resting on flat ground the vehicle is level: what the accelerometer reads beyond
        # [0, 0, g] is its bias (a "level calibration").
        self.accel_bias = mean[3:6] - np.array([0.0, 0.0, GRAVITY])
        q0 = quat.from_accel_mag(mean[3:6] - self.accel_bias, mean[6:9])
        n = np.sqrt(self._count)
        self.ekf.reset(q0, bias=mean[0:3], quat_sigma=CALIBRATED_QUAT_SIGMA, bias_sigma=GYRO_NOISE / n)
        self.altitude.reset(float(mean[9]), self.vehicle.rest_height, self._count)

    def step(self, sample, setpoint: Setpoint) -> tuple[int, int, int, int]:
        """Consume one sensor sample; return the four PWM counts to apply now."""
        if not setpoint.armed:
            if self._armed:
                self.reset()
            self._calibrate(sample)
            self.last_pwm = MOTORS_OFF
            return self.last_pwm
        if not self._armed:
            self._armed = True
            self._reset_loops()
        dt = self.dt
        accel = np.asarray(sample.accel) - self.accel_bias
        q = self.ekf.step(sample.gyro, accel, sample.mag, dt)
        rotation = quat.to_matrix(q)
        height = self.altitude.step(rotation, accel, sample.baro_altitude, dt)
        roll, pitch, yaw = quat.to_euler(q)
        rates = euler_rates(roll, pitch, tuple(np.asarray(sample.gyro) - self.ekf.gyro_bias))
        u_roll = self.pids["roll"].step(setpoint.roll - roll, -rates[0], dt)
        u_pitch = self.pids["pitch"].step(setpoint.pitch - pitch, -rates[1], dt)
        u_yaw = self.pids["yaw"].step(wrap_angle(setpoint.yaw - yaw), -rates[2], dt)
        u_z = self.height_loop.step(
            setpoint.height,
            setpoint.height_rate,
            setpoint.height_accel,
            height,
            self.altitude.velocity,
            roll,
            pitch,
            dt,
        )
        self.last_pwm = self.mixer.pwm(u_z, u_roll, u_pitch, u_yaw)
        return self.last_pwm
