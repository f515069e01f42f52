"""Rotations for the physics side: unit quaternions (w, x, y, z, MuJoCo's order) and matrices.

R(q) maps body vectors to world vectors.  These helpers are independent of the reference
controllers' own quaternion code (:mod:`robosoc.control.quaternion`) so that tests comparing the
two check something.
"""

from __future__ import annotations

import math

import numpy as np


def quat_to_matrix(w: float, x: float, y: float, z: float) -> tuple[float, ...]:
    """Row-major body→world rotation matrix of a unit quaternion, as 9 floats."""
    xx, yy, zz = x * x, y * y, z * z
    xy, xz, yz = x * y, x * z, y * z
    wx, wy, wz = w * x, w * y, w * z
    return (
        1.0 - 2.0 * (yy + zz),
        2.0 * (xy - wz),
        2.0 * (xz + wy),
        2.0 * (xy + wz),
        1.0 - 2.0 * (xx + zz),
        2.0 * (yz - wx),
        2.0 * (xz - wy),
        2.0 * (yz + wx),
        1.0 - 2.0 * (xx + yy),
    )


def euler_from_quat(q: np.ndarray) -> np.ndarray:
    """Roll, pitch, yaw [rad] (Z-Y-X convention: R = Rz(yaw)·Ry(pitch)·Rx(roll)) of the unit
    quaternion (w, x, y, z)."""
    w, x, y, z = (float(c) for c in q)
    return np.array(euler_angles(w, x, y, z))


def euler_angles(w: float, x: float, y: float, z: float) -> tuple[float, float, float]:
    """:func:`euler_from_quat` of the quaternion's Python floats, as Python floats."""
    roll = math.atan2(2.0 * (w * x + y * z), 1.0 - 2.0 * (x * x + y * y))
    pitch = math.asin(max(-1.0, min(1.0, 2.0 * (w * y - z * x))))
    yaw = math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))
    return roll, pitch, yaw
