"""One vehicle's power system in a battery flight: the pack feeding the motors, the chip and the
rest of the avionics, and the budget of what each drew (docs/power.md).

Every physics step (1 ms), in this order:

1. the motors' supply is the pack's terminal voltage at the *previous* step's current (an explicit
   one-step lag, which breaks the loop voltage → motor current → pack current → voltage); a pack
   below its cut-off voltage is disconnected for good (0 V from then on);
2. the motors run on ``pwm/255`` of that voltage (an ideal ESC: the duty cycle scales the pack's
   voltage) and draw ``P_motors = Σ U_i·I_i`` (the propulsion model's voltage and current);
3. the pack delivers ``P = P_motors + P_chip + P_avionics`` at that voltage: ``i = P/V`` (ideal
   converters for the chip and the avionics), and ``i·dt`` is drawn from it.

``P_chip`` is the chip's energy over the current sample period divided by the period (the chip has
run the period when its first step is taken: :mod:`robosoc.cosim.lockstep`), so over a flight the
chip's share of the budget is exactly the chip's energy.  An empty pack delivers nothing: every
consumer's power is 0 from then on (the chip is still simulated, its draw is not counted).
"""

from __future__ import annotations

import dataclasses
import math

from robosoc.config.power import FAILSAFE_LANDED_MARGIN_M, BatteryConfig, PowerConfig
from robosoc.config.vehicle import VehicleConfig
from robosoc.physics.battery import Battery
from robosoc.physics.mjcf import GRAVITY
from robosoc.physics.propulsion import PWM_MAX, steady_state
from robosoc.records import POWER_CONSUMERS, PowerSample


class PowerSystem:
    """The pack and the energy budget of one vehicle.

    Args:
        config: the power system (``supply = "battery"``).
        dt: the physics step [s].
    """

    __slots__ = ("avionics_w", "battery", "chip_w", "current", "dt", "empty_at_s", "energy_j", "low_at_s", "motors_w",
                 "reserve_soc", "steps", "voltage")  # fmt: skip

    def __init__(self, config: PowerConfig, dt: float) -> None:
        self.battery = Battery(config.battery)
        self.avionics_w = config.avionics_w
        self.dt = dt
        self.chip_w = 0.0
        self.motors_w = 0.0
        self.current = 0.0
        self.voltage = self.battery.terminal_v(0.0)
        self.energy_j = dict.fromkeys(POWER_CONSUMERS, 0.0)
        self.empty_at_s: float | None = None
        self.reserve_soc = config.reserve_soc
        self.low_at_s: float | None = None  # when the state of charge first fell below the reserve
        self.steps = 0

    def supply_v(self) -> float:
        """The motors' supply for the coming step: the terminal voltage at the last step's current
        (0 once the pack is cut off)."""
        if self.battery.cut_off(self.current):
            if self.empty_at_s is None:
                self.empty_at_s = self.steps * self.dt
            return 0.0
        return self.battery.terminal_v(self.current)

    def consume(self, motors_w: float, volts: float) -> None:
        """Account one step in which the motors drew ``motors_w`` from a supply of ``volts``."""
        self.steps += 1
        self.voltage = volts
        if volts <= 0.0:
            self.motors_w = 0.0
            self.current = 0.0
            return
        self.motors_w = motors_w
        total = motors_w + self.chip_w + self.avionics_w
        self.current = total / volts
        self.battery.draw(self.current, self.dt)
        if self.low_at_s is None and self.battery.soc < self.reserve_soc:
            self.low_at_s = self.steps * self.dt
        e = self.energy_j
        e["motors"] += motors_w * self.dt
        e["chip"] += self.chip_w * self.dt
        e["avionics"] += self.avionics_w * self.dt

    def sample(self) -> PowerSample:
        """The state after the last step (its time: steps taken × dt)."""
        on = self.voltage > 0.0
        return PowerSample(
            t=self.steps * self.dt,
            pack_v=self.voltage,
            pack_a=self.current,
            soc=self.battery.soc,
            motors_w=self.motors_w,
            chip_w=self.chip_w if on else 0.0,
            avionics_w=self.avionics_w if on else 0.0,
            energy_j=dict(self.energy_j),
            empty_at_s=self.empty_at_s,
            low_at_s=self.low_at_s,
        )


def terminal_at_power(battery: Battery, power_w: float) -> float:
    """The pack's terminal voltage when it delivers ``power_w`` at its present charge: the larger
    root of ``V = E − R·P/V`` (NaN if it cannot deliver that power at all)."""
    e = battery.open_circuit_v()
    r = battery.cells * battery.config.resistance_ohm
    disc = e * e - 4.0 * r * power_w
    if not math.isfinite(e) or disc < 0.0:
        return math.nan
    return 0.5 * (e + math.sqrt(disc))


ENDURANCE_STEPS = 2000
"""Steps of charge over which :func:`endurance_s` integrates the pack's voltage."""


def endurance_s(config: BatteryConfig, power_w: float, reserve_soc: float) -> tuple[float, str]:
    """Time [s] a full pack delivers a constant ``power_w`` until its state of charge falls to
    ``reserve_soc`` (or its terminal voltage to the cut-off, if that comes first), and what ended it.

    Integrates over the charge: each of :data:`ENDURANCE_STEPS` equal slices ``dq`` of the charge
    between full and the reserve takes ``dq·V/P`` hours, ``V`` the terminal voltage at that power
    at the slice's middle (:func:`terminal_at_power`).
    """
    if power_w <= 0.0:
        return math.inf, "no power drawn"
    full = dataclasses.replace(config, initial_soc=1.0)
    battery = Battery(full)
    usable_ah = (1.0 - reserve_soc) * full.capacity_ah
    dq = usable_ah / ENDURANCE_STEPS
    hours = 0.0
    for k in range(ENDURANCE_STEPS):
        battery.drawn_ah = (k + 0.5) * dq
        volts = terminal_at_power(battery, power_w)
        if not volts >= full.cutoff_pack_v:  # NaN too: the pack cannot deliver that power any more
            return hours * 3600.0, f"cut-off voltage at state of charge {1 - k * dq / full.capacity_ah:.3f}"
        hours += dq * volts / power_w
    return hours * 3600.0, f"reserve state of charge {reserve_soc:g}"


def full_throttle(vehicle: VehicleConfig) -> tuple[float, float, float]:
    """The pack of ``vehicle`` at its initial charge with all four motors at PWM 255 in steady state,
    at rest in still air: (terminal voltage [V], pack current [A], total thrust [N]).

    Solves ``V = E − R·(4·U·I(U) + P_avionics)/V`` (with ``U = V``) by fixed-point iteration.
    """
    config = vehicle.power
    battery = Battery(config.battery)
    motor = vehicle.motor
    r = battery.cells * config.battery.resistance_ohm
    volts = battery.terminal_v(0.0)
    current = force = 0.0
    for _ in range(100):
        if not volts > 0.0:
            return 0.0, 0.0, 0.0
        _omega, force, torque = steady_state(motor, PWM_MAX, supply_v=volts)
        current = (4.0 * volts * torque / motor.psi + config.avionics_w) / volts
        volts = battery.open_circuit_v() - r * current
    return volts, current, 4.0 * force


def lift_problem(vehicle: VehicleConfig) -> tuple[str, str] | None:
    """Why the battery of ``vehicle`` cannot fly it, as (the scenario field to blame, the reason):
    empty at the start, too weak to lift it at full throttle, or a failsafe hover height at which the
    failsafe would count it landed.  None if it can (and for a constant supply).  Said before a
    flight starts."""
    config = vehicle.power
    if not config.battery_on:
        return None
    landed = vehicle.rest_height + FAILSAFE_LANDED_MARGIN_M
    if not config.failsafe_height_m > landed:
        return "power.failsafe_height_m", (
            f"{config.failsafe_height_m:g} m is not above the height at which the low-battery failsafe counts "
            f"the vehicle landed ({landed:g} m: its resting height {vehicle.rest_height:g} m + "
            f"{FAILSAFE_LANDED_MARGIN_M:g} m)"
        )
    pack = config.battery
    battery = Battery(pack)
    if not battery.terminal_v(0.0) > pack.cutoff_pack_v:
        return "power.battery.initial_soc", (
            f"the pack is empty at the start: state of charge {pack.initial_soc:g} gives "
            f"{battery.open_circuit_v():.2f} V open-circuit, below the cut-off ({pack.cutoff_pack_v:g} V)"
        )
    volts, current, thrust = full_throttle(vehicle)
    weight = vehicle.mass * GRAVITY
    if not thrust > weight:
        return "power.battery.cells", (
            f"the pack cannot lift the vehicle: {pack.cells} cell(s) at state of charge {pack.initial_soc:g} sag to "
            f"{volts:.2f} V under {current:.1f} A at full throttle, and the four motors give {thrust:.1f} N, "
            f"not more than the vehicle's weight ({vehicle.mass:g} kg: {weight:.1f} N)"
        )
    return None
