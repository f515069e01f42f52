"""The Li-Po pack (Tremblay's model) against hand-computed sag and discharge, and the power budget
of a vehicle on it adding up step by step (docs/power.md)."""

import dataclasses
import math

import pytest

from robosoc.config.power import BatteryConfig, PowerConfig
from robosoc.config.scenario import SensorConfig, WindConfig
from robosoc.config.vehicle import default_vehicle
from robosoc.physics import World
from robosoc.physics.battery import Battery
from robosoc.physics.power import endurance_s, lift_problem
from robosoc.physics.propulsion import steady_state

PACK = BatteryConfig()  # 4 cells, 5 Ah, 4.2 V full / 4.05 V at 5 % / 3.7 V at 90 % at 0.2 C, 4 mΩ, 3.0 V cut-off
# Tremblay's extraction by hand from those points (Q_exp = 0.25 Ah, Q_nom = 4.5 Ah, i = 0.2 C = 1 A):
A = 4.2 - 4.05  # 0.15 V
B = 3 / 0.25  # 12 /Ah
K = (4.2 - 3.7 + A * (math.exp(-B * 4.5) - 1)) * (5.0 - 4.5) / 4.5  # 0.0388889 V
E0 = 4.2 + K + 0.004 * 1.0 - A  # 4.0928889 V


def test_constants_are_tremblays_extraction_from_the_curve() -> None:
    c = PACK.tremblay()
    assert (c.a, c.b, c.q, c.r) == pytest.approx((A, B, 5.0, 0.004), rel=1e-12)
    assert c.k == pytest.approx(0.03888889, abs=1e-8)
    assert c.e0 == pytest.approx(4.09288889, abs=1e-8)


def test_the_model_passes_through_the_full_and_nominal_points_at_the_curves_current() -> None:
    battery = Battery(PACK)
    assert battery.terminal_v(1.0) == pytest.approx(4 * 4.2, abs=1e-12)  # 1 A = 0.2 C
    battery.drawn_ah = 0.9 * 5.0
    assert battery.terminal_v(1.0) == pytest.approx(4 * 3.7, abs=1e-12)


def test_sag_under_load_at_full_charge_by_hand() -> None:
    battery = Battery(PACK)
    open_v = 4 * (E0 - K + A)  # it = 0: 4 x 4.204 = 16.816 V
    assert battery.open_circuit_v() == pytest.approx(16.816, abs=1e-9)
    # 50 A through 4 x 4 mOhm = 0.8 V of sag
    assert battery.terminal_v(50.0) == pytest.approx(open_v - 0.8, abs=1e-9)
    assert battery.terminal_v(50.0) == pytest.approx(16.016, abs=1e-9)


def test_discharge_at_constant_current_by_hand() -> None:
    battery = Battery(PACK)
    for _ in range(360_000):  # 10 A for 360 s in 1 ms steps: 1 Ah drawn
        battery.draw(10.0, 0.001)
    assert battery.drawn_ah == pytest.approx(1.0, rel=1e-9)
    assert battery.soc == pytest.approx(0.8, rel=1e-9)
    cell = E0 - K * 5.0 / (5.0 - 1.0) + A * math.exp(-B * 1.0)  # 4.0442787 V
    assert battery.open_circuit_v() == pytest.approx(4 * cell, abs=1e-8)
    assert battery.terminal_v(10.0) == pytest.approx(4 * cell - 4 * 0.004 * 10.0, abs=1e-8)
    assert battery.terminal_v(10.0) == pytest.approx(16.017115, abs=1e-5)


def test_initial_state_of_charge_sets_the_charge_drawn() -> None:
    battery = Battery(dataclasses.replace(PACK, initial_soc=0.5))
    assert battery.drawn_ah == pytest.approx(2.5)
    assert battery.soc == pytest.approx(0.5)


def test_the_pack_cuts_off_below_its_cut_off_voltage_and_delivers_nothing_after() -> None:
    battery = Battery(PACK)
    steps = 0
    while not battery.cut_off(20.0):
        battery.draw(20.0, 1.0)  # 20 A in 1 s steps
        steps += 1
    # by hand (the exponential term is gone there): E0 - K*Q/(Q - it) - R*i = 3.0 V per cell
    it_cut = 5.0 - K * 5.0 / (E0 - 3.0 - 0.004 * 20.0)
    assert battery.drawn_ah == pytest.approx(it_cut, abs=20.0 / 3600)  # within one step's charge
    assert battery.terminal_v(20.0) == 0.0
    drawn = battery.drawn_ah
    battery.draw(20.0, 1.0)
    assert battery.drawn_ah == drawn


def test_endurance_at_constant_power_matches_the_closed_form_integral() -> None:
    pack = dataclasses.replace(PACK, resistance_ohm=0.0)  # no sag: V is the open-circuit voltage
    power = 80.0
    q = 0.8 * 5.0  # to a reserve of 0.2

    def energy_wh(it: float) -> float:  # ∫ E dq per cell, in closed form
        return E0 * it + K * 5.0 * math.log((5.0 - it) / 5.0) + (A / B) * (1 - math.exp(-B * it))

    # E0 of this pack differs from E0 above by the R*i of the curve (0.004 V)
    expected_h = 4 * (energy_wh(q) - 0.004 * q) / power
    seconds, ended_by = endurance_s(pack, power, 0.2)
    assert seconds == pytest.approx(expected_h * 3600, rel=1e-6)
    assert ended_by.startswith("reserve")


def test_endurance_stops_at_the_cut_off_when_it_comes_before_the_reserve() -> None:
    seconds_low, ended = endurance_s(PACK, 80.0, 0.0)
    assert ended.startswith("cut-off")
    assert seconds_low < endurance_s(PACK, 80.0, 0.0001)[0] + 1  # nothing past the cut-off
    assert seconds_low > endurance_s(PACK, 80.0, 0.2)[0]


def test_a_battery_that_cannot_lift_the_vehicle_is_named_before_flying() -> None:
    def on(pack: BatteryConfig):
        return dataclasses.replace(default_vehicle(), power=PowerConfig(supply="battery", battery=pack))

    assert lift_problem(default_vehicle()) is None  # constant supply
    assert lift_problem(on(PACK)) is None
    field, reason = lift_problem(on(dataclasses.replace(PACK, cells=1)))
    assert field == "power.battery.cells" and "cannot lift the vehicle" in reason
    # the figure in the message is the steady-state thrust at the sagging voltage: below the weight
    assert 4 * steady_state(default_vehicle().motor, 255, supply_v=4.2)[1] < 1.478 * 9.8
    field, reason = lift_problem(on(dataclasses.replace(PACK, initial_soc=0.0)))
    assert field == "power.battery.initial_soc" and "empty at the start" in reason


@pytest.mark.parametrize("soc", [-0.1, 1.5, math.nan])
def test_state_of_charge_outside_0_1_is_refused(soc: float) -> None:
    with pytest.raises(ValueError, match="initial_soc"):
        BatteryConfig(initial_soc=soc)
    with pytest.raises(ValueError, match="reserve_soc"):
        PowerConfig(reserve_soc=soc if soc == soc else 1.0)


def test_a_curve_that_does_not_fall_is_refused() -> None:
    with pytest.raises(ValueError, match="exp_v"):
        BatteryConfig(exp_v=4.3)
    with pytest.raises(ValueError, match="cells"):
        BatteryConfig(cells=0)


def _battery_quad(pack: BatteryConfig = PACK, avionics_w: float = 3.0):
    vehicle = dataclasses.replace(
        default_vehicle(), power=PowerConfig(supply="battery", battery=pack, avionics_w=avionics_w)
    )
    world = World([vehicle], SensorConfig(noise=False), WindConfig())
    world.reset(1)
    return world, world.quadrotors[0]


def test_the_budget_adds_up_at_every_step_and_the_motors_see_the_sagging_pack() -> None:
    world, quad = _battery_quad()
    power = quad.power
    assert power is not None
    motor = quad.config.motor
    r_pack = 4 * 0.004
    power.chip_w = 0.25
    quad.apply_pwm((200, 180, 200, 180))
    drawn_ah = 0.0
    current = 0.0
    for _ in range(300):
        omega = list(quad.propulsion.omega)
        before = dict(power.energy_j)
        volts_expected = Battery(PACK).open_circuit_v()  # at the charge drawn so far ...
        b = Battery(PACK)
        b.drawn_ah = drawn_ah
        volts_expected = b.open_circuit_v() - r_pack * current  # ... at the previous step's current
        world.step()
        assert power.voltage == pytest.approx(volts_expected, rel=1e-12)
        # the motors' electrical power by hand: U = pwm/255 of the pack, I from the motor model
        motors = 0.0
        for pwm, om in zip((200, 180, 200, 180), omega, strict=True):
            u = pwm * volts_expected / 255
            t = (u * motor.beta_m - motor.psi * om) / (2 * motor.r_a)
            motors += u * (t + math.sqrt(t * t + u * motor.alpha_m / motor.r_a))
        assert power.motors_w == pytest.approx(motors, rel=1e-9)
        step = {k: power.energy_j[k] - before[k] for k in before}
        assert step["motors"] == pytest.approx(motors * 0.001, rel=1e-9)
        assert step["chip"] == pytest.approx(0.25 * 0.001, rel=1e-9)
        assert step["avionics"] == pytest.approx(3.0 * 0.001, rel=1e-9)
        total_w = motors + 0.25 + 3.0
        assert sum(step.values()) == pytest.approx(total_w * 0.001, rel=1e-9)  # motors + chip + rest = total
        current = total_w / volts_expected
        drawn_ah += current * 0.001 / 3600
        assert power.current == pytest.approx(current, rel=1e-9)
        assert power.battery.drawn_ah == pytest.approx(drawn_ah, rel=1e-9)
    assert power.voltage < Battery(PACK).open_circuit_v() - 0.1  # it sags under tens of amperes


def test_a_sagging_pack_gives_less_thrust_for_the_same_command() -> None:
    full = 4 * steady_state(default_vehicle().motor, 200, supply_v=16.8)[1]
    sagged = 4 * steady_state(default_vehicle().motor, 200, supply_v=14.0)[1]
    assert sagged < 0.8 * full


def test_an_empty_pack_stops_feeding_the_motors_for_good() -> None:
    tiny = dataclasses.replace(PACK, capacity_ah=0.005)  # 18 C of charge: empty within a second at full throttle
    world, quad = _battery_quad(tiny)
    power = quad.power
    assert power is not None
    quad.apply_pwm((255, 255, 255, 255))
    for _ in range(3000):
        world.step()
    assert power.empty_at_s is not None and 0 < power.empty_at_s < 3.0
    assert power.voltage == 0.0 and power.current == 0.0
    assert quad.propulsion.voltages == [0.0, 0.0, 0.0, 0.0]
    totals = dict(power.energy_j)
    world.step()
    assert power.energy_j == totals  # nothing drawn any more


def test_constant_supply_keeps_no_budget_and_the_published_voltage() -> None:
    world = World([default_vehicle()], SensorConfig(noise=False), WindConfig())
    world.reset(1)
    quad = world.quadrotors[0]
    assert quad.power is None
    quad.apply_pwm((200, 180, 200, 180))
    world.step()
    assert quad.propulsion.voltages == [b * 14.8 / 255 for b in (200, 180, 200, 180)]
