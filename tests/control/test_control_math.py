"""Quaternion product, Euler-rate kinematics and the height profile against independent references.

* The Hamilton product is checked on the basis (i·j = k, j·k = i, k·i = j, j·i = −k, i² = −1) and
  on random quaternions against the matrix form L(a)·b written out here.
* Euler rates are checked against a numerical derivative of the Z-Y-X angles of a quaternion path
  driven by the body rate (angles from a rotation matrix built here, not from the controller).
* The height profile's rate and acceleration are the numerical derivatives of its height, and
  it is at rest (zero rate and acceleration) at both ends, the ends included.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from robosoc.config.scenario import FlightPlan, HeightMove, SetpointStep
from robosoc.control import quaternion as quat
from robosoc.control.altitude import AltitudeFilter
from robosoc.control.ekf import AttitudeEkf, EkfParams
from robosoc.control.pid import HeightController, Pid, PidGains, euler_rates, wrap_angle
from robosoc.control.setpoint import Setpoint, move_profile, setpoint_at

ONE, I, J, K = (np.eye(4)[k] for k in range(4))


def left_matrix(a: np.ndarray) -> np.ndarray:
    """L(a) with a ⊗ b = L(a)·b (Hamilton)."""
    w, x, y, z = a
    return np.array([[w, -x, -y, -z], [x, w, -z, y], [y, z, w, -x], [z, -y, x, w]])


def test_hamilton_product_on_the_basis() -> None:
    table = [(I, J, K), (J, K, I), (K, I, J), (J, I, -K), (K, J, -I), (I, K, -J)]
    for a, b, c in table:
        np.testing.assert_array_equal(quat.multiply(a, b), c)
    for u in (I, J, K):
        np.testing.assert_array_equal(quat.multiply(u, u), -ONE)
        np.testing.assert_array_equal(quat.multiply(ONE, u), u)
        np.testing.assert_array_equal(quat.multiply(u, ONE), u)


def test_hamilton_product_on_random_quaternions() -> None:
    rng = np.random.default_rng(15)
    for _ in range(50):
        a, b = rng.normal(size=4) * 3, rng.normal(size=4) * 3
        np.testing.assert_allclose(quat.multiply(a, b), left_matrix(a) @ b, rtol=1e-12, atol=1e-12)
        # the product of unit quaternions is a unit quaternion; conjugation reverses the order
        ua, ub = a / np.linalg.norm(a), b / np.linalg.norm(b)
        assert np.linalg.norm(quat.multiply(ua, ub)) == pytest.approx(1.0)
        np.testing.assert_allclose(
            quat.conjugate(quat.multiply(a, b)), quat.multiply(quat.conjugate(b), quat.conjugate(a)), atol=1e-12
        )


def _zyx_angles(q: np.ndarray) -> np.ndarray:
    """Roll, pitch, yaw of R = Rz(yaw)·Ry(pitch)·Rx(roll), from R(q) written out here."""
    w, x, y, z = q
    r20 = 2 * (x * z - w * y)
    r21 = 2 * (y * z + w * x)
    r22 = 1 - 2 * (x * x + y * y)
    r10 = 2 * (x * y + w * z)
    r00 = 1 - 2 * (y * y + z * z)
    return np.array([math.atan2(r21, r22), -math.asin(r20), math.atan2(r10, r00)])


def _exp(v: np.ndarray) -> np.ndarray:
    angle = float(np.linalg.norm(v))
    return np.array([math.cos(angle / 2), *(v / angle * math.sin(angle / 2))]) if angle else ONE.copy()


@pytest.mark.parametrize("roll", [-0.7, 0.0, 0.4])
@pytest.mark.parametrize("pitch", [-0.5, 0.3])
def test_euler_rates_are_the_derivative_of_the_angles(roll: float, pitch: float) -> None:
    q = quat.from_euler(roll, pitch, 0.8)
    np.testing.assert_allclose(_zyx_angles(q), [roll, pitch, 0.8], atol=1e-12)
    body = np.array([0.3, -1.1, 0.7])
    h = 1e-6
    ahead = _zyx_angles(quat.multiply(q, _exp(body * h)))  # body rates act on the right
    behind = _zyx_angles(quat.multiply(q, _exp(-body * h)))
    numeric = (ahead - behind) / (2 * h)
    np.testing.assert_allclose(euler_rates(roll, pitch, tuple(body)), numeric, atol=1e-6)


def test_wrap_angle() -> None:
    for angle, wrapped in ((0.0, 0.0), (math.pi, -math.pi), (-math.pi, -math.pi), (3 * math.pi / 2, -math.pi / 2),
                           (-3 * math.pi / 2, math.pi / 2), (7.0, 7.0 - 2 * math.pi)):  # fmt: skip
        assert wrap_angle(angle) == pytest.approx(wrapped, abs=1e-12)


MOVE = HeightMove(start_s=2.0, duration_s=1.5, from_m=0.2, to_m=1.4)


def test_height_profile_is_at_rest_at_both_ends() -> None:
    assert move_profile(MOVE, 1.0) == (0.2, 0.0, 0.0)
    assert move_profile(MOVE, 2.0) == (0.2, 0.0, 0.0)  # the start itself
    assert move_profile(MOVE, 3.5) == (1.4, 0.0, 0.0)  # the end itself
    assert move_profile(MOVE, 9.0) == (1.4, 0.0, 0.0)


def test_height_profile_derivatives_by_finite_differences() -> None:
    h = 1e-6
    for t in (2.1, 2.5, 2.75, 3.0, 3.4):
        z, rate, accel = move_profile(MOVE, t)
        ahead, behind = move_profile(MOVE, t + h), move_profile(MOVE, t - h)
        assert rate == pytest.approx((ahead[0] - behind[0]) / (2 * h), abs=1e-6)
        assert accel == pytest.approx((ahead[1] - behind[1]) / (2 * h), abs=1e-5)
    # the half cosine: halfway it is at the mid height with the peak rate π·Δ/(2T) and no acceleration
    z, rate, accel = move_profile(MOVE, 2.75)
    assert z == pytest.approx(0.8) and rate == pytest.approx(math.pi * 1.2 / 3.0) and accel == pytest.approx(0.0)
    # just after the start: the peak acceleration π²·Δ/(2T²)
    assert move_profile(MOVE, 2.0 + 1e-9)[2] == pytest.approx(math.pi**2 * 1.2 / (2 * 1.5**2), rel=1e-6)


def test_pid_integrates_up_to_and_including_the_band() -> None:
    gains = PidGains(kp=0.0, ki=1.0, kd=0.0, integral_limit=10.0, output_limit=10.0, integral_band=0.25)
    pid = Pid(gains)
    assert pid.step(0.25, 0.0, 2.0) == 0.5  # |e| = band: the integral learns
    assert pid.step(0.26, 0.0, 2.0) == 0.5  # beyond the band: frozen
    assert pid.step(-0.25, 0.0, 1.0) == 0.25


def test_height_integral_learns_at_the_band_while_the_setpoint_holds() -> None:
    gains = PidGains(kp=1.0, ki=1.0, kd=2.0, integral_limit=5.0, output_limit=100.0, integral_band=0.25)
    hc = HeightController(gains, mass=1.0, gravity=9.8, climb_rate=2.0, descent_rate=1.0, max_tilt_gain=1.5)
    hc.step(0.25, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.5)  # error exactly the band, setpoint still
    assert hc.integral == 0.125
    hc.step(0.5, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.5)  # outside the band
    assert hc.integral == 0.125
    hc.step(0.25, 0.5, 0.0, 0.0, 0.0, 0.0, 0.0, 0.5)  # the setpoint moves: no learning
    assert hc.integral == 0.125


def test_altitude_filter_uses_the_vertical_specific_force_of_any_attitude() -> None:
    """Two filters fed the same vertical specific force, one through a tilted R(q) and a body-frame
    reading, the other level with the world-frame reading, must estimate the same height."""
    rotation = quat.to_matrix(quat.from_euler(0.4, -0.3, 1.1))
    tilted, level = AltitudeFilter(), AltitudeFilter()
    for f in (tilted, level):
        f.reset(100.0, 0.2, samples=10)
    accel_body = np.array([1.3, -0.7, 9.9])
    world = rotation @ accel_body
    for k in range(20):
        baro = 100.0 + 0.01 * k
        h1 = tilted.step(rotation, accel_body, baro, 0.01)
        h2 = level.step(np.eye(3), np.array([0.0, 0.0, world[2]]), baro, 0.01)
        assert h1 == pytest.approx(h2, abs=1e-12)
    assert tilted.velocity == pytest.approx(level.velocity, abs=1e-12)


def _axis_angle_quat(axis: np.ndarray, angle: float) -> np.ndarray:
    axis = axis / np.linalg.norm(axis)
    q = np.array([math.cos(angle / 2), *(math.sin(angle / 2) * axis)])
    return -q if q[0] < 0 else q


def _rodrigues(axis: np.ndarray, angle: float) -> np.ndarray:
    """R = I + sin θ·K + (1 − cos θ)·K² for the unit axis k (K the cross-product matrix)."""
    kx, ky, kz = axis / np.linalg.norm(axis)
    k = np.array([[0.0, -kz, ky], [kz, 0.0, -kx], [-ky, kx, 0.0]])
    return np.eye(3) + math.sin(angle) * k + (1 - math.cos(angle)) * k @ k


@pytest.mark.parametrize(
    ("axis", "angle"),
    [
        ((0.3, -0.2, 0.9), 0.5),  # trace > 0
        ((1.0, 0.05, -0.02), 3.0),  # near a half turn about x: R00 is the largest diagonal entry
        ((0.04, 1.0, 0.03), 2.9),  # about y: R11 largest
        ((-0.02, 0.05, 1.0), 3.1),  # about z: R22 largest
        ((1.0, 1.0, 0.0), math.pi),  # exactly half turns: trace = -1
        ((0.0, 1.0, 1.0), math.pi),
        ((1.0, 0.0, 1.0), -math.pi),
        ((0.2, -0.9, 0.4), -2.5),
    ],
)
def test_quaternion_of_a_rotation_matrix_on_every_branch(axis: tuple[float, float, float], angle: float) -> None:
    a = np.array(axis)
    m = _rodrigues(a, angle)
    want = _axis_angle_quat(a, angle)
    got = quat.from_matrix(m)
    if abs(want[0]) < 1e-12:  # w = 0: q and −q are the same rotation, either sign is right
        want = want if np.dot(want, got) > 0 else -want
    np.testing.assert_allclose(got, want, atol=1e-12)
    assert got[0] >= 0.0


def test_angle_between_ignores_the_norms() -> None:
    a = quat.from_euler(0.2, 0.1, -0.3)
    b = quat.multiply(a, _axis_angle_quat(np.array([0.0, 1.0, 0.0]), 0.4))
    assert quat.angle_between(a, b) == pytest.approx(0.4)
    assert quat.angle_between(3.0 * a, 0.5 * b) == pytest.approx(0.4)
    assert quat.angle_between(a, -b) == pytest.approx(0.4)  # −b is the same attitude


def test_euler_angles_clamp_at_gimbal_lock() -> None:
    # 2·(w·y − z·x) slightly outside [−1, 1] (an unnormalised input) reads as ±90° pitch
    assert quat.to_euler(np.array([0.8, 0.0, 0.8, 0.0]))[1] == pytest.approx(math.pi / 2)
    assert quat.to_euler(np.array([0.8, 0.0, -0.8, 0.0]))[1] == pytest.approx(-math.pi / 2)


def _rotation_of(q: np.ndarray) -> np.ndarray:
    """R(q) in the form of quaternion.py's module docstring, 1 − 2(y² + z²) on the diagonal (the
    Jacobian is of this polynomial, whatever the norm of q)."""
    w, x, y, z = q
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def test_rotate_to_body_jacobian_is_the_derivative() -> None:
    rng = np.random.default_rng(3)
    for _ in range(5):
        q = rng.normal(size=4)
        v = rng.normal(size=3)
        h = 1e-6
        numeric = np.column_stack(
            [(_rotation_of(q + h * e).T @ v - _rotation_of(q - h * e).T @ v) / (2 * h) for e in np.eye(4)]
        )
        np.testing.assert_allclose(quat.rotate_to_body_jacobian(q, v), numeric, atol=1e-7)


def test_ekf_process_noise_is_the_papers() -> None:
    """R = (Δt/2)²·Ξ(q)·diag(σ_g²)·Ξ(q)ᵀ + floor·I on the quaternion, σ_b²·Δt·I on the bias, with
    Ξ(q) the matrix of ω ↦ q ⊗ (0, ω), built here from the product."""
    params = EkfParams(gyro_noise=(0.1, 0.2, 0.3), bias_walk=0.02, quat_floor=1e-3)
    q = quat.normalize(np.array([0.9, 0.1, -0.3, 0.2]))
    xi = np.column_stack([quat.multiply(q, np.array([0.0, *e])) for e in np.eye(3)])
    dt = 0.01
    want = np.zeros((7, 7))
    want[:4, :4] = (dt / 2) ** 2 * xi @ np.diag([0.01, 0.04, 0.09]) @ xi.T + 1e-3 * np.eye(4)
    want[4:, 4:] = 0.02**2 * dt * np.eye(3)
    np.testing.assert_allclose(AttitudeEkf(params).process_noise(q, dt), want, rtol=1e-12, atol=1e-18)


def test_ekf_prediction_accepts_integer_gyro_readings() -> None:
    ekf = AttitudeEkf()
    ekf.predict(np.array([0, 0, 1]), 0.01)  # an integer array is read as floats
    assert ekf.x[3] == pytest.approx(math.sin(0.005), rel=1e-4)


def test_setpoint_at_boundaries() -> None:
    plan = FlightPlan(
        takeoff_s=1.0, climb_s=2.0, height_m=1.0,
        steps=(SetpointStep(3.5, "height", 1.5), SetpointStep(4.0, "roll", 10.0)),
    )  # fmt: skip
    rest = 0.2

    def half_cosine(h0: float, h1: float, t0: float, duration: float, t: float) -> float:
        return h0 + (h1 - h0) * (1 - math.cos(math.pi * (t - t0) / duration)) / 2

    assert setpoint_at(plan, rest, 0.99) == Setpoint(height=rest, armed=False)
    at_takeoff = setpoint_at(plan, rest, 1.0)
    assert at_takeoff.armed and at_takeoff.height == rest and at_takeoff.height_rate == 0.0
    # late in the take-off climb, 0.6 s before the next move: still the climb
    assert setpoint_at(plan, rest, 2.9).height == pytest.approx(half_cosine(0.2, 1.0, 1.0, 2.0, 2.9))
    assert setpoint_at(plan, rest, 4.5).height == pytest.approx(half_cosine(1.0, 1.5, 3.5, 2.0, 4.5))
    assert setpoint_at(plan, rest, 3.99).roll == 0.0
    assert setpoint_at(plan, rest, 4.0).roll == pytest.approx(math.radians(10.0))  # from its time on
    assert setpoint_at(plan, rest, 9.0) == Setpoint(roll=math.radians(10.0), height=1.5, armed=True)
