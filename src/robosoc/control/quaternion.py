"""Quaternion algebra of the reference controllers (float64, numpy).

Convention: q = (w, x, y, z), Hamilton product, unit norm; R(q) maps body vectors into the world
frame (body FLU, world x North, y West, z up).  Euler angles are Z-Y-X: roll α about x, pitch β
about y, yaw θ about z, with R = Rz(θ)·Ry(β)·Rx(α).
"""

from __future__ import annotations

import math

import numpy as np

from robosoc.physics.frames import euler_from_quat


def multiply(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton product a ⊗ b."""
    aw, ax, ay, az = a
    bw, bx, by, bz = b
    return np.array(
        [
            aw * bw - ax * bx - ay * by - az * bz,
            aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
        ]
    )


def conjugate(q: np.ndarray) -> np.ndarray:
    """Conjugate (the inverse of a unit quaternion)."""
    return np.array([q[0], -q[1], -q[2], -q[3]])


def normalize(q: np.ndarray) -> np.ndarray:
    """q / |q|."""
    return q / math.sqrt(float(q @ q))


def to_matrix(q: np.ndarray) -> np.ndarray:
    """Body→world rotation matrix R(q) of a unit quaternion."""
    w, x, y, z = q
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def from_matrix(m: np.ndarray) -> np.ndarray:
    """Unit quaternion (w ≥ 0) of a rotation matrix (Shepperd's method, numerically safe)."""
    trace = m[0, 0] + m[1, 1] + m[2, 2]
    if trace > 0:
        s = 2.0 * math.sqrt(1.0 + trace)
        q = np.array([0.25 * s, (m[2, 1] - m[1, 2]) / s, (m[0, 2] - m[2, 0]) / s, (m[1, 0] - m[0, 1]) / s])
    elif m[0, 0] > m[1, 1] and m[0, 0] > m[2, 2]:
        s = 2.0 * math.sqrt(1.0 + m[0, 0] - m[1, 1] - m[2, 2])
        q = np.array([(m[2, 1] - m[1, 2]) / s, 0.25 * s, (m[0, 1] + m[1, 0]) / s, (m[0, 2] + m[2, 0]) / s])
    elif m[1, 1] > m[2, 2]:
        s = 2.0 * math.sqrt(1.0 + m[1, 1] - m[0, 0] - m[2, 2])
        q = np.array([(m[0, 2] - m[2, 0]) / s, (m[0, 1] + m[1, 0]) / s, 0.25 * s, (m[1, 2] + m[2, 1]) / s])
    else:
        s = 2.0 * math.sqrt(1.0 + m[2, 2] - m[0, 0] - m[1, 1])
        q = np.array([(m[1, 0] - m[0, 1]) / s, (m[0, 2] + m[2, 0]) / s, (m[1, 2] + m[2, 1]) / s, 0.25 * s])
    q = normalize(q)
    return -q if q[0] < 0 else q


def to_euler(q: np.ndarray) -> np.ndarray:
    """(roll α, pitch β, yaw θ) [rad] of a unit quaternion (the physics' Z-Y-X convention,
    :func:`robosoc.physics.frames.euler_from_quat`)."""
    return euler_from_quat(q)


def from_euler(roll: float, pitch: float, yaw: float) -> np.ndarray:
    """Unit quaternion of Z-Y-X Euler angles [rad]."""
    cr, sr = math.cos(roll / 2), math.sin(roll / 2)
    cp, sp = math.cos(pitch / 2), math.sin(pitch / 2)
    cy, sy = math.cos(yaw / 2), math.sin(yaw / 2)
    return np.array(
        [
            cr * cp * cy + sr * sp * sy,
            sr * cp * cy - cr * sp * sy,
            cr * sp * cy + sr * cp * sy,
            cr * cp * sy - sr * sp * cy,
        ]
    )


def angle_between(a: np.ndarray, b: np.ndarray) -> float:
    """Rotation angle [rad] of a⁻¹ ⊗ b, in [0, π] (the attitude error between two quaternions)."""
    dot = abs(float(a @ b)) / math.sqrt(float(a @ a) * float(b @ b))
    return 2.0 * math.acos(min(1.0, dot))


def omega_matrix(rate: np.ndarray) -> np.ndarray:
    """Ω(ω) with q ⊗ (0, ω) = Ω(ω)·q, so that dq/dt = ½·Ω(ω)·q for a body rate ω."""
    p, q, r = rate
    return np.array(
        [
            [0.0, -p, -q, -r],
            [p, 0.0, r, -q],
            [q, -r, 0.0, p],
            [r, q, -p, 0.0],
        ]
    )


def xi_matrix(q: np.ndarray) -> np.ndarray:
    """Ξ(q) with q ⊗ (0, ω) = Ξ(q)·ω (the derivative of the kinematics with respect to ω)."""
    w, x, y, z = q
    return np.array(
        [
            [-x, -y, -z],
            [w, -z, y],
            [z, w, -x],
            [-y, x, w],
        ]
    )


def rotate_to_body(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Rᵀ(q)·v: a world vector expressed in the body frame."""
    return to_matrix(q).T @ v


def rotate_to_body_jacobian(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """∂(Rᵀ(q)·v)/∂q, a 3×4 matrix (columns w, x, y, z), for the quadratic form of R(q)."""
    w, x, y, z = q
    v0, v1, v2 = v
    return 2.0 * np.array(
        [
            [z * v1 - y * v2, y * v1 + z * v2, -2 * y * v0 + x * v1 - w * v2, -2 * z * v0 + w * v1 + x * v2],
            [-z * v0 + x * v2, y * v0 - 2 * x * v1 + w * v2, x * v0 + z * v2, -w * v0 - 2 * z * v1 + y * v2],
            [y * v0 - x * v1, z * v0 - w * v1 - 2 * x * v2, w * v0 + z * v1 - 2 * y * v2, x * v0 + y * v1],
        ]
    )


def from_accel_mag(accel: np.ndarray, mag: np.ndarray) -> np.ndarray:
    """Attitude from one gravity and one magnetic reading (TRIAD, gravity exact, field in its plane).

    The accelerometer at rest measures world up in body coordinates, the magnetometer the field.
    World y (West) is up × field; world x = y × up.  These three body-frame vectors are the rows
    of R.
    """
    up = accel / np.linalg.norm(accel)
    west = np.cross(up, mag)
    west /= np.linalg.norm(west)
    north = np.cross(west, up)
    return from_matrix(np.vstack((north, west, up)))
