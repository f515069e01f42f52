"""Vehicle configuration: the hector quadrotor's rigid body, collision shape, motors and drag.

Every number comes from ``shared/reference/quadrotor.md`` (the hector_quadrotor model).  Frames:
body FLU (x forward, y left, z up), world x North, y West, z up.  The model is built from these
fields by :mod:`robosoc.physics.mjcf`; nothing about the vehicle is hard-coded elsewhere.

Two presets exist: :func:`default_vehicle` (1.478 kg, sonar merged in) and :func:`laser_vehicle`
(the laser-scanner variant: 1.748 kg, CoM 15 mm below the body origin).  Load a TOML file with
``load_toml(VehicleConfig, path)``; any field left out keeps the default vehicle's value.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Literal

from robosoc.config.power import PowerConfig
from robosoc.config.ranges import check_fields

Vector3 = tuple[float, float, float]


def _require(condition: bool, name: str, reason: str) -> None:
    if not condition:
        raise ValueError(f"{name}: {reason}")


def _finite(values: tuple[float, ...]) -> bool:
    return all(math.isfinite(v) for v in values)


@dataclass(frozen=True)
class MotorConfig:
    """Brushless motor and rotor of one propulsion unit (identical for all four).

    Symbols as in quadrotor.md: ``psi`` flux constant Psi [V·s/rad], ``j_m`` rotor inertia J_M
    [kg·m²], ``r_a`` armature resistance R_A [Ω], ``k_t`` thrust-to-drag-torque coefficient
    [N·m/N], ``k_m`` friction coefficient [N·m·s/rad] (negative in the original: it makes an
    idle rotor spin up), ``alpha_m``/``beta_m`` the current model's constants, ``ct0s``/``ct1s``/
    ``ct2s`` the thrust polynomial in ω and axial inflow, ``supply_voltage`` V_s [V].
    """

    psi: float = 0.007242179827506
    j_m: float = 2.573048063300000e-5
    r_a: float = 0.201084219222241
    k_t: float = 0.015336864714397
    k_m: float = -7.011631909766668e-5
    alpha_m: float = 0.104863758313889
    beta_m: float = 0.549262344777900
    ct0s: float = 1.538190483976698e-5
    ct1s: float = -2.5224e-4
    ct2s: float = 0.0
    supply_voltage: float = 14.8

    def __post_init__(self) -> None:
        for name in ("psi", "j_m", "r_a", "alpha_m", "beta_m", "ct0s", "supply_voltage"):
            value = getattr(self, name)
            _require(math.isfinite(value) and value > 0, name, f"must be a positive number, got {value}")
        for name in ("k_t", "k_m", "ct1s", "ct2s"):
            _require(math.isfinite(getattr(self, name)), name, "must be finite")
        _require(self.k_t >= 0, "k_t", f"must be >= 0, got {self.k_t}")
        check_fields(self)  # and every float in its range (config/ranges.py)


@dataclass(frozen=True)
class DragConfig:
    """Quadratic aerodynamic drag: force ``C_w·|v_rel|·v_rel`` and torque ``C_m·|ω|·ω`` (body frame)."""

    c_wxy: float = 0.12
    c_wz: float = 0.1
    c_mxy: float = 0.074156208
    c_mz: float = 0.050643264

    def __post_init__(self) -> None:
        for name in ("c_wxy", "c_wz", "c_mxy", "c_mz"):
            value = getattr(self, name)
            _require(math.isfinite(value) and value >= 0, name, f"must be >= 0, got {value}")
        check_fields(self)  # and every float in its range (config/ranges.py)


@dataclass(frozen=True)
class VehicleConfig:
    """One quadrotor: rigid body, collision geometry, spawn pose, motors and drag.

    Lengths in metres, mass in kg, inertia in kg·m² (principal axes = body axes), angles in degrees.
    ``com`` is the centre of mass in the body frame; the propulsion and drag wrenches act at the
    body origin and are moved to the CoM by the physics.  ``name`` prefixes every MuJoCo element of
    this vehicle, so several vehicles with distinct names can share one world.

    ``idle_pwm`` is the lowest PWM count the flight controller commands to any motor while armed
    (on the ground after arming and in the air): its mixer never goes below it.  This motor model
    holds a rotor at its free-spinning speed (297 rad/s, 1.36 N) even at PWM 0, and its thrust
    rises only slowly over the first counts, so a motor commanded below a few tens of counts
    gives no usable differential thrust: attitude control loses its authority.  50 counts give
    1.67 N per rotor in steady state (46 % of the default vehicle's hover thrust; four of them
    still let it sink at up to 5.3 m/s²).

    ``power`` is what feeds the motors (:mod:`robosoc.config.power`): the presets keep the
    published constant 14.8 V; a scenario's ``[power]`` table is put on its preset
    (:meth:`robosoc.config.scenario.ScenarioConfig.vehicle_config`).
    """

    name: str = "quad"
    variant: Literal["default", "laser"] = "default"
    mass: float = 1.478
    inertia: Vector3 = (0.01152, 0.01152, 0.0218)
    com: Vector3 = (0.0, 0.0, 0.0)
    arm_length: float = 0.275
    skid_half_length: float = 0.11
    skid_offset_y: float = 0.09
    skid_bottom_z: float = -0.1825
    skid_radius: float = 0.005
    body_half_extents: Vector3 = (0.075, 0.075, 0.04)
    spawn_position: Vector3 = (0.0, 0.0, 0.3)
    spawn_yaw_deg: float = 0.0
    motor: MotorConfig = field(default_factory=MotorConfig)
    drag: DragConfig = field(default_factory=DragConfig)
    idle_pwm: int = 50
    power: PowerConfig = field(default_factory=PowerConfig)

    def __post_init__(self) -> None:
        _require(
            bool(self.name) and self.name.replace("_", "").replace("-", "").isalnum(),
            "name",
            f"must be a non-empty identifier (letters, digits, _ or -), got {self.name!r}",
        )
        _require(math.isfinite(self.mass) and self.mass > 0, "mass", f"must be positive, got {self.mass}")
        _require(
            _finite(self.inertia) and all(v > 0 for v in self.inertia),
            "inertia",
            f"all three principal moments must be positive, got {self.inertia}",
        )
        ixx, iyy, izz = self.inertia
        _require(
            ixx + iyy >= izz and iyy + izz >= ixx and ixx + izz >= iyy,
            "inertia",
            f"violates the triangle inequality of a rigid body: {self.inertia}",
        )
        _require(
            _finite(self.com) and max(abs(c) for c in self.com) < 0.2,
            "com",
            f"must lie within 0.2 m of the body origin, got {self.com}",
        )
        _require(
            math.isfinite(self.arm_length) and 0.05 <= self.arm_length <= 2.0,
            "arm_length",
            f"must be in [0.05, 2] m, got {self.arm_length}",
        )
        for name in ("skid_half_length", "skid_offset_y", "skid_radius"):
            value = getattr(self, name)
            _require(math.isfinite(value) and value > 0, name, f"must be positive, got {value}")
        _require(
            math.isfinite(self.skid_bottom_z) and self.skid_bottom_z < 0,
            "skid_bottom_z",
            f"must be below the body origin (negative), got {self.skid_bottom_z}",
        )
        _require(
            self.skid_bottom_z + 2 * self.skid_radius < 0,
            "skid_radius",
            "the skid must fit below the body origin",
        )
        _require(
            _finite(self.body_half_extents) and all(v > 0 for v in self.body_half_extents),
            "body_half_extents",
            f"must be positive, got {self.body_half_extents}",
        )
        _require(_finite(self.spawn_position), "spawn_position", "must be finite")
        _require(
            self.spawn_position[2] + self.skid_bottom_z >= 0,
            "spawn_position",
            f"z = {self.spawn_position[2]} puts the skids below the ground (skid_bottom_z = {self.skid_bottom_z})",
        )
        _require(math.isfinite(self.spawn_yaw_deg), "spawn_yaw_deg", "must be finite")
        _require(
            isinstance(self.idle_pwm, int) and 0 <= self.idle_pwm < 255,
            "idle_pwm",
            f"must be a PWM count in [0, 254], got {self.idle_pwm!r}",
        )
        check_fields(self)  # and every float in its range (config/ranges.py)

    @property
    def rest_height(self) -> float:
        """Height of the body origin above flat ground when the vehicle stands on its skids [m]."""
        return -self.skid_bottom_z


def default_vehicle(name: str = "quad", spawn_position: Vector3 = (0.0, 0.0, 0.3)) -> VehicleConfig:
    """The hector quadrotor with the sonar merged in (1.478 kg)."""
    return VehicleConfig(name=name, spawn_position=spawn_position)


def laser_vehicle(name: str = "quad", spawn_position: Vector3 = (0.0, 0.0, 0.3)) -> VehicleConfig:
    """The laser-scanner variant: 1.748 kg, CoM 0.015 m below the origin, larger inertia."""
    return VehicleConfig(
        name=name,
        variant="laser",
        mass=1.748,
        inertia=(0.013931, 0.013957, 0.021988),
        com=(0.0, 0.0, -0.015),
        spawn_position=spawn_position,
    )


VEHICLE_PRESETS = {"default": default_vehicle, "laser": laser_vehicle}


def vehicle_preset(variant: str, name: str = "quad") -> VehicleConfig:
    """The preset vehicle called ``variant`` ("default" or "laser").

    Raises:
        ValueError: ``variant: ...`` for an unknown preset.
    """
    if variant not in VEHICLE_PRESETS:
        raise ValueError(f"variant: unknown vehicle {variant!r} (known: {', '.join(VEHICLE_PRESETS)})")
    return VEHICLE_PRESETS[variant](name=name)
