"""Motor model invariants from quadrotor.md: hover, full thrust, idle speed, step response, signs."""

import dataclasses
import math

import pytest

from robosoc.config.vehicle import MotorConfig, default_vehicle
from robosoc.physics.propulsion import Propulsion, hover_pwm, steady_state

MOTOR = MotorConfig()
DT = 0.001


def test_hover_needs_pwm_121_2_for_1_478_kg() -> None:
    pwm = hover_pwm(MOTOR, 1.478, 9.8)
    assert pwm == pytest.approx(121.2, abs=0.1)
    omega, force, _ = steady_state(MOTOR, pwm)
    assert omega == pytest.approx(485.0, abs=2.0)
    assert force == pytest.approx(3.62, abs=0.01)
    assert 4 * force == pytest.approx(1.478 * 9.8, rel=1e-6)


def test_full_pwm_gives_38_3_newtons() -> None:
    assert 4 * steady_state(MOTOR, 255)[1] == pytest.approx(38.3, abs=0.05)


def _run(prop: Propulsion, seconds: float) -> list[float]:
    trace = []
    for _ in range(round(seconds / DT)):
        prop.step(0.0, 0.0, 0.0)
        trace.append(prop.omega[0])
    return trace


def test_any_positive_pwm_spins_up_to_idle_297() -> None:
    prop = Propulsion(MOTOR, 0.275, DT)
    prop.reset([1.0, 1.0, 1.0, 1.0])
    prop.set_pwm([1, 1, 1, 1])
    _run(prop, 8.0)
    assert prop.omega[0] == pytest.approx(297.0, abs=3.0)
    assert steady_state(MOTOR, 0.0)[0] == pytest.approx(297.5, abs=1.0)


def test_pwm_zero_does_not_stop_a_spinning_rotor() -> None:
    prop = Propulsion(MOTOR, 0.275, DT)
    prop.reset([485.0] * 4)
    prop.set_pwm([0, 0, 0, 0])
    _run(prop, 8.0)
    assert prop.omega[0] == pytest.approx(297.5, abs=2.0)
    assert prop.forces[0] == pytest.approx(1.36, abs=0.02)


def test_step_121_to_140_reaches_63_percent_in_about_66_ms() -> None:
    start = steady_state(MOTOR, 121)[0]
    end = steady_state(MOTOR, 140)[0]
    prop = Propulsion(MOTOR, 0.275, DT)
    prop.reset([start] * 4)
    prop.set_pwm([140] * 4)
    trace = _run(prop, 1.0)
    target = start + 0.632 * (end - start)
    crossing_ms = next(i + 1 for i, w in enumerate(trace) if w >= target)
    assert 60 <= crossing_ms <= 72
    assert trace[-1] == pytest.approx(end, rel=1e-3)


def test_wrench_signs_follow_the_plus_layout() -> None:
    prop = Propulsion(MOTOR, 0.275, DT)
    base = steady_state(MOTOR, 121)[0]
    # Motor 3 (left, +y) faster rolls right-side down: +τx.  Motor 2 (rear) faster: +τy.
    prop.reset([base, base, base, base + 50])
    fz, tx, ty, tz = prop.step(0.0, 0.0, 0.0)
    assert tx > 0 and ty == pytest.approx(0.0) and fz > 4 * 3.6
    prop.reset([base, base, base + 50, base])
    _, tx, ty, _ = prop.step(0.0, 0.0, 0.0)
    assert ty > 0 and tx == pytest.approx(0.0)
    # Front/rear spin clockwise: more voltage on 0 and 2 yaws the body anticlockwise (+z).
    prop.reset([base] * 4)
    prop.set_pwm([150, 121, 150, 121])
    _, _, _, tz = prop.step(0.0, 0.0, 0.0)
    assert tz > 0


def test_inflow_reduces_thrust_when_climbing() -> None:
    prop = Propulsion(MOTOR, 0.275, DT)
    prop.reset([485.0] * 4)
    hover = prop.step(0.0, 0.0, 0.0)[0]
    prop.reset([485.0] * 4)
    climbing = prop.step(2.0, 0.0, 0.0)[0]
    # F = CT0s·ω² + CT1s·v1·ω with CT1s < 0: 4 · 2.5224e-4 · 2 · 485 less.
    assert hover - climbing == pytest.approx(4 * 2.5224e-4 * 2.0 * 485.0, rel=1e-9)


@pytest.mark.parametrize("pwm", [[256, 0, 0, 0], [-1, 0, 0, 0], [1, 2, 3], [1.5, 0, 0, 0]])
def test_bad_pwm_is_rejected(pwm: list) -> None:
    prop = Propulsion(MOTOR, 0.275, DT)
    with pytest.raises(ValueError, match="pwm"):
        prop.set_pwm(pwm)


def test_voltage_is_pwm_times_supply_over_255() -> None:
    prop = Propulsion(default_vehicle().motor, 0.275, DT)
    prop.set_pwm([255, 128, 1, 0])
    assert prop.voltages == [14.8, 128 * 14.8 / 255, 14.8 / 255, 0.0]
    assert math.isclose(prop.voltages[1], 7.4290196, rel_tol=1e-6)


# A motor with an inflow-squared thrust term (the hector default has CT2s = 0), so that each term of
# the thrust polynomial shows.
MOTOR_CT2 = dataclasses.replace(MOTOR, ct2s=2.0e-3)


@pytest.mark.parametrize("motor", [MOTOR, MOTOR_CT2], ids=["hector", "ct2s"])
@pytest.mark.parametrize(("pwm", "inflow"), [(121, 0.0), (200, -3.0), (60, 2.5), (255, 1.0), (0, 0.0)])
def test_steady_state_is_an_equilibrium_of_the_motor_step(motor: MotorConfig, pwm: int, inflow: float) -> None:
    # The equilibrium solved by bisection, fed to the explicit-Euler step (written separately): the
    # step must see the same thrust and electrical torque and leave the speed where it is.
    omega, force, torque = steady_state(motor, pwm, inflow)
    # quadrotor.md: F = CT0s·ω² + CT1s·v1·ω + CT2s·v1², and dω/dt = 0 ⇔ M_e = k_t·F + k_m·ω.
    thrust = motor.ct0s * omega * omega + motor.ct1s * inflow * omega + motor.ct2s * inflow * inflow
    assert force == pytest.approx(thrust, rel=1e-12)
    assert torque == pytest.approx(motor.k_t * force + motor.k_m * omega, rel=1e-9)
    prop = Propulsion(motor, 0.275, DT)
    prop.reset([omega] * 4)
    prop.set_pwm([pwm] * 4)
    prop.step(inflow, 0.0, 0.0)  # no body rates: every rotor sees the same inflow
    assert prop.forces == pytest.approx([force] * 4, rel=1e-12)
    assert prop.torques == pytest.approx([torque] * 4, rel=1e-12)
    assert prop.omega == pytest.approx([omega] * 4, abs=1e-9)


def test_hover_pwm_below_one_when_the_idle_thrust_nearly_carries_the_mass() -> None:
    # A light vehicle: the thrust at PWM 0.4 (idle already gives 4 · 1.36 N) is its weight.
    mass = 4.0 * steady_state(MOTOR, 0.4)[1] / 9.8
    assert hover_pwm(MOTOR, mass, 9.8) == pytest.approx(0.4, abs=1e-9)
    # Lighter than the idle thrust: the lowest command, PWM 0, already carries it.
    assert hover_pwm(MOTOR, 0.5 * mass, 9.8) == pytest.approx(0.0, abs=1e-9)


def test_motor_state_starts_and_resets_to_zero() -> None:
    prop = Propulsion(MOTOR, 0.275, DT)
    assert (prop.omega, prop.voltages, prop.forces, prop.torques) == ([0.0] * 4,) * 4
    prop.reset([400.0, 410.0, 420.0, 430.0])
    prop.set_pwm([100, 110, 120, 130])
    prop.step(0.3, 0.2, -0.1)
    prop.reset()
    assert (prop.omega, prop.voltages, prop.forces, prop.torques) == ([0.0] * 4,) * 4


def test_each_rotor_sees_its_own_inflow_and_the_wrench_sums_them_by_the_plus_layout() -> None:
    # quadrotor.md: v1 = [w − l·q, w − l·p, w + l·q, w + l·p]; τ = ((F3 − F1)·l, (F2 − F0)·l, M0 + M2 − M1 − M3).
    arm, w, p, q = 0.3, 0.4, 1.5, -2.5
    omega = [400.0, 430.0, 460.0, 490.0]
    prop = Propulsion(MOTOR_CT2, arm, DT)
    prop.reset(omega)
    prop.set_pwm([100, 140, 180, 220])
    fz, tx, ty, tz = prop.step(w, p, q)
    for i, inflow in enumerate((w - arm * q, w - arm * p, w + arm * q, w + arm * p)):
        thrust = MOTOR_CT2.ct0s * omega[i] ** 2 + MOTOR_CT2.ct1s * inflow * omega[i] + MOTOR_CT2.ct2s * inflow**2
        assert prop.forces[i] == pytest.approx(thrust, rel=1e-12)
    f, m = prop.forces, prop.torques
    assert (fz, tx, ty, tz) == pytest.approx(
        (sum(f), (f[3] - f[1]) * arm, (f[2] - f[0]) * arm, m[0] + m[2] - m[1] - m[3]), rel=1e-12
    )
    assert len(set(m)) == 4 and tz != 0.0
