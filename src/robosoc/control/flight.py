"""Closed-loop flight: a controller flies a scenario in the physics world, sample by sample.

The loop runs at the sensor rate: at each sample time t the controller receives the sample taken
at t and the setpoint of the flight plan at t, returns four PWM bytes that the motors hold from t
until the next sample, and the world advances one sensor period.  The host controller has no
compute latency; a controller with latency (the chip) will hold its previous command until its
answer is ready.  Each row of the flight (truth, estimate, setpoint, PWM, wind) goes to the
optional ``on_row`` callback as soon as it exists, so a log survives an interrupted flight.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from robosoc.config.scenario import FlightPlan, ScenarioConfig
from robosoc.config.vehicle import VehicleConfig
from robosoc.control import mission
from robosoc.control import quaternion as quat
from robosoc.control.host import Estimate
from robosoc.control.setpoint import Setpoint, setpoint_at
from robosoc.physics import SensorSample, Truth, World
from robosoc.physics.clock import FlightClock

SAMPLE_FIELDS = (
    "gyro_x", "gyro_y", "gyro_z", "accel_x", "accel_y", "accel_z", "mag_x", "mag_y", "mag_z",
    "baro_altitude", "baro_pressure",
)  # fmt: skip
"""Columns of the sensor sample in a flight row: rad/s, m/s², unit field, m, hPa (body frame FLU)."""

ROW_FIELDS = (
    "t",
    "x",
    "y",
    "z",
    "roll",
    "pitch",
    "yaw",
    "qw",
    "qx",
    "qy",
    "qz",
    "est_roll",
    "est_pitch",
    "est_yaw",
    "est_qw",
    "est_qx",
    "est_qy",
    "est_qz",
    "est_height",
    "sp_roll",
    "sp_pitch",
    "sp_yaw",
    "sp_height",
    "armed",
    "pwm0",
    "pwm1",
    "pwm2",
    "pwm3",
    "wind_x",
    "wind_y",
    "wind_z",
    # what the controller was given, so that a log can be replayed into firmware
    "sp_height_rate",
    "sp_height_accel",
    *SAMPLE_FIELDS,
)
"""Columns of one flight row (angles in radians, lengths in metres, time in seconds); the last
ones are the sensor sample the controller received (:data:`SAMPLE_FIELDS`)."""


OVERSHOOT_WINDOW_S = 1.0
"""How long after a height move its overshoot is looked for [s]: the height loop approaches a
target with time constant K_d/K_p = 0.4 s, so an overshoot peaks well within this."""


class Controller(Protocol):
    """Anything that turns sensor samples and setpoints into PWM bytes."""

    def reset(self) -> None:
        """Start a new flight."""

    def step(self, sample: SensorSample, setpoint: Setpoint) -> Sequence[int]:
        """PWM bytes to apply from ``sample.time`` on."""

    @property
    def estimate(self) -> Estimate:
        """The controller's current state estimate."""


def fly(
    scenario: ScenarioConfig,
    vehicle: VehicleConfig,
    controller: Controller,
    on_row: Callable[[np.ndarray], None] | None = None,
    on_sample: Callable[[World, int], None] | None = None,
) -> np.ndarray:
    """Fly ``scenario`` and return the flight as an array with the columns :data:`ROW_FIELDS`.

    Args:
        scenario: duration, sensors, wind and flight plan.
        vehicle: the vehicle flown (its spawn pose is used as is).
        controller: the flight controller.
        on_row: called with each row as soon as it is computed (logging).
        on_sample: called with the world and the sample index after each row (progress, video).

    """
    clock = FlightClock.of(scenario)
    world = World([vehicle], scenario.sensors, scenario.wind)
    world.reset(scenario.seed)
    quad = world.quadrotors[0]
    controller.reset()
    rows = np.empty((clock.sample_count, len(ROW_FIELDS)))
    rest = vehicle.rest_height
    for k in clock.samples():
        sample = quad.sensors()
        t = sample.time
        setpoint = setpoint_at(scenario.flight, rest, t)
        pwm = controller.step(sample, setpoint)
        quad.apply_pwm([int(v) for v in pwm])
        row = flight_row(sample, quad.truth(), controller.estimate, setpoint, quad.pwm, world.wind.velocity)
        rows[k] = row
        if on_row is not None:
            on_row(row)
        if on_sample is not None:
            on_sample(world, k)
        for _ in clock.steps(k):
            world.step()
    return rows


def flight_row(
    sample: SensorSample,
    truth: Truth,
    estimate: Estimate,
    setpoint: Setpoint,
    pwm: Sequence[int],
    wind: Sequence[float],
) -> np.ndarray:
    """One row of a flight (columns :data:`ROW_FIELDS`) at the time of ``sample``."""
    return np.concatenate(
        (
            [sample.time],
            truth.position,
            truth.euler,
            truth.quaternion,
            estimate.euler,
            estimate.quaternion,
            [
                estimate.height,
                setpoint.roll,
                setpoint.pitch,
                setpoint.yaw,
                setpoint.height,
                float(setpoint.armed),
            ],
            pwm,
            wind,
            [setpoint.height_rate, setpoint.height_accel],
            sample.gyro,
            sample.accel,
            sample.mag,
            [sample.baro_altitude, sample.baro_pressure],
        )
    )


def column(rows: np.ndarray, name: str) -> np.ndarray:
    """One column of a flight array by name."""
    return rows[:, ROW_FIELDS.index(name)]


@dataclass(frozen=True)
class FlightMetrics:
    """Figures of merit of a flight (angles in degrees, lengths in metres)."""

    hover_rms: float
    """RMS of true height − height setpoint while hovering: from the end of the take-off climb
    (+0.5 s settling) on, leaving out every later height move and 0.5 s after it."""
    hover_max: float
    """Largest |true height − height setpoint| over the same span."""
    overshoot: float
    """Largest excursion of the true height beyond the target of a height move (above it for a
    climb, below it for a descent; 0 if the vehicle never passes it), from the move's start until
    :data:`OVERSHOOT_WINDOW_S` after its end (or the next move's start).  Later excursions are
    hover errors (``hover_max``)."""
    min_pwm_armed: int
    """Lowest PWM count of any motor while armed (-1 if never armed)."""
    tracking_rms: tuple[float, float, float]
    """RMS of true − setpoint roll, pitch, yaw from take-off + ``climb_s`` on (whether or not the
    height is still moving), leaving out 0.5 s after each step of that axis."""
    step_rise: tuple[tuple[str, float, float], ...]
    """(axis, step time, 90 % rise time [s] or nan) for every roll/pitch/yaw step of the plan."""
    ekf_rms: float
    """RMS of the attitude error angle (estimate vs truth) while armed."""
    ekf_max: float
    """Largest attitude error angle while armed."""
    ekf_euler_rms: tuple[float, float, float]
    """RMS of estimated − true roll, pitch, yaw while armed."""
    height_estimate_rms: float
    """RMS of estimated − true height while armed."""


def _rms(values: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.square(values)))) if values.size else math.nan


def _wrap(values: np.ndarray) -> np.ndarray:
    return (values + np.pi) % (2 * np.pi) - np.pi


def flight_metrics(rows: np.ndarray, plan: FlightPlan, rest_height: float, settle_s: float = 0.5) -> FlightMetrics:
    """Hover, overshoot, motor, tracking and estimation figures of a flight array.

    ``rest_height`` is the vehicle's (it fixes the take-off climb of ``plan``).
    """
    t = column(rows, "t")
    z = column(rows, "z")
    moves = plan.height_moves(rest_height)
    hover = t >= moves[0].end_s + settle_s
    for move in moves[1:]:
        hover &= ~((t >= move.start_s - 1e-9) & (t < move.end_s + settle_s))
    if plan.mission is not None:  # the hover ends with the mission's last hold (then it lands)
        hover &= t < mission.timeline(plan, rest_height).holds[-1]
    height_error = z - column(rows, "sp_height")
    overshoot = 0.0
    for i, move in enumerate(moves):
        until = move.end_s + OVERSHOOT_WINDOW_S
        if i + 1 < len(moves):
            until = min(until, moves[i + 1].start_s)
        span = (t >= move.start_s - 1e-9) & (t < until - 1e-9)
        if span.any():
            beyond = z[span] - move.to_m if move.to_m >= move.from_m else move.to_m - z[span]
            overshoot = max(overshoot, float(beyond.max()))
    armed = column(rows, "armed") > 0.5
    pwm = rows[:, [ROW_FIELDS.index(f"pwm{i}") for i in range(4)]]
    tracking = []
    for axis in ("roll", "pitch", "yaw"):
        mask = t >= plan.attitude_from_s
        for step in plan.steps:
            if step.axis == axis:
                mask &= ~((t >= step.time_s - 1e-9) & (t < step.time_s + settle_s))
        err = _wrap(column(rows, axis) - column(rows, f"sp_{axis}"))
        # a mission's attitude setpoints are the firmware's own (its position controller's): none to track
        tracking.append(math.degrees(_rms(err[mask])) if plan.mission is None else math.nan)
    rises = []
    for step in sorted(plan.steps, key=lambda s: s.time_s):
        if step.axis == "height":
            continue
        before = t < step.time_s - 1e-9
        after = t >= step.time_s - 1e-9
        truth = column(rows, step.axis)
        old = float(column(rows, f"sp_{step.axis}")[before][-1]) if before.any() else 0.0
        new = math.radians(step.value)
        rise = math.nan
        if abs(new - old) > 1e-9:
            progress = (truth[after] - old) / (new - old)
            hit = np.nonzero(progress >= 0.9)[0]
            if hit.size:
                rise = float(t[after][hit[0]] - step.time_s)
        rises.append((step.axis, step.time_s, rise))
    q_true = rows[:, [ROW_FIELDS.index(n) for n in ("qw", "qx", "qy", "qz")]]
    q_est = rows[:, [ROW_FIELDS.index(n) for n in ("est_qw", "est_qx", "est_qy", "est_qz")]]
    angle = np.array([quat.angle_between(a, b) for a, b in zip(q_est, q_true, strict=True)])
    euler_err = [
        math.degrees(_rms(_wrap(column(rows, f"est_{axis}") - column(rows, axis))[armed]))
        for axis in ("roll", "pitch", "yaw")
    ]
    return FlightMetrics(
        hover_rms=_rms(height_error[hover]),
        hover_max=float(np.max(np.abs(height_error[hover]))) if hover.any() else math.nan,
        overshoot=overshoot,
        min_pwm_armed=int(pwm[armed].min()) if armed.any() else -1,
        tracking_rms=(tracking[0], tracking[1], tracking[2]),
        step_rise=tuple(rises),
        ekf_rms=math.degrees(_rms(angle[armed])),
        ekf_max=math.degrees(float(np.max(angle[armed]))) if armed.any() else math.nan,
        ekf_euler_rms=(euler_err[0], euler_err[1], euler_err[2]),
        height_estimate_rms=_rms((column(rows, "est_height") - column(rows, "z"))[armed]),
    )
