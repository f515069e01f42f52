"""Scenario configuration: sensors, wind and the flight plan of one ``robosoc fly`` run.

A scenario TOML file holds any subset of these fields (the rest keep their defaults)::

    name = "gusty"
    duration_s = 12.0
    vehicle = "laser"

    [sensors]
    rate_hz = 100.0          # must divide into whole 1 ms physics steps
    noise = true

    [wind]
    constant = [1.0, 0.0, 0.0]
    gust_sigma = 0.5         # random (seeded) gusts, m/s per axis
    [[wind.gusts]]           # scheduled gusts
    start_s = 8.0
    duration_s = 1.0
    velocity = [3.0, 0.0, 0.0]

    [flight]
    takeoff_s = 1.0
    height_m = 1.0
    [[flight.steps]]
    time_s = 4.0
    axis = "roll"
    value = 10.0             # degrees for roll/pitch/yaw, metres for height

The physics step is fixed at :data:`PHYSICS_DT_S` (1 ms); every period in here must be a whole
number of physics steps.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Literal

from robosoc.config.vehicle import VEHICLE_PRESETS

PHYSICS_DT_S = 0.001
"""The MuJoCo step: 1 ms, as in the seed's Gazebo setup."""

Vector3 = tuple[float, float, float]


def _require(condition: bool, name: str, reason: str) -> None:
    if not condition:
        raise ValueError(f"{name}: {reason}")


def steps_per_period(rate_hz: float, dt_s: float = PHYSICS_DT_S) -> int | None:
    """Physics steps per period of ``rate_hz``, or ``None`` if it is not a whole number."""
    if not (math.isfinite(rate_hz) and rate_hz > 0):
        return None
    steps = 1.0 / (rate_hz * dt_s)
    whole = round(steps)
    if whole < 1 or abs(steps - whole) > 1e-9 * max(1.0, steps):
        return None
    return whole


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

    @property
    def update_steps(self) -> int:
        """Physics steps between wind updates."""
        steps = steps_per_period(1.0 / self.update_s)
        assert steps is not None
        return steps


@dataclass(frozen=True)
class SetpointStep:
    """From ``time_s`` on, the setpoint of ``axis`` is ``value`` (degrees, or metres for height)."""

    time_s: float
    axis: Literal["roll", "pitch", "yaw", "height"]
    value: float

    def __post_init__(self) -> None:
        _require(math.isfinite(self.time_s) and self.time_s >= 0, "time_s", f"must be >= 0, got {self.time_s}")
        limit = 5.0 if self.axis == "height" else 45.0
        if self.axis == "height":
            _require(0 < self.value <= 5.0, "value", f"height must be in (0, 5] m, got {self.value}")
        else:
            _require(
                math.isfinite(self.value) and abs(self.value) <= limit,
                "value",
                f"{self.axis} must be within ±{limit:g} degrees, got {self.value}",
            )


@dataclass(frozen=True)
class FlightPlan:
    """Setpoints over time: calibrate on the ground, take off, then step the setpoints.

    Until ``takeoff_s`` the motors stay off and the controller calibrates (the vehicle rests on
    flat ground).  The height setpoint then ramps from the rest height to ``height_m`` over
    ``climb_s`` (half-cosine profile).  ``steps`` change one setpoint each, at their time.
    """

    takeoff_s: float = 3.0
    height_m: float = 1.0
    climb_s: float = 1.5
    steps: tuple[SetpointStep, ...] = ()

    def __post_init__(self) -> None:
        _require(
            math.isfinite(self.takeoff_s) and self.takeoff_s >= 0.1,
            "takeoff_s",
            f"must be >= 0.1 s (the controller calibrates before take-off), got {self.takeoff_s}",
        )
        _require(
            math.isfinite(self.height_m) and 0.3 <= self.height_m <= 5.0,
            "height_m",
            f"must be in [0.3, 5] m, got {self.height_m}",
        )
        _require(math.isfinite(self.climb_s) and self.climb_s >= 0, "climb_s", f"must be >= 0, got {self.climb_s}")
        for i, step in enumerate(self.steps):
            _require(
                step.time_s >= self.takeoff_s + self.climb_s,
                f"steps[{i}].time_s",
                f"must not come before the climb ends ({self.takeoff_s + self.climb_s:g} s), got {step.time_s}",
            )

    @property
    def hover_from_s(self) -> float:
        """Time at which the climb ends and the vehicle should hover at ``height_m``."""
        return self.takeoff_s + self.climb_s


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


@dataclass(frozen=True)
class ScenarioConfig:
    """One flight: duration, vehicle preset, sensors, wind and the flight plan.

    The default is the issue's scenario: calibrate 1 s on the ground, take off to 1 m, hover,
    roll/pitch/yaw 10° steps, a 3.6 m/s gust, 10 s in total.
    """

    name: str = "default"
    duration_s: float = 10.0
    vehicle: str = "default"
    sensors: SensorConfig = field(default_factory=SensorConfig)
    wind: WindConfig = field(default_factory=_default_wind)
    flight: FlightPlan = field(default_factory=lambda: FlightPlan(steps=_default_steps()))

    def __post_init__(self) -> None:
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
