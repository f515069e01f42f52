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
    """Height and vertical velocity from barometer altitude and vertical specific force."""

    def __init__(self, params: AltitudeParams | None = None) -> None:
        self.params = params or AltitudeParams()
        self.reference = 0.0
        self.x = np.zeros(3)
        self.P = np.eye(3)

    @property
    def height(self) -> float:
        """Estimated height of the body origin above the ground [m]."""
        return float(self.x[0])

    @property
    def velocity(self) -> float:
        """Estimated vertical velocity [m/s] (up positive)."""
        return float(self.x[1])

    def reset(self, baro_ground: float, rest_height: float) -> None:
        """Calibrate: ``baro_ground`` is the mean barometer altitude while resting at ``rest_height``."""
        self.reference = baro_ground - rest_height
        self.x = np.array([rest_height, 0.0, 0.0])
        self.P = np.diag([self.params.baro_noise**2, 0.01**2, self.params.initial_bias_sigma**2])

    def step(self, rotation: np.ndarray, accel: np.ndarray, baro_altitude: float, dt: float) -> float:
        """Predict with the accelerometer (body frame, rotated by ``rotation`` = R(q)) and correct
        with the barometer; returns the height estimate."""
        p = self.params
        vertical = float(rotation[2] @ accel) - GRAVITY
        h, v, b = self.x
        a = vertical - b
        self.x = np.array([h + v * dt + 0.5 * a * dt * dt, v + a * dt, b])
        f = np.array([[1.0, dt, -0.5 * dt * dt], [0.0, 1.0, -dt], [0.0, 0.0, 1.0]])
        g = np.array([0.5 * dt * dt, dt, 0.0])
        self.P = f @ self.P @ f.T + np.outer(g, g) * p.accel_noise**2 + np.diag([0.0, 0.0, p.bias_walk**2 * dt])
        innovation = (baro_altitude - self.reference) - self.x[0]
        s = self.P[0, 0] + p.baro_noise**2
        gain = self.P[:, 0] / s
        self.x = self.x + gain * innovation
        self.P = self.P - np.outer(gain, self.P[0, :])
        return self.height
