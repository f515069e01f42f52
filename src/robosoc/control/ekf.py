"""Quaternion attitude EKF of the seed's Algorithm 1 (float64 reference model).

State ``x = [q_w, q_x, q_y, q_z, b_p, b_q, b_r]``: the body→world orientation quaternion and the
three gyroscope biases [rad/s].  One call of :meth:`AttitudeEkf.step` is one pass of Algorithm 1::

    1: x̄ = f(x, ω_m)                   q̄ = (I₄ + ½·Δt·Ω(ω_m − b))·q,  b̄ = b
    2: P̄ = F·P·Fᵀ + R                  F = ∂f/∂x (7×7), R = process noise (7×7)
    3: K = P̄·Hᵀ·(H·P̄·Hᵀ + Q)⁻¹          H = ∂h/∂x (6×7), Q = measurement noise (6×6)
    4: x = x̄ + K·(z − h(x̄))
    5: P = (I − K·H)·P̄
    6: q ← q/|q|                        (not in the paper: keeps q a rotation)

The paper writes R for the process noise (line 2) and Q for the measurement noise (line 3); the
names follow the paper here.  (Its prose gives them swapped dimensions; the algorithm's use fixes
them.)

**Measurement model.**  The paper says z ∈ ℝ⁴ without saying what the four values are; we use the
six components of the two unit vectors the sensors give, which needs no extra trigonometry:
``z = [a/|a|, m/|m|]`` and ``h(q) = [Rᵀ(q)·e_z, Rᵀ(q)·m_ref]`` with ``e_z`` world up (an
accelerometer at rest reads +g along world up) and ``m_ref = [0.5, 0, −0.866]`` the field.  H is
``[∂(Rᵀv)/∂q for v = e_z and m_ref | 0]``, the biases enter only through f.

**Noise choices** (defaults of :class:`EkfParams`):

- process R: the quaternion block is the gyroscope's white noise mapped through the kinematics,
  ``(½·Δt)²·Ξ(q)·diag(σ_g²)·Ξ(q)ᵀ`` with σ_g = (0.05, 0.05, 0.015) rad/s (quadrotor.md), plus a
  small floor (1e-10) that keeps P̄ positive definite; the bias block is a random walk of
  ``bias_walk²·Δt`` per axis.
- measurement Q: diagonal.  The magnetometer's σ is its white noise (0.013 of a unit field).  The
  accelerometer's direction noise is set far above its white noise (0.35/9.8 ≈ 0.036):
  in flight it measures thrust plus drag, not gravity, so its direction is off by the
  vehicle's horizontal acceleration (about 10° during a 10° attitude step).  σ_a = 1.0 makes
  gravity a weak, long-term reference, while the magnetometer (unaffected by acceleration) pins
  every axis except rotations about the field itself.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from robosoc.control import quaternion as quat

EARTH_UP = np.array([0.0, 0.0, 1.0])
MAGNETIC_REFERENCE = np.array([0.5, 0.0, -0.866])


@dataclass(frozen=True)
class EkfParams:
    """Tuning of the attitude EKF (see the module docstring for each choice)."""

    gyro_noise: tuple[float, float, float] = (0.05, 0.05, 0.015)
    """White noise σ of one gyroscope sample [rad/s] (quadrotor.md)."""
    bias_walk: float = 1e-4
    """Random walk of the gyroscope bias [rad/s/√s]."""
    accel_noise: float = 1.0
    """σ of the normalised accelerometer direction (dimensionless), inflated for manoeuvres."""
    mag_noise: float = 0.013
    """σ of the normalised magnetometer (dimensionless), its white noise."""
    quat_floor: float = 1e-10
    """Added to the quaternion block of the process noise (keeps P̄ positive definite)."""
    initial_quat_sigma: float = 0.05
    """σ of each quaternion component at initialisation."""
    initial_bias_sigma: float = 0.1
    """σ of each gyroscope bias at initialisation [rad/s] (the sensor's bias spread)."""
    mag_reference: tuple[float, float, float] = (0.5, 0.0, -0.866)
    """Earth field in the world frame (normalised before use)."""


class AttitudeEkf:
    """Float64 attitude EKF: orientation quaternion + gyroscope biases from IMU and magnetometer."""

    def __init__(self, params: EkfParams | None = None) -> None:
        self.params = params or EkfParams()
        ref = np.array(self.params.mag_reference, dtype=float)
        self.mag_reference = ref / np.linalg.norm(ref)
        self.measurement_cov = np.diag([self.params.accel_noise**2] * 3 + [self.params.mag_noise**2] * 3)
        self.x = np.array([1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0])
        self.P = np.eye(7)
        self.reset(np.array([1.0, 0.0, 0.0, 0.0]))

    @property
    def quaternion(self) -> np.ndarray:
        """Estimated orientation (w, x, y, z), body→world."""
        return self.x[:4].copy()

    @property
    def gyro_bias(self) -> np.ndarray:
        """Estimated gyroscope biases [rad/s]."""
        return self.x[4:].copy()

    def reset(
        self,
        q: np.ndarray,
        bias: np.ndarray | None = None,
        quat_sigma: float | None = None,
        bias_sigma: float | None = None,
    ) -> None:
        """Start from orientation ``q`` and gyroscope ``bias``; σ of each quaternion component and
        each bias default to the params' initial values."""
        self.x = np.concatenate((quat.normalize(np.asarray(q, dtype=float)), np.zeros(3) if bias is None else bias))
        sq = self.params.initial_quat_sigma if quat_sigma is None else quat_sigma
        sb = self.params.initial_bias_sigma if bias_sigma is None else bias_sigma
        self.P = np.diag([sq**2] * 4 + [sb**2] * 3)

    def process_noise(self, q: np.ndarray, dt: float) -> np.ndarray:
        """The paper's R: 7×7 process noise for one step of length ``dt``."""
        xi = quat.xi_matrix(q)
        noise = np.zeros((7, 7))
        noise[:4, :4] = (0.5 * dt) ** 2 * xi @ np.diag(np.square(self.params.gyro_noise)) @ xi.T
        noise[:4, :4] += self.params.quat_floor * np.eye(4)
        noise[4:, 4:] = self.params.bias_walk**2 * dt * np.eye(3)
        return noise

    def predict(self, gyro: np.ndarray, dt: float) -> None:
        """Lines 1–2: propagate with the bias-corrected gyroscope reading over ``dt`` [s]."""
        q = self.x[:4].copy()
        rate = np.asarray(gyro, dtype=float) - self.x[4:]
        transition = np.eye(4) + 0.5 * dt * quat.omega_matrix(rate)
        jacobian = np.eye(7)
        jacobian[:4, :4] = transition
        jacobian[:4, 4:] = -0.5 * dt * quat.xi_matrix(q)
        self.x[:4] = transition @ q
        self.P = jacobian @ self.P @ jacobian.T + self.process_noise(q, dt)

    def measurement(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """h(q) (6) and its Jacobian H (6×7) for the accelerometer and magnetometer directions."""
        h = np.concatenate((quat.rotate_to_body(q, EARTH_UP), quat.rotate_to_body(q, self.mag_reference)))
        jac = np.zeros((6, 7))
        jac[:3, :4] = quat.rotate_to_body_jacobian(q, EARTH_UP)
        jac[3:, :4] = quat.rotate_to_body_jacobian(q, self.mag_reference)
        return h, jac

    def update(self, accel: np.ndarray, mag: np.ndarray) -> None:
        """Lines 3–5 (and the normalisation): correct with one accelerometer + magnetometer reading."""
        z = np.concatenate((accel / np.linalg.norm(accel), mag / np.linalg.norm(mag)))
        h, jac = self.measurement(self.x[:4])
        innovation = z - h
        innovation_cov = jac @ self.P @ jac.T + self.measurement_cov
        gain = self.P @ jac.T @ np.linalg.inv(innovation_cov)
        self.x = self.x + gain @ innovation
        self.P = (np.eye(7) - gain @ jac) @ self.P
        self.x[:4] = quat.normalize(self.x[:4])

    def step(self, gyro: np.ndarray, accel: np.ndarray, mag: np.ndarray, dt: float) -> np.ndarray:
        """One pass of Algorithm 1; returns the new orientation estimate."""
        self.predict(gyro, dt)
        self.update(accel, mag)
        return self.quaternion
