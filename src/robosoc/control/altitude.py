"""Altitude estimate from barometer and accelerometer: a three-state linear Kalman filter.

State ``[h, v, b]``: height of the body origin above the take-off ground [m], vertical velocity
[m/s] and the bias of the vertical acceleration [m/s²].  Per sample (Δt = sensor period)::

    a   = (R(q)·a_m)_z − g              vertical acceleration from the accelerometer, rotated
                                        by the attitude estimate
    h  ← h + v·Δt + ½·(a − b)·Δt²
    v  ← v + (a − b)·Δt
    P  ← F·P·Fᵀ + G·Gᵀ·σ_a² + diag(0, 0, σ_b²·Δt)   F = [[1, Δt, −½Δt²], [0, 1, −Δt], [0, 0, 1]],
                                                   G = [½Δt², Δt, 0]
    then a scalar update with the barometer: z = baro_altitude − reference, H = [1, 0, 0],
    variance σ_baro².

The barometer has a bias of ~10 m, so the ``reference`` (baro reading at ground level) is
calibrated on the ground before take-off: the mean barometer reading minus the known rest height
of the body origin.  Constants: σ_a = 0.35 m/s² (accelerometer white noise), σ_b = 0.01 m/s²/√s
(bias walk), σ_baro = 0.1 m (barometer white noise), g = 9.8 m/s².
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

GRAVITY = 9.8


@dataclass(frozen=True)
class AltitudeParams:
    """Noise constants of the altitude filter."""

    accel_noise: float = 0.35
    """σ of the vertical acceleration per sample [m/s²]."""
    bias_walk: float = 0.01
    """Random walk of the acceleration bias [m/s²/√s]."""
    baro_noise: float = 0.1
    """σ of one barometer reading [m]."""
    initial_bias_sigma: float = 0.1
    """σ of the acceleration bias at start [m/s²]."""


class AltitudeFilter:
    """Height and vertical velocity from barometer altitude and vertical specific force.

    Written out in scalars for the fixed-point port: the state is ``h, v, b`` and the symmetric
    covariance P is held as its six distinct entries ``p00 p01 p02 p11 p12 p22``.
    """

    def __init__(self, params: AltitudeParams | None = None) -> None:
        self.params = params or AltitudeParams()
        self.reference = 0.0
        self.h = self.v = self.b = 0.0
        self.p00 = self.p11 = self.p22 = 1.0
        self.p01 = self.p02 = self.p12 = 0.0

    @property
    def height(self) -> float:
        """Estimated height of the body origin above the ground [m]."""
        return self.h

    @property
    def velocity(self) -> float:
        """Estimated vertical velocity [m/s] (up positive)."""
        return self.v

    @property
    def covariance(self) -> np.ndarray:
        """P as a 3×3 matrix (for inspection and tests)."""
        return np.array(
            [[self.p00, self.p01, self.p02], [self.p01, self.p11, self.p12], [self.p02, self.p12, self.p22]]
        )

    def reset(self, baro_ground: float, rest_height: float, samples: int = 1) -> None:
        """Calibrate: ``baro_ground`` is the mean of ``samples`` barometer altitudes taken while
        resting at ``rest_height``, so the reference is uncertain by σ_baro/√samples."""
        self.reference = baro_ground - rest_height
        self.h, self.v, self.b = rest_height, 0.0, 0.0
        self.p00 = self.params.baro_noise**2 / max(1, samples)
        self.p11 = 0.01**2
        self.p22 = self.params.initial_bias_sigma**2
        self.p01 = self.p02 = self.p12 = 0.0

    def step(self, rotation: np.ndarray, accel: np.ndarray, baro_altitude: float, dt: float) -> float:
        """Predict with the accelerometer (body frame, rotated by ``rotation`` = R(q)) and correct
        with the barometer; returns the height estimate."""
        prm = self.params
        # Vertical acceleration: the third row of R times the specific force, minus gravity.
        vertical = rotation[2, 0] * accel[0] + rotation[2, 1] * accel[1] + rotation[2, 2] * accel[2] - GRAVITY
        half = 0.5 * dt * dt
        a = vertical - self.b
        self.h += self.v * dt + half * a
        self.v += a * dt
        # A = F·P with the rows of F (1, dt, −half), (0, 1, −dt), (0, 0, 1); the upper triangle of
        # F·P·Fᵀ = A·Fᵀ needs only these five entries of A (row 2 of A is row 2 of P).
        a00 = self.p00 + dt * self.p01 - half * self.p02
        a01 = self.p01 + dt * self.p11 - half * self.p12
        a02 = self.p02 + dt * self.p12 - half * self.p22
        a11 = self.p11 - dt * self.p12
        a12 = self.p12 - dt * self.p22
        # P = A·Fᵀ + G·Gᵀ·σ_a² + diag(0, 0, σ_b²·Δt) with G = (half, dt, 0).
        qa = prm.accel_noise * prm.accel_noise
        self.p00 = a00 + dt * a01 - half * a02 + half * half * qa
        self.p01 = a01 - dt * a02 + half * dt * qa
        self.p02 = a02
        self.p11 = a11 - dt * a12 + dt * dt * qa
        self.p12 = a12
        self.p22 = self.p22 + prm.bias_walk * prm.bias_walk * dt
        # Update with the barometer: H = (1, 0, 0), K = P·Hᵀ/s, P ← P − K·H·P.
        innovation = (baro_altitude - self.reference) - self.h
        s = self.p00 + prm.baro_noise * prm.baro_noise
        k0, k1, k2 = self.p00 / s, self.p01 / s, self.p02 / s
        self.h += k0 * innovation
        self.v += k1 * innovation
        self.b += k2 * innovation
        p00, p01, p02 = self.p00, self.p01, self.p02
        self.p00 -= k0 * p00
        self.p01 -= k0 * p01
        self.p02 -= k0 * p02
        self.p11 -= k1 * p01
        self.p12 -= k1 * p02
        self.p22 -= k2 * p02
        return self.h
