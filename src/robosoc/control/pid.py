"""PID controllers of the seed's equations 1–2 (float64 reference model).

Equation 1 (roll α; pitch β and yaw θ alike)::

    u_α = K_p·(α_sp − α) + K_i·∫(α_sp − α)dt + K_d·d/dt(α_sp − α)

Equation 2 (height z)::

    u_z = (K_p·(z_sp − z) + K_i·∫(z_sp − z)dt + K_d·d/dt(z_sp − z) + T_gravity) / (cos α·cos β)

Discretisation (Δt = sensor period): the integral is a forward-Euler sum ``I ← I + e·Δt``
clamped to ±``integral_limit`` and frozen while |e| > ``integral_band`` (anti-windup).  The
derivative of the error is supplied by the caller.  For the attitude loops it is
``−(measured rate)``: with step setpoints d/dt(sp − y) = −dy/dt except at the instants of a
step, where the literal derivative would be an impulse ("derivative kick").  For height it is
``ż_sp − ż`` with the profile's rate ż_sp.  The output is clamped to ±``output_limit``.

Height control (:class:`HeightController`) writes equation 2 as a position loop feeding a
velocity loop, which is the same law while no limit is reached and lets the commanded vertical
speed be limited (K_p·e + K_d·(ż_sp − ż) = K_d·(ż_cmd − ż) with ż_cmd = ż_sp + (K_p/K_d)·e)::

    e     = z_sp − z
    ż_cmd = clamp(ż_sp + (K_p/K_d)·e, −descent_rate, +climb_rate)     commanded vertical speed
    I     ← clamp(I + e·Δt, ±integral_limit)      only while ż_sp = 0 and |e| ≤ integral_band
    u     = clamp(K_d·(ż_cmd − ż) + K_i·I, ±output_limit)
    u_z   = min(max_tilt_gain, 1/(cos α·cos β)) · (u + m·(g + z̈_sp))

``m·g`` is T_gravity; ``m·z̈_sp`` is the feed-forward of the setpoint profile's acceleration,
so a profile flown exactly needs no error to drive it.  The integral learns only while the
setpoint holds still (hovering) and the error is within ``integral_band`` (0.1 m in the tuned
gains): the lag of the take-off (rotors spinning up from rest), of a climb or of an unshaped step
would otherwise wind it up and make the vehicle overshoot.  A height step of any size is flown at
the commanded speed limit and then approached with time constant K_d/K_p (with the tuned gains
the position and velocity loops form a pair of poles with damping 0.87).
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
    integral_band: float = math.inf
    """The integral learns only while |error| is within this band (integral separation)."""


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
        if abs(error) <= g.integral_band:
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


class HeightController:
    """Equation 2 with the setpoint profile's feed-forward and a commanded vertical-speed limit.

    ``gains.kd`` must be positive: ``K_p/K_d`` [1/s] turns the height error into a commanded
    speed.  ``mass`` [kg] and ``gravity`` [m/s²] give T_gravity = m·g and the acceleration
    feed-forward.  ``climb_rate`` and ``descent_rate`` [m/s] are positive limits of the
    commanded vertical speed up and down.
    """

    def __init__(
        self,
        gains: PidGains,
        mass: float,
        gravity: float,
        climb_rate: float,
        descent_rate: float,
        max_tilt_gain: float,
    ) -> None:
        if not gains.kd > 0.0:
            raise ValueError(f"height.kd: must be positive, got {gains.kd}")
        if not (climb_rate > 0.0 and descent_rate > 0.0):
            raise ValueError(f"climb and descent rates must be positive, got {climb_rate}, {descent_rate}")
        self.gains = gains
        self.mass = mass
        self.gravity = gravity
        self.climb_rate = climb_rate
        self.descent_rate = descent_rate
        self.max_tilt_gain = max_tilt_gain
        self.position_gain = gains.kp / gains.kd
        self.integral = 0.0
        self.speed_command = 0.0

    def reset(self) -> None:
        """Zero the integral."""
        self.integral = 0.0
        self.speed_command = 0.0

    def step(
        self,
        height_setpoint: float,
        rate_setpoint: float,
        accel_setpoint: float,
        height: float,
        velocity: float,
        roll: float,
        pitch: float,
        dt: float,
    ) -> float:
        """Total thrust [N] for the setpoint (height, rate, acceleration) and the estimate
        (height, vertical velocity, roll, pitch), after a step ``dt``."""
        g = self.gains
        error = height_setpoint - height
        wanted = rate_setpoint + self.position_gain * error
        command = min(self.climb_rate, max(-self.descent_rate, wanted))
        if rate_setpoint == 0.0 and abs(error) <= g.integral_band:
            self.integral = min(g.integral_limit, max(-g.integral_limit, self.integral + error * dt))
        self.speed_command = command
        out = g.kd * (command - velocity) + g.ki * self.integral
        out = min(g.output_limit, max(-g.output_limit, out))
        tilt = min(self.max_tilt_gain, 1.0 / max(1e-6, math.cos(roll) * math.cos(pitch)))
        return tilt * (out + self.mass * (self.gravity + accel_setpoint))
