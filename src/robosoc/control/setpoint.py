"""The controller's setpoint: attitude angles, the height profile and whether the motors may run.

The flight plan's height moves (:meth:`~robosoc.config.scenario.FlightPlan.height_moves`) are
half cosines.  A move from h₀ to h₁ = h₀ + Δ over T seconds from t₀ gives, with s = (t − t₀)/T::

    h(t) = h₀ + Δ·(1 − cos πs)/2
    ḣ(t) = Δ·π/(2T)·sin πs
    ḧ(t) = Δ·π²/(2T²)·cos πs

and outside the move h = h₁ (after) or h₀ (before), ḣ = ḧ = 0.  The controller receives all
three: ḣ and ḧ are the feed-forward of the profile (see :mod:`robosoc.control.pid`).  A flight
plan with a mission (:mod:`robosoc.control.mission`) takes its height, rate and acceleration from
the mission's setpoint once the take-off climb has ended, and disarms when the mission says.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

from robosoc.config.scenario import FlightPlan, HeightMove
from robosoc.control import mission


@dataclass(frozen=True, slots=True)
class Setpoint:
    """Desired roll α, pitch β, yaw θ [rad], height z [m] with its rate [m/s] and acceleration [m/s²].

    ``armed = False`` keeps the motors off.
    """

    roll: float = 0.0
    pitch: float = 0.0
    yaw: float = 0.0
    height: float = 0.0
    armed: bool = False
    height_rate: float = 0.0
    height_accel: float = 0.0


def move_profile(move: HeightMove, t: float) -> tuple[float, float, float]:
    """Height [m], rate [m/s] and acceleration [m/s²] of ``move`` at time ``t`` [s]."""
    if t <= move.start_s:
        return move.from_m, 0.0, 0.0
    if t >= move.end_s:
        return move.to_m, 0.0, 0.0
    delta = move.to_m - move.from_m
    w = math.pi / move.duration_s
    phase = w * (t - move.start_s)
    return (
        move.from_m + 0.5 * delta * (1.0 - math.cos(phase)),
        0.5 * delta * w * math.sin(phase),
        0.5 * delta * w * w * math.cos(phase),
    )


@functools.lru_cache(maxsize=16)
def _moves(plan: FlightPlan, rest_height: float) -> tuple[HeightMove, ...]:
    return plan.height_moves(rest_height)


def setpoint_at(plan: FlightPlan, rest_height: float, t: float) -> Setpoint:
    """The setpoint of a :class:`~robosoc.config.scenario.FlightPlan` at time ``t`` [s].

    Before ``takeoff_s``: disarmed (motors off, controller calibrating).  Then the height
    follows the plan's height moves, the take-off climb from ``rest_height`` first; attitude
    setpoints start at zero and each step sets one axis from its time on (degrees → radians).
    """
    if t < plan.takeoff_s - 1e-9:
        return Setpoint(height=rest_height, armed=False)
    if plan.mission is not None:
        line = mission.timeline(plan, rest_height)
        if line.disarm_s is not None and t >= line.disarm_s - 1e-9:
            return Setpoint(height=rest_height, armed=False)
        if t >= line.start_s - 1e-9:
            (_, _, height), (_, _, rate), (_, _, accel) = line.at(t)
            return Setpoint(height=height, armed=True, height_rate=rate, height_accel=accel)
    moves = _moves(plan, rest_height)
    current = moves[0]
    for move in moves[1:]:
        if move.start_s <= t + 1e-9:
            current = move
    height, rate, accel = move_profile(current, t)
    values = {"roll": 0.0, "pitch": 0.0, "yaw": 0.0}
    for step in sorted(plan.steps, key=lambda s: s.time_s):
        if step.axis != "height" and step.time_s <= t + 1e-9:
            values[step.axis] = math.radians(step.value)
    return Setpoint(values["roll"], values["pitch"], values["yaw"], height, True, rate, accel)
