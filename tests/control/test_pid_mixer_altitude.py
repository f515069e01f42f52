"""PID (equations 1–2), mixer (equation 3) and altitude filter against hand-checked values."""

import math

import numpy as np
import pytest

from robosoc.config.vehicle import MotorConfig, vehicle_preset
from robosoc.control.altitude import AltitudeFilter
from robosoc.control.host import default_gains
from robosoc.control.mixer import Mixer, pwm_counts, thrust_to_voltage, yaw_coefficient
from robosoc.control.pid import HeightController, Pid, PidGains, euler_rates, wrap_angle
from robosoc.physics.propulsion import steady_state

MOTOR = MotorConfig()


def test_pid_hand_checked() -> None:
    pid = Pid(PidGains(kp=2.0, ki=0.5, kd=0.1, integral_limit=10.0, output_limit=10.0))
    # I = 1·0.01; u = 2·1 + 0.5·0.01 + 0.1·(−0.2) = 1.985
    assert pid.step(1.0, -0.2, 0.01) == pytest.approx(1.985, abs=1e-15)
    # I = 0.01 + 0.5·0.01 = 0.015; u = 1 + 0.0075 + 0 = 1.0075
    assert pid.step(0.5, 0.0, 0.01) == pytest.approx(1.0075, abs=1e-15)


def test_pid_clamps_integral_and_output() -> None:
    pid = Pid(PidGains(kp=1.0, ki=1.0, kd=0.0, integral_limit=0.05, output_limit=1.5))
    for _ in range(100):
        out = pid.step(1.0, 0.0, 0.01)
    assert pid.integral == 0.05
    assert out == 1.05
    assert pid.step(10.0, 0.0, 0.01) == 1.5
    assert pid.step(-10.0, 0.0, 0.01) == -1.5


HEIGHT = PidGains(kp=10.0, ki=2.0, kd=5.0, integral_limit=1.0, output_limit=20.0, integral_band=0.1)


def _height(climb: float = 2.0, descent: float = 1.0) -> HeightController:
    return HeightController(HEIGHT, mass=1.5, gravity=9.8, climb_rate=climb, descent_rate=descent, max_tilt_gain=1.5)


def test_height_controller_is_equation_2_with_feed_forward() -> None:
    hc = _height()
    # Level, e = 0.1 m, ż_sp = 0.3, ż = 0.1, z̈_sp = 0.5 m/s²:
    # K_p·e + K_d·(ż_sp − ż) + m·(g + z̈_sp) = 1 + 1 + 1.5·10.3 = 17.45; the setpoint moves, so I stays 0.
    assert hc.step(1.1, 0.3, 0.5, 1.0, 0.1, 0.0, 0.0, 0.01) == pytest.approx(17.45, abs=1e-12)
    assert hc.integral == 0.0
    # Hovering setpoint, e = 0.05 m at rest: I = 0.05·0.01, u = 10·0.05 + 2·0.0005 + 1.5·9.8.
    assert hc.step(1.05, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.01) == pytest.approx(15.201, abs=1e-12)
    assert hc.integral == pytest.approx(0.0005, abs=1e-15)
    # Beyond integral_band (0.1 m) the integral holds.
    hc.step(1.5, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.01)
    assert hc.integral == pytest.approx(0.0005, abs=1e-15)
    # Rolled 20°, pitched 10°: everything divided by cos α·cos β.
    expected = 1.5 * 9.8 / (math.cos(math.radians(20)) * math.cos(math.radians(10)))
    value = _height().step(1.0, 0.0, 0.0, 1.0, 0.0, math.radians(20), math.radians(10), 0.01)
    assert value == pytest.approx(expected, rel=1e-12)
    # At 60° roll 1/cos = 2 is limited to 1.5.
    assert _height().step(1.0, 0.0, 0.0, 1.0, 0.0, math.radians(60), 0.0, 0.01) == pytest.approx(1.5 * 14.7)


def test_height_controller_limits_the_commanded_vertical_speed() -> None:
    # 4 m below the setpoint at rest: K_p/K_d·e = 8 m/s is limited to the climb rate, 2 m/s,
    # so u = K_d·2 = 10 N above the weight (not K_p·4 = 40 N), and the integral does not learn.
    hc = _height()
    assert hc.step(5.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.01) == pytest.approx(10.0 + 14.7)
    assert hc.speed_command == 2.0 and hc.integral == 0.0
    # Climbing at 2 m/s already: no more thrust than the weight.
    assert hc.step(5.0, 0.0, 0.0, 1.0, 2.0, 0.0, 0.0, 0.01) == pytest.approx(14.7)
    # 4 m above: the descent rate, 1 m/s.
    hc = _height()
    assert hc.step(1.0, 0.0, 0.0, 5.0, 0.0, 0.0, 0.0, 0.01) == pytest.approx(-5.0 + 14.7)
    assert hc.speed_command == -1.0


@pytest.mark.parametrize(("start", "target", "rate"), [(1.0, 5.0, 2.0), (4.0, 0.5, 1.0)])
def test_an_unshaped_height_step_is_flown_at_the_rate_limit_without_overshoot(
    start: float, target: float, rate: float
) -> None:
    """A point mass m·z̈ = u_z − m·g under the tuned controller, perfect measurements, a raw step."""
    vehicle = vehicle_preset("default")
    mass, dt = vehicle.mass, 0.01
    hc = HeightController(default_gains(vehicle).height, mass, 9.8, 2.0, 1.0, 1.5)
    z, v, heights, speeds = start, 0.0, [], []
    for _ in range(1500):
        v += (hc.step(target, 0.0, 0.0, z, v, 0.0, 0.0, dt) / mass - 9.8) * dt
        z += v * dt
        heights.append(z)
        speeds.append(abs(v))
    assert rate - 1e-3 < max(speeds) <= rate + 1e-9  # reaches the limit, never exceeds it
    beyond = max(h - target for h in heights) if target > start else max(target - h for h in heights)
    assert beyond < 0.02
    assert z == pytest.approx(target, abs=1e-3)


def test_euler_rates_and_wrap() -> None:
    assert euler_rates(0.0, 0.0, (0.1, 0.2, 0.3)) == pytest.approx((0.1, 0.2, 0.3))
    # Rolled 90°: a body pitch rate q turns the heading (θ̇ = q·sin α / cos β), β̇ = q·cos α = 0.
    rates = euler_rates(math.pi / 2, 0.0, (0.0, 0.5, 0.0))
    assert rates == pytest.approx((0.0, 0.0, 0.5), abs=1e-12)
    assert wrap_angle(math.radians(350)) == pytest.approx(math.radians(-10))
    assert wrap_angle(-math.pi) == pytest.approx(-math.pi)


def test_thrust_to_voltage_inverts_the_physics_motor_model() -> None:
    for pwm in (30.0, 80.0, 121.2, 200.0, 250.0):
        _, force, _ = steady_state(MOTOR, pwm)
        volts = thrust_to_voltage(MOTOR, force)
        assert volts * 255 / 14.8 == pytest.approx(pwm, rel=1e-6)
    assert thrust_to_voltage(MOTOR, 0.0) == 0.0
    assert thrust_to_voltage(MOTOR, 1.0) == 0.0  # below the idle thrust no voltage is needed


HOVER = 1.478 * 9.8
IDLE = 50


def _mixer() -> Mixer:
    return Mixer(MOTOR, 0.275, HOVER / 4, IDLE)


def _torques(mixer: Mixer, f: tuple[float, float, float, float]) -> tuple[float, float, float]:
    """τ_x, τ_y, τ_z of four rotor thrusts (the physics' wrench, with the mixer's yaw coefficient)."""
    return ((f[3] - f[1]) * 0.275, (f[2] - f[0]) * 0.275, mixer.yaw_k * (f[0] + f[2] - f[1] - f[3]))


def test_mixer_hover_and_equation_3() -> None:
    mixer = _mixer()
    assert mixer.pwm(HOVER, 0.0, 0.0, 0.0) == (121, 121, 121, 121)
    f = mixer.equation_3(HOVER, 0.2, -0.1, 0.05)
    assert _torques(mixer, f) == pytest.approx((0.2, -0.1, 0.05))
    assert sum(f) == pytest.approx(HOVER)
    assert mixer.forces(HOVER, 0.2, -0.1, 0.05) == pytest.approx(f, abs=1e-15)  # nothing saturates
    # k = k_t + k_m/(2·CT0s·ω_h), ω_h = sqrt(F_h/CT0s)
    omega_h = math.sqrt(HOVER / 4 / MOTOR.ct0s)
    assert yaw_coefficient(MOTOR, HOVER / 4) == pytest.approx(MOTOR.k_t + MOTOR.k_m / (2 * MOTOR.ct0s * omega_h))


def test_mixer_limits_are_the_motor_steady_states_at_idle_and_full_pwm() -> None:
    mixer = _mixer()
    assert mixer.min_force == pytest.approx(steady_state(MOTOR, IDLE)[1], rel=1e-9)
    assert mixer.max_force == pytest.approx(steady_state(MOTOR, 255)[1], rel=1e-9)
    assert 4 * mixer.max_force == pytest.approx(38.28, abs=0.01)  # quadrotor.md: pwm 255 gives 38.3 N


def test_pwm_counts_round_half_up() -> None:
    # Python's round() gives 120 for 120.5 (half to even); the firmware's floor(x + 0.5) gives 121.
    assert pwm_counts(MOTOR, 120.5 * 14.8 / 255) == 121
    assert pwm_counts(MOTOR, 121.5 * 14.8 / 255) == 122
    assert pwm_counts(MOTOR, 121.49 * 14.8 / 255) == 121
    assert pwm_counts(MOTOR, 0.0) == 0 and pwm_counts(MOTOR, 20.0) == 255


def test_mixer_never_commands_below_idle_and_saturates_at_255() -> None:
    mixer = _mixer()
    assert mixer.pwm(1000.0, 0.0, 0.0, 0.0) == (255, 255, 255, 255)
    assert mixer.pwm(-5.0, 0.0, 0.0, 0.0) == (IDLE, IDLE, IDLE, IDLE)
    assert mixer.pwm(0.0, 0.0, 0.0, 0.0) == (IDLE, IDLE, IDLE, IDLE)
    assert all(isinstance(p, int) for p in mixer.pwm(HOVER, 0.1, 0.0, 0.0))


def test_desaturation_at_the_bottom_keeps_the_whole_torque() -> None:
    # 4 N in total (below four idle thrusts, 6.7 N) with 0.2 N·m of roll: the right motor sits at
    # idle, the left one 0.2/0.275 N above it; collective thrust gives way, not the torque.
    mixer = _mixer()
    f = mixer.forces(4.0, 0.2, 0.0, 0.0)
    assert f[1] == pytest.approx(mixer.min_force) and f[3] == pytest.approx(mixer.min_force + 0.2 / 0.275)
    assert f[0] == pytest.approx(mixer.min_force + 0.1 / 0.275) == pytest.approx(f[2])
    assert _torques(mixer, f) == pytest.approx((0.2, 0.0, 0.0), abs=1e-12)
    pwm = mixer.pwm(4.0, 0.2, 0.0, 0.0)
    assert pwm[1] == IDLE and pwm[3] > IDLE + 20


def test_desaturation_at_the_top_keeps_the_whole_torque() -> None:
    mixer = _mixer()
    f = mixer.forces(40.0, 0.0, -0.3, 0.0)
    assert f[0] == pytest.approx(mixer.max_force) and f[2] == pytest.approx(mixer.max_force - 0.3 / 0.275)
    assert _torques(mixer, f) == pytest.approx((0.0, -0.3, 0.0), abs=1e-12)


def test_desaturation_scales_roll_pitch_it_cannot_fit_and_gives_yaw_the_rest() -> None:
    mixer = _mixer()
    room = mixer.max_force - mixer.min_force
    # Roll/pitch overflow (r = 5/0.55 N > room/2): both scaled by the same factor, yaw dropped.
    tx, ty, tz = _torques(mixer, mixer.forces(HOVER, 5.0, 2.5, 0.2))
    assert tx == pytest.approx(room * 0.275) and ty == pytest.approx(room * 0.275 / 2) and tz == 0.0
    # Roll fits, yaw only in part: |y| ≤ (room − |r| − |p|)/2, with its sign.
    r = 1.0 / 0.55
    f = mixer.forces(HOVER, 1.0, 0.0, -0.3)
    tx, ty, tz = _torques(mixer, f)
    assert tx == pytest.approx(1.0) and ty == pytest.approx(0.0, abs=1e-12)
    assert tz == pytest.approx(-mixer.yaw_k * 4 * (room - r) / 2)
    assert max(f) == pytest.approx(mixer.max_force) and min(f) == pytest.approx(mixer.min_force)


def test_desaturation_keeps_every_torque_sign_and_every_motor_within_limits() -> None:
    mixer = _mixer()
    rng = np.random.default_rng(16)
    n = 3000
    commands = zip(
        rng.uniform(-10, 50, n), rng.normal(0, 1.0, n), rng.normal(0, 1.0, n), rng.normal(0, 0.2, n), strict=True
    )
    for u_z, u_roll, u_pitch, u_yaw in commands:
        f = mixer.forces(u_z, u_roll, u_pitch, u_yaw)
        assert all(mixer.min_force - 1e-9 <= fi <= mixer.max_force + 1e-9 for fi in f)
        for wanted, got in zip((u_roll, u_pitch, u_yaw), _torques(mixer, f), strict=True):
            assert math.copysign(1.0, wanted) * got >= -1e-12  # same sign, or zero
            assert abs(got) <= abs(wanted) + 1e-9  # never more than asked for
        raw = mixer.equation_3(u_z, u_roll, u_pitch, u_yaw)
        if all(mixer.min_force <= fi <= mixer.max_force for fi in raw):
            assert f == pytest.approx(raw, abs=1e-12)
        else:  # something gave way: a motor sits on a limit
            assert min(f) == pytest.approx(mixer.min_force) or max(f) == pytest.approx(mixer.max_force)
        assert all(IDLE <= p <= 255 for p in mixer.pwm(u_z, u_roll, u_pitch, u_yaw))


def test_altitude_filter_hand_checked_and_tracks_a_climb() -> None:
    alt = AltitudeFilter()
    alt.reset(baro_ground=12.0, rest_height=0.2)
    assert alt.reference == pytest.approx(11.8)
    level = np.eye(3)
    # Consistent data (at rest, baro = ground reading): nothing moves.
    assert alt.step(level, np.array([0.0, 0.0, 9.8]), 12.0, 0.01) == pytest.approx(0.2, abs=1e-12)
    # Constant 1 m/s² climb, noise-free: h = 0.2 + ½·t².
    for k in range(1, 301):
        t = 0.01 * k
        alt.step(level, np.array([0.0, 0.0, 10.8]), 11.8 + 0.2 + 0.5 * t * t, 0.01)
    assert alt.height == pytest.approx(0.2 + 0.5 * 9.0, abs=0.01)
    assert alt.velocity == pytest.approx(3.0, abs=0.02)


def test_altitude_filter_scalars_match_the_matrix_form() -> None:
    """The scalar code against the documented matrix equations, run side by side in numpy."""
    alt = AltitudeFilter()
    alt.reset(baro_ground=11.0, rest_height=0.2)
    p = alt.params
    x = np.array([0.2, 0.0, 0.0])
    cov = np.diag([p.baro_noise**2, 0.01**2, p.initial_bias_sigma**2])
    dt = 0.01
    f = np.array([[1.0, dt, -0.5 * dt * dt], [0.0, 1.0, -dt], [0.0, 0.0, 1.0]])
    g = np.array([0.5 * dt * dt, dt, 0.0])
    h = np.array([1.0, 0.0, 0.0])
    rng = np.random.default_rng(3)
    for _ in range(300):
        c, s = np.cos(0.1), np.sin(0.1)
        rotation = np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])  # rolled 0.1 rad
        accel = np.array([0.0, 0.0, 9.8]) + rng.normal(0.0, 0.5, 3)
        baro = 10.8 + rng.normal(0.0, 0.3)
        alt.step(rotation, accel, baro, dt)
        a = rotation[2] @ accel - 9.8
        x = f @ x + g * a
        cov = f @ cov @ f.T + np.outer(g, g) * p.accel_noise**2 + np.diag([0.0, 0.0, p.bias_walk**2 * dt])
        gain = cov @ h / (h @ cov @ h + p.baro_noise**2)
        x = x + gain * (baro - 10.8 - h @ x)
        cov = cov - np.outer(gain, h @ cov)
    np.testing.assert_allclose([alt.height, alt.velocity, alt.b], x, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(alt.covariance, cov, rtol=1e-9, atol=1e-15)


def test_altitude_reference_from_many_samples_is_trusted_accordingly() -> None:
    # The ground reference is the mean of N barometer readings: uncertain by σ_baro/√N, so one
    # noisy reading right after take-off moves the estimate by K = P/(P + σ²) ≈ 1/(N + 1) of its error.
    level, rest = np.eye(3), np.array([0.0, 0.0, 9.8])
    for samples, expected in ((1, 0.15), (100, 0.3 / 101)):
        alt = AltitudeFilter()
        alt.reset(baro_ground=12.0, rest_height=0.2, samples=samples)
        assert alt.covariance[0, 0] == pytest.approx(0.01 / samples)
        assert alt.step(level, rest, 12.0 + 0.3, 0.01) - 0.2 == pytest.approx(expected, rel=1e-3)
