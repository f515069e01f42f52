"""The mission in time (robosoc.control.mission): leg durations by the documented formula, a setpoint
that starts and stops at rest on each waypoint, the landing and the disarm; and the mission figures
of a flight measured on rows made by hand (waypoint errors, landing detection)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from robosoc.config.scenario import FlightPlan, MissionPlan
from robosoc.control import mission
from robosoc.control.flight import ROW_FIELDS
from robosoc.control.setpoint import setpoint_at

REST = 0.18
SQUARE = ((2.0, 0.0, 1.0), (2.0, 2.0, 1.0), (0.0, 2.0, 1.0), (0.0, 0.0, 1.0))
PLAN = FlightPlan(takeoff_s=2.0, height_m=1.0, mission=MissionPlan(waypoints=SQUARE, hold_s=2.0, speed_mps=1.0))


def test_the_schedule_follows_the_formula() -> None:
    line = mission.timeline(PLAN, REST)
    # take-off climb 0.82 m: max(climb_s 1.5, π·0.82/(2·2), π·sqrt(0.82/6)) = 1.5 s
    assert line.start_s == pytest.approx(3.5)
    # a 2 m side at 1 m/s: π·2/2 = π s (the acceleration bound π·sqrt(2/4) = 2.22 s is shorter)
    for i, leg in enumerate(line.legs):
        assert leg.duration_s == pytest.approx(math.pi)
        assert leg.start_s == pytest.approx(3.5 + i * (math.pi + 2.0))
        assert line.holds[i] == pytest.approx(leg.end_s + 2.0)
    assert line.legs[1].start == SQUARE[0] and line.legs[1].end == SQUARE[1]
    # landing: 1.0 m down to 0.3 m below the rest height at 0.5 m/s: π·1.12/(2·0.5)
    assert line.landing is not None and line.landing.end == (0.0, 0.0, REST - mission.LAND_BELOW_M)
    assert line.landing.duration_s == pytest.approx(math.pi * (1.0 - REST + 0.3) / 1.0)
    assert line.disarm_s == pytest.approx(line.landing.end_s + 1.0) and line.end_s == line.disarm_s
    # a short leg is bounded by the acceleration: 0.5 m at 1 m/s, π·sqrt(0.5/(2·2)) = 1.11 s > π/4
    assert mission.leg_duration((0, 0, 1), (0.5, 0, 1), PLAN, 1.0) == pytest.approx(math.pi * math.sqrt(0.5 / 4))
    assert mission.leg_duration((1, 1, 1), (1, 1, 1), PLAN, 1.0) == 0.0


def test_the_setpoint_rests_at_each_waypoint_and_moves_smoothly_between() -> None:
    line = mission.timeline(PLAN, REST)
    leg = line.legs[0]
    assert mission.position_setpoint(PLAN, REST, 3.0) is None  # still climbing: over the take-off point
    mid = leg.start_s + leg.duration_s / 2
    (x, y, z), (vx, vy, vz), (ax, _, _) = mission.position_setpoint(PLAN, REST, mid)
    assert (x, y, z) == pytest.approx((1.0, 0.0, 1.0))
    assert vx == pytest.approx(1.0) and vy == vz == 0.0  # the peak speed is the speed limit
    assert ax == pytest.approx(0.0, abs=1e-12)
    # the velocity is the derivative of the position (central difference)
    h = 1e-5
    (xa, _, _), _, _ = mission.position_setpoint(PLAN, REST, mid + 0.3 + h)
    (xb, _, _), _, _ = mission.position_setpoint(PLAN, REST, mid + 0.3 - h)
    _, (v, _, _), _ = mission.position_setpoint(PLAN, REST, mid + 0.3)
    assert (xa - xb) / (2 * h) == pytest.approx(v, rel=1e-6)
    for t in (leg.end_s, leg.end_s + 1.0, line.holds[0] - 1e-6):  # held, at rest
        p, v, a = mission.position_setpoint(PLAN, REST, t)
        assert p == pytest.approx(SQUARE[0]) and v == (0.0, 0.0, 0.0) and a == (0.0, 0.0, 0.0)


def test_the_setpoint_heights_and_arming_follow_the_mission() -> None:
    line = mission.timeline(PLAN, REST)
    assert not setpoint_at(PLAN, REST, 1.9).armed
    assert setpoint_at(PLAN, REST, 10.0).height == 1.0 and setpoint_at(PLAN, REST, 10.0).armed
    assert line.landing is not None
    descending = setpoint_at(PLAN, REST, line.landing.start_s + 1.0)
    assert descending.armed and REST < descending.height < 1.0 and descending.height_rate < 0
    assert descending.height_rate >= -mission.LAND_SPEED_MPS - 1e-9
    after = setpoint_at(PLAN, REST, line.disarm_s + 0.01)
    assert not after.armed and after.height == REST
    hover = FlightPlan(takeoff_s=2.0, mission=MissionPlan(waypoints=((1.0, 0.0, 2.0),), land=False))
    assert mission.timeline(hover, REST).disarm_s is None
    assert setpoint_at(hover, REST, 1000.0).armed and setpoint_at(hover, REST, 1000.0).height == 2.0


def _rows(t: np.ndarray, x: np.ndarray, y: np.ndarray, z: np.ndarray) -> np.ndarray:
    rows = np.zeros((len(t), len(ROW_FIELDS)))
    for name, values in (("t", t), ("x", x), ("y", y), ("z", z)):
        rows[:, ROW_FIELDS.index(name)] = values
    return rows


def test_mission_figures_measure_the_holds_and_detect_the_landing() -> None:
    line = mission.timeline(PLAN, REST)
    t = np.round(np.arange(0.0, 30.0, 0.01), 9)
    x, y, z = np.full(len(t), 0.5), np.full(len(t), -0.25), np.full(len(t), 1.0)  # take-off point (0.5, -0.25)
    for leg, leave in zip(line.legs, line.holds, strict=True):  # on each waypoint, 10 cm off in x at one instant
        hold = (t >= leg.end_s) & (t <= leave)
        x[hold], y[hold] = 0.5 + leg.end[0], -0.25 + leg.end[1]
        x[np.nonzero(hold)[0][50]] += 0.10
    assert line.landing is not None
    down = t >= line.landing.start_s + 2.0  # on the ground 2 s into the descent, resting from then on
    z[down] = REST + 0.01
    rows = _rows(t, x, y, z)
    figures = mission.mission_figures(rows, PLAN, REST)
    assert figures["reached"] == 4 and figures["horizontal_error_max_m"] == pytest.approx(0.10)
    first = figures["waypoints"][0]
    assert (first["x"], first["y"], first["z"]) == (2.5, -0.25, 1.0)
    held = np.count_nonzero((t >= line.legs[0].end_s) & (t <= line.holds[0]))
    assert first["horizontal_error_mean_m"] == pytest.approx(0.10 / held)
    assert figures["landed"] is True
    # (the vertical speed is a central difference: the row after the step is the first at rest)
    assert figures["landed_s"] == pytest.approx(line.landing.start_s + 2.0, abs=0.021)
    assert figures["landing_error_m"] == pytest.approx(0.0)
    # acceptance 5 cm: the 10 cm instant fails each waypoint; a flight cut short has no figures
    strict = FlightPlan(takeoff_s=2.0, mission=MissionPlan(waypoints=SQUARE, hold_s=2.0, acceptance_m=0.05))
    assert mission.mission_figures(rows, strict, REST)["reached"] == 0
    short = mission.mission_figures(rows[t < line.holds[1]], PLAN, REST)
    assert short["reached"] == 1 and short["waypoints"][1]["horizontal_error_max_m"] is None
    assert short["landed"] is False and short["landed_s"] is None


def test_a_vehicle_still_falling_or_hovering_low_has_not_landed() -> None:
    line = mission.timeline(PLAN, REST)
    assert line.landing is not None
    t = np.round(np.arange(0.0, 30.0, 0.01), 9)
    zero = np.zeros(len(t))
    hovering = np.where(t >= line.landing.start_s, REST + 0.08, 1.0)  # 8 cm above its rest height
    assert mission.mission_figures(_rows(t, zero, zero, hovering), PLAN, REST)["landed"] is False
    # resting only 0.3 s before bouncing up again, then resting for good from 27 s
    bounce = np.where(t >= line.landing.start_s, REST, 1.0)
    bounce[(t >= line.landing.start_s + 0.3) & (t < 27.0)] = REST + 0.2
    figures = mission.mission_figures(_rows(t, zero, zero, bounce), PLAN, REST)
    assert figures["landed"] is True and figures["landed_s"] == pytest.approx(27.0, abs=0.021)
