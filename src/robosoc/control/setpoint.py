"""The controller's setpoint: attitude angles, height and whether the motors may run."""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True, slots=True)
class Setpoint:
    """Desired roll α, pitch β, yaw θ [rad] and height z [m]; ``armed = False`` keeps the motors off."""

    roll: float = 0.0
    pitch: float = 0.0
    yaw: float = 0.0
    height: float = 0.0
    armed: bool = False


def setpoint_at(plan, rest_height: float, t: float) -> Setpoint:
    """The setpoint of a :class:`~robosoc.config.scenario.FlightPlan` at time ``t`` [s].

    Before ``takeoff_s``: disarmed (motors off, controller calibrating).  Then the height
    ramps from ``rest_height`` to ``height_m`` over ``climb_s`` along a half cosine (zero
    speed at both ends); attitude setpoints
    start at zero and each step sets one axis from its time on (degrees → radians).
    """
    if t < plan.takeoff_s - 1e-9:
        return Setpoint(height=rest_height, armed=False)
    if plan.climb_s > 0 and t < plan.takeoff_s + plan.climb_s:
        frac = (t - plan.takeoff_s) / plan.climb_s
        height = rest_height + 0.5 * (1.0 - math.cos(math.pi * frac)) * (plan.height_m - rest_height)
    else:
        height = plan.height_m
    values = {"roll": 0.0, "pitch": 0.0, "yaw": 0.0, "height": height}
    for step in sorted(plan.steps, key=lambda s: s.time_s):
        if step.time_s <= t + 1e-9:
            values[step.axis] = step.value if step.axis == "height" else math.radians(step.value)
    return Setpoint(values["roll"], values["pitch"], values["yaw"], values["height"], armed=True)
