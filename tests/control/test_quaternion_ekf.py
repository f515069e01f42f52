"""Quaternion algebra and the attitude EKF against hand-checked cases and synthetic data."""

import math

import numpy as np

from robosoc.control import quaternion as quat
from robosoc.control.ekf import AttitudeEkf, EkfParams

MAG = np.array([0.5, 0.0, -0.866])


def test_euler_round_trip_and_matrix() -> None:
    q = quat.from_euler(0.3, -0.2, 1.1)
    np.testing.assert_allclose(quat.to_euler(q), [0.3, -0.2, 1.1], atol=1e-12)
    rot = quat.to_matrix(q)
    np.testing.assert_allclose(rot @ rot.T, np.eye(3), atol=1e-12)
    # Z-Y-X: R = Rz(yaw)·Ry(pitch)·Rx(roll), written out by hand.
    cr, sr, cp, sp, cy, sy = math.cos(0.3), math.sin(0.3), math.cos(-0.2), math.sin(-0.2), math.cos(1.1), math.sin(1.1)
    rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    np.testing.assert_allclose(rot, rz @ ry @ rx, atol=1e-12)
    np.testing.assert_allclose(quat.from_matrix(rot), q * np.sign(q[0]), atol=1e-12)


def test_kinematics_matrices_agree_with_the_product() -> None:
    q = quat.normalize(np.array([0.9, 0.1, -0.3, 0.2]))
    w = np.array([0.4, -1.0, 2.0])
    product = quat.multiply(q, np.array([0.0, *w]))
    np.testing.assert_allclose(quat.omega_matrix(w) @ q, product, atol=1e-15)
    np.testing.assert_allclose(quat.xi_matrix(q) @ w, product, atol=1e-15)


def test_measurement_jacobian_matches_finite_differences() -> None:
    q = quat.normalize(np.array([0.8, 0.2, -0.4, 0.3]))
    for v in (np.array([0.0, 0.0, 1.0]), MAG):
        jac = quat.rotate_to_body_jacobian(q, v)
        eps = 1e-7
        numeric = np.column_stack(
            [(quat.rotate_to_body(q + eps * e, v) - quat.rotate_to_body(q - eps * e, v)) / (2 * eps) for e in np.eye(4)]
        )
        np.testing.assert_allclose(jac, numeric, atol=1e-7)


def test_triad_recovers_a_known_attitude() -> None:
    q = quat.from_euler(0.2, -0.1, 0.7)
    accel = quat.rotate_to_body(q, np.array([0.0, 0.0, 9.8]))
    mag = quat.rotate_to_body(q, MAG)
    assert quat.angle_between(quat.from_accel_mag(accel, mag), q) < 1e-9


def test_predict_hand_checked() -> None:
    ekf = AttitudeEkf(EkfParams(gyro_noise=(0.1, 0.1, 0.1), bias_walk=0.0, quat_floor=0.0))
    ekf.reset(np.array([1.0, 0.0, 0.0, 0.0]), quat_sigma=0.0, bias_sigma=0.0)
    ekf.predict(np.array([0.1, 0.0, 0.0]), 0.01)
    # q̄ = (I + ½·dt·Ω(ω))·q = (1, ½·0.01·0.1, 0, 0); not normalised by the prediction.
    np.testing.assert_allclose(ekf.x, [1.0, 0.0005, 0.0, 0.0, 0.0, 0.0, 0.0], atol=1e-15)
    # With P = 0 the new P is the process noise: (½·dt)²·σ²·Ξ·Ξᵀ, Ξ(identity)·Ξᵀ = diag(0, 1, 1, 1).
    np.testing.assert_allclose(np.diag(ekf.P)[:4], [0.0, 2.5e-7, 2.5e-7, 2.5e-7], atol=1e-20)


def test_consistent_measurement_leaves_the_state_and_shrinks_p() -> None:
    ekf = AttitudeEkf()
    q = quat.from_euler(0.1, 0.2, -0.3)
    ekf.reset(q)
    trace = np.trace(ekf.P)
    ekf.update(quat.rotate_to_body(q, np.array([0.0, 0.0, 9.8])), quat.rotate_to_body(q, MAG))
    np.testing.assert_allclose(ekf.quaternion, q, atol=1e-12)
    assert np.trace(ekf.P) < trace


def test_converges_to_a_tilted_attitude_and_the_gyro_bias_when_still() -> None:
    # A vehicle at rest: gravity is exact, so the accelerometer may be trusted at its own noise
    # (0.35/9.8 ≈ 0.036); the in-flight default (1.0) would leave the rotation about the field
    # to the gyroscope alone.
    rng = np.random.default_rng(1)
    truth = quat.from_euler(math.radians(20), math.radians(-10), math.radians(45))
    bias = np.array([0.05, -0.03, 0.02])
    ekf = AttitudeEkf(EkfParams(accel_noise=0.036))
    for _ in range(3000):  # 30 s at 100 Hz, vehicle still
        gyro = bias + rng.normal(0.0, [0.05, 0.05, 0.015])
        accel = quat.rotate_to_body(truth, np.array([0.0, 0.0, 9.8])) + rng.normal(0.0, 0.35, 3)
        mag = quat.rotate_to_body(truth, MAG) + rng.normal(0.0, 0.013, 3)
        ekf.step(gyro, accel, mag, 0.01)
    assert math.degrees(quat.angle_between(ekf.quaternion, truth)) < 0.5
    np.testing.assert_allclose(ekf.gyro_bias, bias, atol=0.01)
    assert abs(np.linalg.norm(ekf.quaternion) - 1.0) < 1e-12


def test_ekf_is_deterministic() -> None:
    def run() -> np.ndarray:
        rng = np.random.default_rng(4)
        ekf = AttitudeEkf()
        for _ in range(200):
            ekf.step(rng.normal(0, 0.05, 3), np.array([0, 0, 9.8]) + rng.normal(0, 0.3, 3), MAG, 0.01)
        return np.concatenate((ekf.x, ekf.P.ravel()))

    assert np.array_equal(run(), run())
