"""Scenario configuration: sensors, wind and the flight plan of one ``robosoc fly`` run.

A scenario TOML file names only the fields it changes; every other field keeps its default,
field by field (see :func:`robosoc.config.validate.from_mapping` and ``docs/scenarios.md``).
Nested tables are merged into the default's tables; a list (``wind.gusts``, ``flight.steps``,
vectors) is replaced as a whole.  All fields, with their defaults::

    name = "default"
    duration_s = 10.0
    seed = 1                 # drives every random number (noise, biases, gusts)
    vehicle = "default"      # or "laser"
    vehicles = 1             # quadrotors in one world (1..16), each with its own chip
    controller = "chip"      # "chip": the firmware on the chip, in lockstep; "host": float64 Python

    [firmware]               # the build and task mapping (robosoc.config.firmware.FirmwareConfig)
    arith = "fixed"
    multiplier = true
    project = ""             # "": the shipped quadrotor project (estimator on (0, 1), PID on (1, 0))
    ...

    [chip]                   # the chip (robosoc.config.chip.ChipConfig): the seed's 2x2, tile (1, 1) off
    width = 2
    height = 2
    powered_off = [[1, 1]]
    ...

    [sensors]
    rate_hz = 100.0          # must divide into whole 1 ms physics steps
    noise = true

    [wind]
    constant = [0.0, 0.0, 0.0]
    gust_sigma = 0.0         # random (seeded) gusts, m/s per axis
    [[wind.gusts]]           # scheduled gusts (the default has this one)
    start_s = 8.5
    duration_s = 1.5
    rise_s = 0.3
    velocity = [3.0, 2.0, 0.0]

    [power]                  # what feeds the motors (robosoc.config.power.PowerConfig, docs/power.md)
    supply = "constant"      # or "battery": the Li-Po pack of [power.battery], and a power budget
    avionics_w = 3.0
    reserve_soc = 0.2
    [power.battery]
    cells = 4
    capacity_ah = 5.0
    initial_soc = 1.0
    ...

    [flight]
    takeoff_s = 3.0
    height_m = 1.0
    climb_s = 1.5            # shortest duration of a height move
    climb_rate_mps = 2.0     # vertical-speed limits of the controller and the height profile
    descent_rate_mps = 1.0
    [[flight.steps]]         # the default has five: roll, pitch and yaw 10° steps
    time_s = 5.0
    axis = "roll"
    value = 10.0             # degrees for roll/pitch/yaw, metres for height
    [flight.mission]         # optional: a waypoint mission after the take-off (then steps = [])
    waypoints = [[2.0, 0.0, 1.0], [2.0, 2.0, 1.0]]   # x, y from the take-off point, z height [m]
    hold_s = 2.0
    acceptance_m = 0.3
    speed_mps = 1.0
    land = true
    land_settle_s = 1.0

    [sensors.position]       # a position fix (mocap-like), sent to a project that declares it
    enabled = false
    rate_hz = 50.0
    position_sigma = 0.02    # m per axis
    velocity_sigma = 0.05    # m/s per axis

The physics step is fixed at :data:`PHYSICS_DT_S` (1 ms); every period in here must be a whole
number of physics steps.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Literal

from robosoc.config.chip import ChipConfig
from robosoc.config.firmware import FirmwareConfig
from robosoc.config.power import PowerConfig
from robosoc.config.ranges import MAX_SEED, check_fields
from robosoc.config.toml_text import to_toml
from robosoc.config.validate import ConfigError
from robosoc.config.vehicle import VEHICLE_PRESETS, VehicleConfig

PHYSICS_DT_S = 0.001
"""The MuJoCo step: 1 ms, as in the seed's Gazebo setup."""

DEFAULT_CLIMB_RATE_MPS = 2.0
"""Default vertical-speed limit upwards [m/s] (PX4's multicopter defaults: 3 up, 1 down)."""
DEFAULT_DESCENT_RATE_MPS = 1.0
"""Default vertical-speed limit downwards [m/s]: slower, a rotor sinking into its own wake loses lift."""
HEIGHT_ACCEL_LIMIT_MPS2 = 3.0
"""Peak vertical acceleration of a height move [m/s²].  Downwards it must stay below what the
motors at their idle thrust allow (g − 4·f_idle/m = 5.3 m/s² for the default vehicle)."""
MIN_HEIGHT_M = 0.3
"""Lowest height setpoint [m] (the body origin rests at 0.18 m)."""
MAX_HEIGHT_M = 5.0
"""Highest height setpoint [m]."""
MAX_ANGLE_DEG = 45.0
"""Largest roll, pitch or yaw setpoint [degrees]."""
MAX_VEHICLES = 16
"""Most quadrotors in one world (each brings its own chip)."""
CONTROLLERS = ("chip", "host")
"""Who flies: the firmware on the chip (lockstep) or the float64 host controller."""
Controller = Literal["chip", "host"]

Vector3 = tuple[float, float, float]


def _require(condition: bool, name: str, reason: str) -> None:
    if not condition:
        raise ValueError(f"{name}: {reason}")


def steps_per_period(rate_hz: float, dt_s: float = PHYSICS_DT_S) -> int | None:
    """Physics steps per period of ``rate_hz``, or ``None`` if it is not a whole number."""
    if not (math.isfinite(rate_hz) and rate_hz > 0):
        return None
    per_step = rate_hz * dt_s  # periods per physics step
    if per_step <= 0 or not math.isfinite(1.0 / per_step):  # a rate so low that its period overflows
        return None
    steps = 1.0 / per_step
    whole = round(steps)
    if whole < 1 or abs(steps - whole) > 1e-9 * max(1.0, steps):
        return None
    return whole


@dataclass(frozen=True)
class PositionSensorConfig:
    """A position fix like a motion-capture system's (or a good RTK GNSS'): the world-frame position
    and velocity of the body origin, ``truth + N(0, sigma)`` per axis, white (no bias), at
    ``rate_hz`` (a whole divisor of the sensor rate: a fix with every n-th sensor sample, the first
    at t = 0).  ``sensors.noise = false`` removes the noise.  Off by default: the I/O tile sends it
    only to a firmware project that declares a message of it (docs/firmware-projects.md); the draws
    come from a stream of their own (:mod:`robosoc.physics.sensors`), so turning it on changes no
    other reading.
    """

    enabled: bool = False
    rate_hz: float = 50.0
    position_sigma: float = 0.02
    velocity_sigma: float = 0.05

    def __post_init__(self) -> None:
        check_fields(self)  # every float finite and in its range (config/ranges.py)


@dataclass(frozen=True)
class SensorConfig:
    """Sensor rate and noise model (quadrotor.md's table).

    Every axis of every sensor reads ``truth + bias + N(0, sigma)``; the bias is drawn once from
    ``N(0, *_bias)`` at reset and decays towards zero with time constant ``bias_tau_s``.
    ``noise = false`` removes both bias and white noise.  Accelerometer and gyroscope are averages over one
    sample period (finite differences of velocity and orientation).
    """

    rate_hz: float = 100.0
    noise: bool = True
    accel_sigma: Vector3 = (0.35, 0.35, 0.3)
    accel_bias: float = 0.1
    gyro_sigma: Vector3 = (0.05, 0.05, 0.015)
    gyro_bias: float = 0.1
    mag_sigma: float = 0.013
    mag_bias: float = 0.0
    baro_sigma: float = 0.1
    baro_bias: float = 10.0
    bias_tau_s: float = 3600.0
    position: PositionSensorConfig = field(default_factory=PositionSensorConfig)

    def __post_init__(self) -> None:
        _require(
            steps_per_period(self.rate_hz) is not None,
            "rate_hz",
            f"{self.rate_hz} Hz is not a whole number of {PHYSICS_DT_S * 1000:g} ms physics steps "
            "(use 1000, 500, 250, 200, 100, 50, ... Hz)",
        )
        for name in ("accel_sigma", "gyro_sigma"):
            values = getattr(self, name)
            _require(all(math.isfinite(v) and v >= 0 for v in values), name, f"must be >= 0, got {values}")
        for name in ("accel_bias", "gyro_bias", "mag_sigma", "mag_bias", "baro_sigma", "baro_bias"):
            value = getattr(self, name)
            _require(math.isfinite(value) and value >= 0, name, f"must be >= 0, got {value}")
        _require(
            math.isfinite(self.bias_tau_s) and self.bias_tau_s > 0,
            "bias_tau_s",
            f"must be positive, got {self.bias_tau_s}",
        )
        ratio = self.rate_hz / self.position.rate_hz
        _require(
            not self.position.enabled
            or (self.position.rate_hz <= self.rate_hz and abs(ratio - round(ratio)) < 1e-9 * ratio),
            "position.rate_hz",
            f"must divide the sensor rate ({self.rate_hz:g} Hz) into whole sensor samples, "
            f"got {self.position.rate_hz:g}",
        )
        check_fields(self)  # and every float in its range (config/ranges.py)

    @property
    def position_every(self) -> int:
        """Sensor samples per position fix."""
        return round(self.rate_hz / self.position.rate_hz)

    @property
    def period_steps(self) -> int:
        """Physics steps per sensor sample."""
        steps = steps_per_period(self.rate_hz)
        assert steps is not None  # checked in __post_init__
        return steps


@dataclass(frozen=True)
class GustConfig:
    """A scheduled gust: wind ramps (half-cosine, ``rise_s``) to ``velocity``, holds, ramps back."""

    start_s: float = 0.0
    duration_s: float = 1.0
    rise_s: float = 0.2
    velocity: Vector3 = (3.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        _require(math.isfinite(self.start_s) and self.start_s >= 0, "start_s", f"must be >= 0, got {self.start_s}")
        _require(
            math.isfinite(self.duration_s) and self.duration_s > 0,
            "duration_s",
            f"must be positive, got {self.duration_s}",
        )
        _require(
            math.isfinite(self.rise_s) and 0 <= 2 * self.rise_s <= self.duration_s,
            "rise_s",
            f"must be >= 0 and at most half of duration_s, got {self.rise_s}",
        )
        _require(
            all(math.isfinite(v) and abs(v) <= 30 for v in self.velocity),
            "velocity",
            f"components must be within ±30 m/s, got {self.velocity}",
        )
        check_fields(self)  # and every float in its range (config/ranges.py)


@dataclass(frozen=True)
class WindConfig:
    """Wind in the world frame: constant + seeded random gusts + scheduled gusts [m/s].

    Random gusts are an Ornstein–Uhlenbeck process per axis with stationary spread
    ``gust_sigma`` and correlation time ``gust_tau_s``, updated every ``update_s``.
    """

    constant: Vector3 = (0.0, 0.0, 0.0)
    gust_sigma: float = 0.0
    gust_tau_s: float = 2.0
    update_s: float = 0.01
    gusts: tuple[GustConfig, ...] = ()

    def __post_init__(self) -> None:
        _require(
            all(math.isfinite(v) and abs(v) <= 30 for v in self.constant),
            "constant",
            f"components must be within ±30 m/s, got {self.constant}",
        )
        _require(
            math.isfinite(self.gust_sigma) and 0 <= self.gust_sigma <= 10,
            "gust_sigma",
            f"must be in [0, 10] m/s, got {self.gust_sigma}",
        )
        _require(
            math.isfinite(self.gust_tau_s) and self.gust_tau_s > 0,
            "gust_tau_s",
            f"must be positive, got {self.gust_tau_s}",
        )
        _require(
            steps_per_period(1.0 / self.update_s if self.update_s > 0 else math.nan) is not None,
            "update_s",
            f"must be a whole number of {PHYSICS_DT_S * 1000:g} ms physics steps, got {self.update_s}",
        )
        check_fields(self)  # and every float in its range (config/ranges.py)

    @property
    def update_steps(self) -> int:
        """Physics steps between wind updates."""
        steps = steps_per_period(1.0 / self.update_s)
        assert steps is not None
        return steps


@dataclass(frozen=True)
class SetpointStep:
    """From ``time_s`` on, the setpoint of ``axis`` is ``value`` (degrees, or metres for height).

    A roll, pitch or yaw step is a step; a height step starts a height move (see
    :class:`FlightPlan`) towards ``value``.
    """

    time_s: float
    axis: Literal["roll", "pitch", "yaw", "height"]
    value: float

    def __post_init__(self) -> None:
        _require(math.isfinite(self.time_s) and self.time_s >= 0, "time_s", f"must be >= 0, got {self.time_s}")
        if self.axis == "height":
            _require(
                math.isfinite(self.value) and MIN_HEIGHT_M <= self.value <= MAX_HEIGHT_M,
                "value",
                f"height must be in [{MIN_HEIGHT_M:g}, {MAX_HEIGHT_M:g}] m, got {self.value}",
            )
        else:
            _require(
                math.isfinite(self.value) and abs(self.value) <= MAX_ANGLE_DEG,
                "value",
                f"{self.axis} must be within ±{MAX_ANGLE_DEG:g} degrees, got {self.value}",
            )
        check_fields(self)  # and every float in its range (config/ranges.py)


@dataclass(frozen=True)
class HeightMove:
    """One height move of a flight plan: from ``from_m`` to ``to_m`` in ``duration_s`` from ``start_s``."""

    start_s: float
    duration_s: float
    from_m: float
    to_m: float

    @property
    def end_s(self) -> float:
        """Time at which the move arrives at ``to_m``."""
        return self.start_s + self.duration_s


def move_duration(delta_m: float, shortest_s: float, climb_rate: float, descent_rate: float) -> float:
    """Duration [s] of a half-cosine height move over ``delta_m`` (up positive).

    The move takes at least ``shortest_s``, and long enough that its peak speed π·|Δ|/(2·T)
    stays within the climb (Δ > 0) or descent rate and its peak acceleration π²·|Δ|/(2·T²)
    within :data:`HEIGHT_ACCEL_LIMIT_MPS2`::

        T = max(shortest_s, π·|Δ|/(2·rate), π·sqrt(|Δ|/(2·a_max)))
    """
    distance = abs(delta_m)
    rate = climb_rate if delta_m > 0 else descent_rate
    by_speed = math.pi * distance / (2.0 * rate)
    by_accel = math.pi * math.sqrt(distance / (2.0 * HEIGHT_ACCEL_LIMIT_MPS2))
    return max(shortest_s, by_speed, by_accel)


MAX_WAYPOINTS = 100
"""Most waypoints of a mission."""
MISSION_RANGE_M = 100.0
"""Largest horizontal offset of a waypoint from the take-off point [m]."""
MISSION_ACCEL_LIMIT_MPS2 = 2.0
"""Peak horizontal acceleration of the mission's setpoint between two waypoints [m/s²] (a tilt of
about 11.5°, well inside the attitude loops' range)."""


@dataclass(frozen=True)
class MissionPlan:
    """A waypoint mission, flown after the take-off climb (docs/scenarios.md, "Missions").

    ``waypoints`` are ``[x, y, z]``: x and y [m] relative to the vehicle's take-off point (its spawn
    position), z the height [m] of the body origin above the ground.  The position setpoint moves
    along a straight line from each point to the next (a half cosine in time whose duration keeps
    within ``speed_mps``, the flight plan's climb and descent rates and
    :data:`MISSION_ACCEL_LIMIT_MPS2`), then holds the waypoint for ``hold_s``.  The schedule is
    fixed in time (:mod:`robosoc.control.mission`), so every build flies the same setpoints; a
    waypoint counts as reached when the vehicle stays within ``acceptance_m`` of it horizontally
    throughout its hold.  With ``land`` the setpoint then descends at the descent rate to below the
    ground under the last waypoint, and the motors are disarmed ``land_settle_s`` after that descent
    ends; the summary says whether, when and where the vehicle landed.
    """

    waypoints: tuple[Vector3, ...]
    hold_s: float = 2.0
    acceptance_m: float = 0.3
    speed_mps: float = 1.0
    land: bool = True
    land_settle_s: float = 1.0

    def __post_init__(self) -> None:
        _require(len(self.waypoints) >= 1, "waypoints", "a mission needs at least one waypoint [x, y, z]")
        _require(
            len(self.waypoints) <= MAX_WAYPOINTS,
            "waypoints",
            f"at most {MAX_WAYPOINTS} waypoints, got {len(self.waypoints)}",
        )
        for i, point in enumerate(self.waypoints):
            _require(len(point) == 3, f"waypoints[{i}]", f"expected [x, y, z], got {list(point)}")
            x, y, z = point
            _require(
                all(isinstance(v, float | int) and not isinstance(v, bool) for v in point),
                f"waypoints[{i}]",
                f"expected three numbers, got {list(point)}",
            )
            _require(
                all(math.isfinite(v) and abs(v) <= MISSION_RANGE_M for v in (x, y)),
                f"waypoints[{i}]",
                f"x and y must be finite and within ±{MISSION_RANGE_M:g} m of the take-off point, got {list(point)}",
            )
            _require(
                math.isfinite(z) and MIN_HEIGHT_M <= z <= MAX_HEIGHT_M,
                f"waypoints[{i}]",
                f"z must be a height in [{MIN_HEIGHT_M:g}, {MAX_HEIGHT_M:g}] m, got {list(point)}",
            )
        _require(math.isfinite(self.hold_s) and self.hold_s >= 0, "hold_s", f"must be >= 0, got {self.hold_s}")
        _require(
            math.isfinite(self.acceptance_m) and self.acceptance_m > 0,
            "acceptance_m",
            f"must be positive, got {self.acceptance_m}",
        )
        _require(
            math.isfinite(self.speed_mps) and self.speed_mps > 0,
            "speed_mps",
            f"must be positive, got {self.speed_mps}",
        )
        _require(
            math.isfinite(self.land_settle_s) and self.land_settle_s >= 0,
            "land_settle_s",
            f"must be >= 0, got {self.land_settle_s}",
        )
        check_fields(self)  # and every float in its range (config/ranges.py)


@dataclass(frozen=True)
class FlightPlan:
    """Setpoints over time: calibrate on the ground, take off, then step the setpoints.

    Until ``takeoff_s`` the motors stay off and the controller calibrates (the vehicle rests on
    flat ground).  The height setpoint then moves from the rest height to ``height_m``, and each
    height step moves it on from the previous target.  Every height move follows a half cosine
    (zero speed at both ends) whose duration is :func:`move_duration`: at least ``climb_s``, and
    long enough that it stays within ``climb_rate_mps`` upwards, ``descent_rate_mps`` downwards
    and :data:`HEIGHT_ACCEL_LIMIT_MPS2`.  The controller limits its commanded vertical speed
    to the same two rates.  ``steps`` change one setpoint each, at their time: attitude steps
    from ``takeoff_s + climb_s`` on, height steps once the previous height move has ended (checked
    by :class:`ScenarioConfig`, which knows the vehicle's rest height).  A ``mission``
    (:class:`MissionPlan`) takes over after the take-off climb; it needs ``steps = []``.
    """

    takeoff_s: float = 3.0
    height_m: float = 1.0
    climb_s: float = 1.5
    climb_rate_mps: float = DEFAULT_CLIMB_RATE_MPS
    descent_rate_mps: float = DEFAULT_DESCENT_RATE_MPS
    steps: tuple[SetpointStep, ...] = ()
    mission: MissionPlan | None = None

    def __post_init__(self) -> None:
        _require(
            math.isfinite(self.takeoff_s) and self.takeoff_s >= 0.1,
            "takeoff_s",
            f"must be >= 0.1 s (the controller calibrates before take-off), got {self.takeoff_s}",
        )
        _require(
            math.isfinite(self.height_m) and MIN_HEIGHT_M <= self.height_m <= MAX_HEIGHT_M,
            "height_m",
            f"must be in [{MIN_HEIGHT_M:g}, {MAX_HEIGHT_M:g}] m, got {self.height_m}",
        )
        _require(math.isfinite(self.climb_s) and self.climb_s >= 0, "climb_s", f"must be >= 0, got {self.climb_s}")
        for name in ("climb_rate_mps", "descent_rate_mps"):
            value = getattr(self, name)
            _require(math.isfinite(value) and 0.1 <= value <= 10.0, name, f"must be in [0.1, 10] m/s, got {value}")
        for i, step in enumerate(self.steps):
            _require(
                step.axis == "height" or step.time_s >= self.attitude_from_s,
                f"steps[{i}].time_s",
                f"must not come before take-off + climb_s ({self.attitude_from_s:g} s), got {step.time_s}",
            )
        _require(
            self.mission is None or not self.steps,
            "steps",
            "must be empty in a flight with a mission (the mission sets the position and height; "
            f"write steps = []), got {len(self.steps)} steps",
        )
        check_fields(self)  # and every float in its range (config/ranges.py)

    @property
    def attitude_from_s(self) -> float:
        """Time from which attitude steps may come and attitude tracking is measured."""
        return self.takeoff_s + self.climb_s

    def height_moves(self, rest_height: float) -> tuple[HeightMove, ...]:
        """The take-off climb from ``rest_height`` and one move per height step, in time order."""
        moves = []
        start, target = self.takeoff_s, self.height_m
        previous = rest_height
        height_steps = sorted((s for s in self.steps if s.axis == "height"), key=lambda s: s.time_s)
        for step in (None, *height_steps):
            if step is not None:
                start, target = step.time_s, step.value
            delta = target - previous
            duration = move_duration(delta, self.climb_s, self.climb_rate_mps, self.descent_rate_mps)
            moves.append(HeightMove(start, duration, previous, target))
            previous = target
        return tuple(moves)


def _default_steps() -> tuple[SetpointStep, ...]:
    return (
        SetpointStep(5.0, "roll", 10.0),
        SetpointStep(6.0, "roll", 0.0),
        SetpointStep(6.5, "pitch", 10.0),
        SetpointStep(7.5, "pitch", 0.0),
        SetpointStep(8.0, "yaw", 10.0),
    )


def _default_wind() -> WindConfig:
    return WindConfig(gusts=(GustConfig(start_s=8.5, duration_s=1.5, rise_s=0.3, velocity=(3.0, 2.0, 0.0)),))


def _default_chip() -> ChipConfig:
    return FirmwareConfig().seed_chip()


@dataclass(frozen=True)
class ScenarioConfig:
    """One flight: duration, seed, vehicles, who flies them (the firmware on which chip, or the host),
    sensors, wind and the flight plan.

    The default is the issue's scenario: calibrate on the ground until 3 s, take off to 1 m, hover,
    roll/pitch/yaw 10° steps, a 3.6 m/s gust, 10 s in total, flown by the fixed-point firmware with
    the multiplier on the seed's 2×2 chip (:meth:`FirmwareConfig.seed_chip`).
    """

    name: str = "default"
    duration_s: float = 10.0
    seed: int = 1
    vehicle: str = "default"
    vehicles: int = 1
    controller: Controller = "chip"
    sensors: SensorConfig = field(default_factory=SensorConfig)
    wind: WindConfig = field(default_factory=_default_wind)
    flight: FlightPlan = field(default_factory=lambda: FlightPlan(steps=_default_steps()))
    firmware: FirmwareConfig = field(default_factory=FirmwareConfig)
    chip: ChipConfig = field(default_factory=_default_chip)
    power: PowerConfig = field(default_factory=PowerConfig)

    def __post_init__(self) -> None:
        _require(
            bool(self.name) and self.name.replace("_", "").replace("-", "").replace(".", "").isalnum(),
            "name",
            f"must be letters, digits, '_', '-' or '.' (it names the run folder), got {self.name!r}",
        )
        _require(
            isinstance(self.seed, int) and 0 <= self.seed <= MAX_SEED,
            "seed",
            f"must be between 0 and 2**63-1, got {self.seed}",
        )
        _require(
            isinstance(self.vehicles, int) and 1 <= self.vehicles <= MAX_VEHICLES,
            "vehicles",
            f"must be between 1 and {MAX_VEHICLES}, got {self.vehicles}",
        )
        _require(
            self.controller in CONTROLLERS,
            "controller",
            f"must be one of {', '.join(map(repr, CONTROLLERS))}, got {self.controller!r}",
        )
        try:
            # a relative project path is the scenario file's to resolve (cli/scenario_flags.py); its
            # tasks are checked when it is loaded to be built
            if not self.firmware.project or Path(self.firmware.project).is_absolute():
                self.firmware.check_chip(self.chip)
        except ConfigError as exc:  # the project file itself (its path and key named)
            raise ValueError(f"firmware.project: {exc}") from exc
        except ValueError as exc:
            raise ValueError(f"firmware.{exc}") from exc
        _require(
            math.isfinite(self.duration_s) and 0 < self.duration_s <= 3600,
            "duration_s",
            f"must be in (0, 3600] s, got {self.duration_s}",
        )
        _require(
            self.vehicle in VEHICLE_PRESETS,
            "vehicle",
            f"unknown vehicle {self.vehicle!r} (known: {', '.join(VEHICLE_PRESETS)})",
        )
        whole = round(self.duration_s / PHYSICS_DT_S)
        _require(
            abs(whole * PHYSICS_DT_S - self.duration_s) < 1e-9,
            "duration_s",
            f"must be a whole number of {PHYSICS_DT_S * 1000:g} ms physics steps, got {self.duration_s}",
        )
        _require(
            self.samples >= 1,
            "duration_s",
            f"a flight lasts at least one sensor period ({1 / self.sensors.rate_hz:g} s at "
            f"{self.sensors.rate_hz:g} Hz), got {self.duration_s:g} s",
        )
        moves = self.flight.height_moves(VEHICLE_PRESETS[self.vehicle]().rest_height)
        height_steps = sorted(
            (i for i, s in enumerate(self.flight.steps) if s.axis == "height"),
            key=lambda i: self.flight.steps[i].time_s,
        )
        for i, previous in zip(height_steps, moves, strict=False):
            _require(
                self.flight.steps[i].time_s >= previous.end_s,
                f"flight.steps[{i}].time_s",
                f"a height step must not come before the previous height move ends ({previous.end_s:g} s), "
                f"got {self.flight.steps[i].time_s}",
            )
        check_fields(self)  # and every float in its range (config/ranges.py)

    def vehicle_config(self) -> VehicleConfig:
        """The preset :attr:`vehicle` with this scenario's :attr:`power` system."""
        preset = VEHICLE_PRESETS[self.vehicle]()
        return preset if self.power == preset.power else dataclasses.replace(preset, power=self.power)

    @property
    def samples(self) -> int:
        """Sensor samples of the flight: one per sensor period in ``duration_s`` (at least one)."""
        return round(self.duration_s * self.sensors.rate_hz)


SCENARIO_HEADER = """\
robosoc scenario: every field, resolved (docs/scenarios.md).
Edit and fly it with: robosoc fly FILE.toml (a file may also name only the fields it changes)."""


def scenario_toml(scenario: ScenarioConfig) -> str:
    """The resolved scenario as TOML, every field (what ``robosoc scenario show`` prints and a run
    folder keeps as ``scenario.toml``); it loads back to an equal scenario."""
    return to_toml(scenario, SCENARIO_HEADER)
