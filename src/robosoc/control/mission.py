"""A waypoint mission in time: the position setpoint of each instant, and what a flight achieved.

A scenario's ``[flight.mission]`` (:class:`~robosoc.config.scenario.MissionPlan`) is flown after the
take-off climb of its flight plan, on a schedule fixed in time (:func:`timeline`), so that every
build and every controller is given the same setpoints and is judged by how closely it follows
them:

1. the take-off climb of the flight plan (from the rest height to ``height_m``, over the take-off
   point), then for each waypoint
2. a leg: the setpoint moves on a straight line from the previous point to the waypoint, a half
   cosine in time (zero speed at both ends, like the flight plan's height moves) of duration::

       T = max(π·|Δxy|/(2·speed_mps),  move_duration(Δz),  π·sqrt(|Δ|/(2·a_max)))

   (the horizontal speed limit, the flight plan's climb/descent rates and vertical acceleration
   limit, a_max = :data:`~robosoc.config.scenario.MISSION_ACCEL_LIMIT_MPS2` along the leg);
3. a hold of ``hold_s`` at the waypoint;
4. with ``land``: a descent at min(descent rate, :data:`LAND_SPEED_MPS`) to
   :data:`LAND_BELOW_M` below the rest height (so the vehicle sits on its skids whatever its
   height estimate says), and the motors disarmed ``land_settle_s`` after that descent ends.

Positions are relative to the take-off point (the vehicle's spawn position, where it stands at
t = 0); heights are above the ground.  :func:`mission_figures` measures a flight against the
schedule: per waypoint the horizontal distance from it throughout its hold, and the landing.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from robosoc.config.scenario import MISSION_ACCEL_LIMIT_MPS2, FlightPlan, move_duration

Vector3 = tuple[float, float, float]

LAND_BELOW_M = 0.3
"""How far below the rest height the landing descent aims [m]."""
LAND_SPEED_MPS = 0.5
"""Fastest landing descent [m/s] (touch-down speed stays below it)."""
LANDED_HEIGHT_M = 0.05
"""A vehicle whose body origin is within this of its rest height ... [m]"""
LANDED_SPEED_MPS = 0.1
"""... moving vertically slower than this [m/s] ..."""
LANDED_FOR_S = 0.5
"""... for this long [s] has landed (from the start of the landing descent on)."""


@dataclass(frozen=True)
class Leg:
    """The setpoint moving from ``start`` to ``end`` (relative positions [m]) in ``duration_s`` from ``start_s``."""

    start_s: float
    duration_s: float
    start: Vector3
    end: Vector3

    @property
    def end_s(self) -> float:
        return self.start_s + self.duration_s

    def at(self, t: float) -> tuple[Vector3, Vector3, Vector3]:
        """Position [m], velocity [m/s] and acceleration [m/s²] of the setpoint at ``t`` [s]."""
        if t <= self.start_s or self.duration_s <= 0:
            return (self.start if t <= self.start_s else self.end), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)
        if t >= self.end_s:
            return self.end, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)
        w = math.pi / self.duration_s
        phase = w * (t - self.start_s)
        c, s = math.cos(phase), math.sin(phase)
        d = [e - b for b, e in zip(self.start, self.end, strict=True)]
        p = tuple(b + 0.5 * di * (1.0 - c) for b, di in zip(self.start, d, strict=True))
        v = tuple(0.5 * di * w * s for di in d)
        a = tuple(0.5 * di * w * w * c for di in d)
        return (p[0], p[1], p[2]), (v[0], v[1], v[2]), (a[0], a[1], a[2])


@dataclass(frozen=True)
class Timeline:
    """The mission of a flight plan in time (:func:`timeline`).

    Attributes:
        start_s: end of the take-off climb: the first leg starts here.
        legs: one per waypoint, in order; waypoint i is held from ``legs[i].end_s`` to ``holds[i]``.
        holds: when the hold at each waypoint ends (the next leg starts).
        landing: the landing descent (None without ``land``).
        disarm_s: when the motors are disarmed (None without ``land``).
    """

    start_s: float
    legs: tuple[Leg, ...]
    holds: tuple[float, ...]
    landing: Leg | None
    disarm_s: float | None

    @property
    def end_s(self) -> float:
        """When the mission is over: disarmed after landing, or the last hold's end."""
        return self.disarm_s if self.disarm_s is not None else self.holds[-1]

    def at(self, t: float) -> tuple[Vector3, Vector3, Vector3]:
        """Relative position, velocity and acceleration of the setpoint at ``t`` (from ``start_s`` on)."""
        current = self.legs[0]
        for leg in (*self.legs[1:], *((self.landing,) if self.landing is not None else ())):
            if leg.start_s <= t + 1e-9:
                current = leg
        return current.at(t)


def leg_duration(start: Vector3, end: Vector3, plan: FlightPlan, speed_mps: float) -> float:
    """Duration [s] of a leg (the module docstring's T)."""
    dx, dy, dz = (e - b for b, e in zip(start, end, strict=True))
    horizontal = math.hypot(dx, dy)
    distance = math.sqrt(horizontal * horizontal + dz * dz)
    if distance == 0.0:
        return 0.0
    return max(
        math.pi * horizontal / (2.0 * speed_mps),
        move_duration(dz, 0.0, plan.climb_rate_mps, plan.descent_rate_mps),
        math.pi * math.sqrt(distance / (2.0 * MISSION_ACCEL_LIMIT_MPS2)),
    )


@functools.lru_cache(maxsize=16)
def timeline(plan: FlightPlan, rest_height: float) -> Timeline:
    """The schedule of ``plan.mission`` for a vehicle resting at ``rest_height``.

    Raises:
        ValueError: the plan has no mission.
    """
    mission = plan.mission
    if mission is None:
        raise ValueError("mission: the flight plan has none")
    climb = plan.height_moves(rest_height)[0]
    t = climb.end_s
    start_s = t
    point: Vector3 = (0.0, 0.0, plan.height_m)
    legs, holds = [], []
    for waypoint in mission.waypoints:
        end: Vector3 = (float(waypoint[0]), float(waypoint[1]), float(waypoint[2]))
        leg = Leg(t, leg_duration(point, end, plan, mission.speed_mps), point, end)
        legs.append(leg)
        t = leg.end_s + mission.hold_s
        holds.append(t)
        point = end
    landing = disarm = None
    if mission.land:
        ground: Vector3 = (point[0], point[1], rest_height - LAND_BELOW_M)
        landing_plan = _landing_plan(plan)
        landing = Leg(t, leg_duration(point, ground, landing_plan, mission.speed_mps), point, ground)
        disarm = landing.end_s + mission.land_settle_s
    return Timeline(start_s, tuple(legs), tuple(holds), landing, disarm)


def _landing_plan(plan: FlightPlan) -> FlightPlan:
    """The plan's rates with the descent slowed to :data:`LAND_SPEED_MPS` at most."""
    import dataclasses

    return dataclasses.replace(plan, descent_rate_mps=min(plan.descent_rate_mps, LAND_SPEED_MPS), steps=())


def position_setpoint(plan: FlightPlan, rest_height: float, t: float) -> tuple[Vector3, Vector3, Vector3] | None:
    """Relative position, velocity and acceleration of the mission's setpoint at ``t``, or None
    before the mission starts (or without a mission): the setpoint then holds the take-off point."""
    if plan.mission is None:
        return None
    line = timeline(plan, rest_height)
    if t < line.start_s - 1e-9:
        return None
    return line.at(t)


# --- what a flight achieved ---------------------------------------------------------------------


def _landed(t: np.ndarray, z: np.ndarray, rest_height: float, start_s: float) -> int | None:
    """Index of the first row from ``start_s`` on from which the vehicle rests for LANDED_FOR_S."""
    if len(t) < 2:
        return None
    dt = float(t[1] - t[0])
    speed = np.abs(np.gradient(z, dt))
    resting = (np.abs(z - rest_height) <= LANDED_HEIGHT_M) & (speed <= LANDED_SPEED_MPS) & (t >= start_s - 1e-9)
    run = max(1, round(LANDED_FOR_S / dt))
    count = 0
    for i in range(len(t)):
        count = count + 1 if resting[i] else 0
        if count >= run:
            return i - run + 1
    return None


def mission_figures(rows: np.ndarray, flight: FlightPlan, rest_height: float) -> dict[str, Any]:
    """The ``mission`` figures of a flight (rows with the columns of
    :data:`robosoc.control.flight.ROW_FIELDS`): per waypoint its absolute position, its hold
    window, the largest and mean horizontal distance of the vehicle from it during the hold and the
    largest height error, and whether it was reached (the hold flown, the distance within
    ``acceptance_m`` throughout); and whether, when and where the vehicle landed.  A hold the flight
    did not reach the end of has no figures (None) and is not reached.

    Raises:
        ValueError: ``flight`` has no mission.
    """
    from robosoc.control.flight import column

    mission = flight.mission
    if mission is None:
        raise ValueError("mission: the flight plan has none")
    line = timeline(flight, rest_height)
    t = column(rows, "t")
    x, y, z = column(rows, "x"), column(rows, "y"), column(rows, "z")
    x0, y0 = (float(x[0]), float(y[0])) if len(rows) else (0.0, 0.0)
    last_t = float(t[-1]) if len(rows) else -math.inf
    waypoints = []
    for leg, leave in zip(line.legs, line.holds, strict=True):
        wx, wy, wz = x0 + leg.end[0], y0 + leg.end[1], leg.end[2]
        window = (t >= leg.end_s - 1e-9) & (t <= leave + 1e-9)
        flown = last_t >= leave - 1e-9 and bool(window.any())
        distance = np.hypot(x[window] - wx, y[window] - wy) if flown else np.empty(0)
        worst = float(distance.max()) if flown else None
        waypoints.append(
            {
                "x": wx, "y": wy, "z": wz, "arrive_s": leg.end_s, "leave_s": leave,
                "horizontal_error_max_m": worst,
                "horizontal_error_mean_m": float(distance.mean()) if flown else None,
                "height_error_max_m": float(np.abs(z[window] - wz).max()) if flown else None,
                "reached": worst is not None and worst <= mission.acceptance_m,
            }
        )  # fmt: skip
    figures: dict[str, Any] = {
        "waypoints": waypoints,
        "reached": sum(w["reached"] for w in waypoints),
        "acceptance_m": mission.acceptance_m,
        "horizontal_error_max_m": max(
            (w["horizontal_error_max_m"] for w in waypoints if w["horizontal_error_max_m"] is not None), default=None
        ),
    }
    if line.landing is not None:
        i = _landed(t, z, rest_height, line.landing.start_s)
        last = waypoints[-1]
        figures["landed"] = i is not None
        figures["landed_s"] = float(t[i]) if i is not None else None
        figures["landed_x"] = float(x[i]) if i is not None else None
        figures["landed_y"] = float(y[i]) if i is not None else None
        figures["landing_error_m"] = float(math.hypot(x[i] - last["x"], y[i] - last["y"])) if i is not None else None
    return figures


__all__ = [
    "LANDED_FOR_S",
    "LANDED_HEIGHT_M",
    "LANDED_SPEED_MPS",
    "LAND_BELOW_M",
    "LAND_SPEED_MPS",
    "Leg",
    "Timeline",
    "leg_duration",
    "mission_figures",
    "position_setpoint",
    "timeline",
]
