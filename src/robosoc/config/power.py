"""The vehicle's power system: what feeds the motors (a constant voltage or a Li-Po pack), the rest
of the avionics, and the reserve an endurance estimate stops at (docs/power.md).

``supply = "constant"`` (the default) is the hector model as published: the motors see
:attr:`robosoc.config.vehicle.MotorConfig.supply_voltage` (14.8 V) whatever they draw, and a flight
keeps no power budget.  ``supply = "battery"`` feeds them from the pack of :class:`BatteryConfig`:
the motors' supply is the pack's terminal voltage under load, the pack discharges, and the flight
keeps one power budget (motors, chip, rest of the avionics).

The pack follows Tremblay's battery model (O. Tremblay, L.-A. Dessaint, A.-I. Dekkiche, "A generic
battery model for the dynamic simulation of hybrid electric vehicles", IEEE VPPC 2007; the
Li-ion parameters validated in O. Tremblay, L.-A. Dessaint, "Experimental validation of a battery
dynamic model for EV applications", World Electric Vehicle Journal 3, 2009), a Shepherd model
without temperature, per cell::

    E(it) = E0 - K·Q/(Q - it) + A·exp(-B·it)       open-circuit voltage, it = charge drawn [Ah]
    V     = E(it) - R·i                             terminal voltage at current i [A]

Its four constants come from three points of a datasheet discharge curve by Tremblay's extraction
(:meth:`BatteryConfig.tremblay`): the fully charged voltage, the end of the exponential zone and
the end of the nominal zone, read at the curve's current.  The defaults describe a typical Li-Po
cell (assumed, not a particular datasheet): 4.2 V full, 4.05 V at 5 % of the capacity drawn,
3.7 V at 90 %, read at 0.2 C, 4 mΩ, cut off at 3.0 V; 4 cells of 5 Ah (a 4S 5000 mAh pack, 14.8 V
nominal: the hector model's supply voltage).  The pack's mass is taken to be in the vehicle's.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Literal, NamedTuple, get_args

from robosoc.config.ranges import check_fields

Supply = Literal["constant", "battery"]
SUPPLIES: tuple[Supply, ...] = get_args(Supply)


FAILSAFE_LAND_RATE_MPS = 0.5
"""The low-battery failsafe's vertical speed, climbing to its hover height or landing [m/s] (assumed:
half the controller's descent limit, a gentle touchdown)."""
FAILSAFE_LANDED_MARGIN_M = 0.05
"""The failsafe disarms once the estimated height is within this of the resting height [m]; its
height setpoint stops as far below the resting height, so that the vehicle does settle."""


def _require(condition: bool, name: str, reason: str) -> None:
    if not condition:
        raise ValueError(f"{name}: {reason}")


class TremblayConstants(NamedTuple):
    """One cell's constants of Tremblay's model: E0 [V], K [V], A [V], B [1/Ah], Q [Ah], R [Ω]."""

    e0: float
    k: float
    a: float
    b: float
    q: float
    r: float


@dataclass(frozen=True)
class BatteryConfig:
    """A Li-Po pack: ``cells`` identical cells in series, each described by its discharge curve.

    Attributes:
        cells: cells in series (the pack's voltage is ``cells`` times a cell's).
        capacity_ah: rated capacity Q of a cell (= of the pack) [Ah].
        full_v: a cell's voltage when fully charged, at ``curve_c`` (the curve's first point) [V].
        exp_v, exp_fraction: end of the exponential zone: ``exp_v`` after ``exp_fraction`` of Q drawn.
        nominal_v, nominal_fraction: end of the nominal zone: ``nominal_v`` after ``nominal_fraction`` of Q.
        curve_c: the discharge current of that curve, in C (multiples of Q per hour).
        resistance_ohm: a cell's internal resistance R [Ω] (the pack's is ``cells`` times it).
        cutoff_v: a cell's lowest terminal voltage: below it the pack is empty and is disconnected.
        initial_soc: state of charge at the start of the flight, 0..1 (1 = full).
    """

    cells: int = 4
    capacity_ah: float = 5.0
    full_v: float = 4.2
    exp_v: float = 4.05
    exp_fraction: float = 0.05
    nominal_v: float = 3.7
    nominal_fraction: float = 0.9
    curve_c: float = 0.2
    resistance_ohm: float = 0.004
    cutoff_v: float = 3.0
    initial_soc: float = 1.0

    def __post_init__(self) -> None:
        _require(
            isinstance(self.cells, int) and not isinstance(self.cells, bool) and 1 <= self.cells <= 24,
            "cells",
            f"must be a whole number of cells in series, 1..24, got {self.cells!r}",
        )
        check_fields(self)  # every float in its range first (config/ranges.py): names the field
        _require(
            0.0 <= self.initial_soc <= 1.0,
            "initial_soc",
            f"a state of charge is a fraction in 0..1, got {self.initial_soc}",
        )
        _require(
            self.full_v > self.exp_v > self.nominal_v > self.cutoff_v,
            "exp_v",
            "a discharge curve falls: full_v > exp_v > nominal_v > cutoff_v, got "
            f"{self.full_v} > {self.exp_v} > {self.nominal_v} > {self.cutoff_v}",
        )
        _require(
            0 < self.exp_fraction < self.nominal_fraction < 1,
            "exp_fraction",
            f"must be below nominal_fraction ({self.nominal_fraction}), got {self.exp_fraction}",
        )
        c = self.tremblay()
        _require(
            c.k > 0,
            "nominal_v",
            f"the curve's points give no falling voltage over the nominal zone (K = {c.k:.4g} V)",
        )

    def tremblay(self) -> TremblayConstants:
        """Tremblay's extraction (2007, eqs. 5-8): the model through the curve's three points.

        ``A = V_full − V_exp``, ``B = 3/Q_exp`` (the exponential term has fallen to 5 % at the zone's
        end), ``K = (V_full − V_nom + A·(exp(−B·Q_nom) − 1))·(Q − Q_nom)/Q_nom``,
        ``E0 = V_full + K + R·i − A`` with ``i`` the curve's current.
        """
        q = self.capacity_ah
        q_exp, q_nom = self.exp_fraction * q, self.nominal_fraction * q
        a = self.full_v - self.exp_v
        b = 3.0 / q_exp
        k = (self.full_v - self.nominal_v + a * (math.exp(-b * q_nom) - 1.0)) * (q - q_nom) / q_nom
        e0 = self.full_v + k + self.resistance_ohm * self.curve_c * q - a
        return TremblayConstants(e0, k, a, b, q, self.resistance_ohm)

    @property
    def pack_resistance_ohm(self) -> float:
        """The pack's internal resistance: ``cells`` cells in series [Ω]."""
        return self.cells * self.resistance_ohm

    @property
    def cutoff_pack_v(self) -> float:
        """The pack's cut-off terminal voltage [V]."""
        return self.cells * self.cutoff_v


@dataclass(frozen=True)
class PowerConfig:
    """What powers the vehicle (docs/power.md).

    Attributes:
        supply: ``"constant"`` (the motors see ``motor.supply_voltage``; no budget kept: every
            result as before) or ``"battery"`` (the pack of ``battery``; one power budget).
        battery: the pack (used with ``supply = "battery"``).
        avionics_w: the rest of the avionics besides the chip and the motors, as one constant draw
            (sensors, receiver, ESC logic, regulators; assumed, no source): 3 W.
        reserve_soc: the state of charge an endurance estimate stops at (a landing reserve), and
            below which the firmware's low-battery failsafe takes over.
        failsafe_height_m: the hover height the failsafe first climbs or descends to [m, the body's
            height above the ground, as the setpoints'] (assumed: 1 m, the default scenario's hover);
            it must be above the height at which the failsafe counts the vehicle landed
            (checked against the vehicle's resting height when the firmware is built).
        failsafe_hold_s: how long the failsafe holds that height before it lands [s] (assumed: 1 s).
    """

    supply: Supply = "constant"
    battery: BatteryConfig = field(default_factory=BatteryConfig)
    avionics_w: float = 3.0
    reserve_soc: float = 0.2
    failsafe_height_m: float = 1.0
    failsafe_hold_s: float = 1.0

    def __post_init__(self) -> None:
        _require(
            self.supply in SUPPLIES,
            "supply",
            f"must be one of {', '.join(map(repr, SUPPLIES))}, got {self.supply!r}",
        )
        check_fields(self)
        _require(
            0.0 <= self.reserve_soc < 1.0,
            "reserve_soc",
            f"a state of charge is a fraction in 0..1 (below 1: something must be left to fly on), "
            f"got {self.reserve_soc}",
        )

    @property
    def battery_on(self) -> bool:
        """Whether the motors are fed by the pack (and a power budget is kept)."""
        return self.supply == "battery"
