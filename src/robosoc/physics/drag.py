"""Quadratic aerodynamic drag of the hector quadrotor, in the body frame.

With the air-relative velocity ``v_rel = Rᵀ·(v_world − wind)`` (R body→world, so Rᵀ takes world
vectors into the body frame) and body rates ω::

    F = −[C_wxy, C_wxy, C_wz] ⊙ |v_rel| · v_rel
    τ = −[C_mxy, C_mxy, C_mz] ⊙ |ω| · ω

|·| is the Euclidean norm.  The original plugin rotates by R where Rᵀ is meant, which flips the
sign of the roll coupling; this model uses Rᵀ.
"""

from __future__ import annotations

import math

from robosoc.config.vehicle import DragConfig


class Drag:
    """Drag coefficients of one vehicle, evaluated on Python floats (hot path)."""

    __slots__ = ("_cmxy", "_cmz", "_cwxy", "_cwz")

    def __init__(self, config: DragConfig) -> None:
        self._cwxy = config.c_wxy
        self._cwz = config.c_wz
        self._cmxy = config.c_mxy
        self._cmz = config.c_mz

    def wrench(
        self, u: float, v: float, w: float, p: float, q: float, r: float
    ) -> tuple[float, float, float, float, float, float]:
        """Body-frame drag (Fx, Fy, Fz, τx, τy, τz) for air-relative body velocity and body rates."""
        speed = math.sqrt(u * u + v * v + w * w)
        rate = math.sqrt(p * p + q * q + r * r)
        fxy = -self._cwxy * speed
        mxy = -self._cmxy * rate
        return (
            fxy * u,
            fxy * v,
            -self._cwz * speed * w,
            mxy * p,
            mxy * q,
            -self._cmz * rate * r,
        )
