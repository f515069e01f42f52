"""Wind in the world frame: constant + seeded random gusts + scheduled gusts.

Random gusts are an Ornstein–Uhlenbeck process per axis, advanced with its exact discretisation
``g ← φ·g + σ·sqrt(1 − φ²)·n`` (φ = exp(−Δt/τ), n ~ N(0, 1)) every ``update_s``; it starts in its
stationary distribution.  A scheduled gust ramps up over ``rise_s`` along a half cosine, holds its
velocity and ramps down over the last ``rise_s`` of its duration.  The wind is held constant
between updates (piecewise constant over ``update_s``, 10 ms by default).
"""

from __future__ import annotations

import math

import numpy as np

from robosoc.config.scenario import GustConfig, WindConfig


def gust_profile(gust: GustConfig, t: float) -> float:
    """Scale 0..1 of a scheduled gust at time ``t`` [s]."""
    local = t - gust.start_s
    if local <= 0.0 or local >= gust.duration_s:
        return 0.0
    rise = gust.rise_s
    if rise <= 0.0:
        return 1.0
    if local < rise:
        return 0.5 * (1.0 - math.cos(math.pi * local / rise))
    remaining = gust.duration_s - local
    if remaining < rise:
        return 0.5 * (1.0 - math.cos(math.pi * remaining / rise))
    return 1.0


class Wind:
    """The wind field shared by every vehicle of a world."""

    def __init__(self, config: WindConfig, dt: float) -> None:
        self.config = config
        self.update_dt = config.update_steps * dt
        self._phi = math.exp(-self.update_dt / config.gust_tau_s)
        self._drive = config.gust_sigma * math.sqrt(1.0 - self._phi * self._phi)
        self._random = np.zeros(3)
        self._rng = np.random.default_rng(0)
        self.velocity: tuple[float, float, float] = config.constant

    def reset(self, rng: np.random.Generator) -> None:
        """Draw the random gust state from ``rng`` (stationary start) and evaluate the wind at t = 0."""
        self._rng = rng
        if self.config.gust_sigma > 0:
            self._random = self.config.gust_sigma * rng.standard_normal(3)
        else:
            self._random = np.zeros(3)
        self.update(0.0, advance=False)

    def update(self, t: float, advance: bool = True) -> tuple[float, float, float]:
        """Advance the random gusts by one update period (if ``advance``) and evaluate the wind at ``t``."""
        config = self.config
        if advance and config.gust_sigma > 0:
            self._random = self._phi * self._random + self._drive * self._rng.standard_normal(3)
        wx, wy, wz = config.constant
        rx, ry, rz = self._random.tolist()
        wx += rx
        wy += ry
        wz += rz
        for gust in config.gusts:
            scale = gust_profile(gust, t)
            if scale:
                gx, gy, gz = gust.velocity
                wx += scale * gx
                wy += scale * gy
                wz += scale * gz
        self.velocity = (wx, wy, wz)
        return self.velocity
