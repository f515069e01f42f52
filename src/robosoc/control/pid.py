"""PID controllers of the seed's equations 1–2 (float64 reference model).

Equation 1 (roll α; pitch β and yaw θ alike)::

    u_α = K_p·(α_sp − α) + K_i·∫(α_sp − α)dt + K_d·d/dt(α_sp − α)

Equation 2 (height z)::

    u_z = (K_p·(z_sp − z) + K_i·∫(z_sp − z)dt + K_d·d/dt(z_sp − z) + T_gravity) / (cos α·cos β)

Discretisation (Δt = sensor period): the integral is a forward-Euler sum ``I ← I + e·Δt``
clamped to ±``integral_limit`` (anti-windup); the derivative of the error is supplied by the
caller as ``−(measured rate)``: with piecewise-constant setpoints d/dt(sp − y) = −dy/dt except at
the instants of a step, where the literal derivative would be an impulse ("derivative kick").
The output is clamped to ±``output_limit``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class PidGains:
    """Gains and limits of one PID loop (units: output per unit error, per unit error·s, per unit error/s)."""

    kp: float
    ki: float
    kd: float
    integral_limit: float
    output_limit: float


class Pid:
    """One PID loop with a clamped integral and a clamped output."""

    def __init__(self, gains: PidGains) -> None:
        self.gains = gains
        self.integral = 0.0

    def reset(self) -> None:
        """Zero the integral."""
        self.integral = 0.0

    def step(self, error: float, error_rate: float, dt: float) -> float:
        """Output for ``error`` (setpoint − measurement) and its rate of change, after a step ``dt``."""
        g = self.gains
        self.integral = min(g.integral_limit, max(-g.integral_limit, self.integral + error * dt))
        out = g.kp * error + g.ki * self.integral + g.kd * error_rate
        return min(g.output_limit, max(-g.output_limit, out))


def wrap_angle(angle: float) -> float:
    """Angle in [−π, π)."""
    return (angle + math.pi) % (2.0 * math.pi) - math.pi


def euler_rates(roll: float, pitch: float, body_rate: tuple[float, float, float]) -> tuple[float, float, float]:
    """Z-Y-X Euler angle rates (α̇, β̇, θ̇) from body rates (p, q, r).

    α̇ = p + (q·sin α + r·cos α)·tan β;  β̇ = q·cos α − r·sin α;  θ̇ = (q·sin α + r·cos α)/cos β.
    """
    p, q, r = body_rate
    sa, ca = math.sin(roll), math.cos(roll)
    cb = math.cos(pitch)
    tb = math.tan(pitch)
    return (p + (q * sa + r * ca) * tb, q * ca - r * sa, (q * sa + r * ca) / cb)


def height_thrust(
    pid: Pid,
    error: float,
    error_rate: float,
    dt: float,
    t_gravity: float,
    roll: float,
    pitch: float,
    max_tilt_gain: float,
) -> float:
    """Equation 2: total thrust [N] for a height error, T_gravity and the tilt compensation.

    ``1/(cos α·cos β)`` is limited to ``max_tilt_gain`` so that a large tilt cannot demand
    unbounded thrust.
    """
    tilt = min(max_tilt_gain, 1.0 / max(1e-6, math.cos(roll) * math.cos(pitch)))
    return tilt * (pid.step(error, error_rate, dt) + t_gravity)
