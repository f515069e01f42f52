"""The controller's parameters for the firmware, generated from the Python configs.

The C controller (``app/pid.c``, ``app/mixer.c``, ``app/altitude.c``) takes every gain, limit and
constant from ``robosoc_control.h``, which this module writes from the golden model itself: the
:class:`~robosoc.control.host.HostController` built for a vehicle and a scenario (its gains,
its mixer's idle and full-thrust forces and yaw coefficient, its height loop's climb and descent
rates, its altitude filter's noise constants).  No number is copied by hand, so the firmware
flies the configuration the host controller flies.

The header also fixes the fixed-point units of the C code (the powers of two below,
docs/firmware-libraries.md) and :func:`control_header` checks that every quantity stored in
them fits Q16.16 (±32768): a configuration that would overflow is an error here, not a
saturated value on the chip.

Build with :func:`control_include_dir` as an include folder::

    build_elf([..., *pid_sources()], include_dirs=[MATH_DIR, APP_DIR, control_include_dir()])

``python -m robosoc.host.control_params [vehicle]`` prints the header.
"""

from __future__ import annotations

import hashlib
import math
import sys
from collections.abc import Sequence
from pathlib import Path

from robosoc.config.power import FAILSAFE_LAND_RATE_MPS, FAILSAFE_LANDED_MARGIN_M
from robosoc.config.scenario import ScenarioConfig
from robosoc.config.vehicle import VehicleConfig, vehicle_preset
from robosoc.control.altitude import GRAVITY, AltitudeFilter
from robosoc.control.host import CALIBRATED_QUAT_SIGMA, GYRO_NOISE, MOTION_ACCEL, HostController
from robosoc.control.pid import PidGains
from robosoc.physics.propulsion import PWM_MAX

HEADER_NAME = "robosoc_control.h"

PID_INTEGRAL_SHIFT = 14
"""PID integrals are stored as I · 2^14: LSB 6.1e-5 · 1.5e-5 = 9.3e-10 (the smallest increment, one
Q16.16 LSB of error over 10 ms, is 164 of them), range ±2 (the limits are 0.2 and 0.5)."""
ALT_P_SHIFT = 20
"""The altitude filter's covariance is stored as P · 2^20 (the EKF's unit): LSB 1.5e-11, so the
smallest process-noise term (Δt²/2)²σ_a² = 3.1e-10 keeps 21 LSB; largest variance 0.031."""
ALT_K_SHIFT = 10
"""The altitude filter's gains are stored as K · 2^10: the bias gain (down to 5e-5) keeps 3,300 LSB."""
ALT_SIGMA_SHIFT = ALT_P_SHIFT // 2
"""σ · 2^10: its square is a variance in the covariance's unit."""
Q16_LIMIT = 32768.0
"""Magnitude limit of a Q16.16 value."""

LOOPS = ("roll", "pitch", "yaw", "height")


def _c(value: float) -> str:
    """A C double literal that reads back as exactly ``value``."""
    if not math.isfinite(value):
        raise ValueError(f"{value} cannot be a C constant")
    text = repr(float(value))
    return text if any(c in text for c in ".e") else text + ".0"


def _check_fits(name: str, value: float) -> None:
    if not abs(value) < Q16_LIMIT:
        raise ValueError(f"{name}: {value:g} does not fit Q16.16 (|value| < 32768) in its fixed-point unit")


def _loop_lines(name: str, gains: PidGains) -> list[str]:
    upper = name.upper()
    has_band = math.isfinite(gains.integral_band)
    lines = [
        f"#define CTL_{upper}_KP {_c(gains.kp)}",
        f"#define CTL_{upper}_KI {_c(gains.ki)}",
        f"#define CTL_{upper}_KD {_c(gains.kd)}",
        f"#define CTL_{upper}_INTEGRAL_LIMIT {_c(gains.integral_limit)}",
        f"#define CTL_{upper}_OUTPUT_LIMIT {_c(gains.output_limit)}",
        f"#define CTL_{upper}_HAS_BAND {int(has_band)}",
        f"#define CTL_{upper}_INTEGRAL_BAND {_c(gains.integral_band if has_band else 0.0)}",
    ]
    for field in ("kp", "ki", "kd", "output_limit", "integral_band"):
        value = getattr(gains, field)
        if math.isfinite(value):
            _check_fits(f"{name}.{field}", value)
    stored = gains.integral_limit * 2**PID_INTEGRAL_SHIFT
    _check_fits(f"{name}.integral_limit (stored · 2^{PID_INTEGRAL_SHIFT})", stored)
    return lines


def control_header(vehicle: VehicleConfig | None = None, scenario: ScenarioConfig | None = None) -> str:
    """The text of ``robosoc_control.h`` for ``vehicle`` flying ``scenario`` (defaults: the default
    scenario and its vehicle preset).

    Raises:
        ValueError: a parameter that does not fit its fixed-point unit.
    """
    scenario = scenario or ScenarioConfig()
    vehicle = vehicle or vehicle_preset(scenario.vehicle)
    host = HostController.for_scenario(scenario, vehicle)
    gains = host.gains
    mixer = host.mixer
    motor = vehicle.motor
    height = host.height_loop
    alt = host.altitude.params
    probe = AltitudeFilter(alt)
    probe.reset(0.0, 0.0)
    velocity_sigma = math.sqrt(probe.p11)

    # Equation 3 inverted and the motor model folded into few constants (mixer.c).
    root_ct0s = math.sqrt(motor.ct0s)
    counts_per_volt = PWM_MAX / motor.supply_voltage
    mix = {
        "MIX_ROLL_PITCH_GAIN": (1.0 / (2.0 * mixer.arm), "r = u_roll / (2 l), p = u_pitch / (2 l) [N per N m]"),
        "MIX_YAW_GAIN": (1.0 / (4.0 * mixer.yaw_k), "y = u_yaw / (4 k), k the yaw coefficient at hover [N per N m]"),
        "MIX_MIN_FORCE": (mixer.min_force, "thrust at idle_pwm in steady state [N]"),
        "MIX_MAX_FORCE": (mixer.max_force, "thrust at full supply voltage [N]"),
        "MIX_CURRENT_PER_FORCE": (motor.k_t / motor.psi, "k_t / Psi: I = this f + MIX_CURRENT_PER_ROOT_FORCE sqrt(f)"),
        "MIX_CURRENT_PER_ROOT_FORCE": (motor.k_m / (motor.psi * root_ct0s), "k_m / (Psi sqrt(CT0s)), w = sqrt(f/CT0s)"),
        "MIX_COUNTS_PER_SQUARE_CURRENT": (motor.r_a * counts_per_volt, "R_A * 255 / V_s"),
        "MIX_COUNTS_PER_CURRENT_ROOT_FORCE": (motor.psi / root_ct0s * counts_per_volt, "Psi / sqrt(CT0s) * 255 / V_s"),
        "MIX_ALPHA_M": (motor.alpha_m, "alpha_m of the current model"),
        "MIX_BETA_M": (motor.beta_m, "beta_m of the current model"),
    }
    for name, (value, _) in mix.items():
        _check_fits(name, value)
    t_top = height.max_tilt_gain * (gains.height.output_limit + height.mass * (height.gravity + 10.0))
    _check_fits("largest thrust command (max_tilt_gain · (output_limit + m·(g + 10 m/s²)))", t_top)
    for name, value in (
        ("baro_noise² · 2^20", alt.baro_noise**2 * 2**ALT_P_SHIFT),
        ("initial_bias_sigma² · 2^20", alt.initial_bias_sigma**2 * 2**ALT_P_SHIFT),
        ("accel_noise · 2^10", alt.accel_noise * 2**ALT_SIGMA_SHIFT),
        ("bias_walk² · 2^20", alt.bias_walk**2 * 2**ALT_P_SHIFT),
    ):
        _check_fits(f"altitude {name}", value)

    lines = [
        "/*",
        f" * {HEADER_NAME} - the controller's parameters and fixed-point units.",
        " *",
        " * GENERATED by src/robosoc/host/control_params.py from the golden model built for",
        f' * vehicle "{vehicle.name}" ({vehicle.variant}, {vehicle.mass} kg) and scenario "{scenario.name}":',
        " * HostController.for_scenario(scenario, vehicle).  Do not edit; doubles are exact reprs.",
        " */",
        "#ifndef ROBOSOC_CONTROL_H",
        "#define ROBOSOC_CONTROL_H",
        "",
        "/* Fixed-point units (powers of two, exact in the float build): docs/firmware-libraries.md */",
        f"#define PID_INTEGRAL_SHIFT {PID_INTEGRAL_SHIFT}",
        f"#define ALT_P_SHIFT {ALT_P_SHIFT}",
        f"#define ALT_K_SHIFT {ALT_K_SHIFT}",
        f"#define ALT_SIGMA_SHIFT {ALT_SIGMA_SHIFT}",
        "",
        "/* PID loops (control/pid.py): gains, integral and output limits, integral band */",
    ]
    for name in LOOPS:
        lines += _loop_lines(name, getattr(gains, name))
    lines += [
        "",
        "/* Height control (control/pid.py HeightController) */",
        f"#define CTL_POSITION_GAIN {_c(height.position_gain)} /* K_p / K_d [1/s] */",
        f"#define CTL_CLIMB_RATE {_c(height.climb_rate)} /* [m/s] */",
        f"#define CTL_DESCENT_RATE {_c(height.descent_rate)} /* [m/s] */",
        f"#define CTL_MAX_TILT_GAIN {_c(height.max_tilt_gain)} /* upper limit of 1 / (cos roll cos pitch) */",
        f"#define CTL_MASS {_c(height.mass)} /* [kg] */",
        f"#define CTL_GRAVITY {_c(height.gravity)} /* [m/s^2] */",
        "",
        "/* Mixer (control/mixer.py) */",
        f"#define MIX_IDLE_PWM {mixer.idle_pwm}",
        f"#define MIX_PWM_MAX {PWM_MAX}",
    ]
    lines += [f"#define {name} {_c(value)} /* {doc} */" for name, (value, doc) in mix.items()]
    lines += [
        "",
        "/* Calibration while disarmed (control/host.py), the estimator task's (app/estimator.c) */",
        f"#define CAL_MOTION_ACCEL {_c(MOTION_ACCEL)} /* |norm(a) - g| above this is motion [m/s^2] */",
        f"#define CAL_QUAT_SIGMA {_c(CALIBRATED_QUAT_SIGMA)} /* sigma of each quaternion component, calibrated */",
        f"#define CAL_GYRO_NOISE {_c(GYRO_NOISE)} /* one gyro sample: bias sigma * sqrt(n) [rad/s] */",
        "",
        "/* Altitude filter (control/altitude.py) */",
        f"#define ALT_ACCEL_NOISE {_c(alt.accel_noise)} /* [m/s^2] */",
        f"#define ALT_BIAS_WALK {_c(alt.bias_walk)} /* [m/s^2/sqrt(s)] */",
        f"#define ALT_BARO_NOISE {_c(alt.baro_noise)} /* [m] */",
        f"#define ALT_INITIAL_BIAS_SIGMA {_c(alt.initial_bias_sigma)} /* [m/s^2] */",
        f"#define ALT_INITIAL_VELOCITY_SIGMA {_c(velocity_sigma)} /* [m/s], AltitudeFilter.reset */",
        f"#define ALT_GRAVITY {_c(GRAVITY)} /* [m/s^2] */",
        f"#define ALT_REST_HEIGHT {_c(vehicle.rest_height)} /* body origin above the ground at rest [m] */",
    ]
    if scenario.power.battery_on:  # only then: a flight on the constant supply builds the same firmware
        lines += [
            "",
            "/* Low-battery failsafe (docs/power.md): below the reserve the I/O tile sets ROBOSOC_FLAG_LOW_BATTERY;",
            " * the PID task then levels the vehicle, climbs or descends at CTL_LAND_RATE to CTL_FAILSAFE_HEIGHT,",
            " * holds it CTL_FAILSAFE_HOLD seconds, descends at CTL_LAND_RATE and disarms on the ground */",
            "#define CTL_FAILSAFE 1",
            f"#define CTL_LAND_RATE {_c(FAILSAFE_LAND_RATE_MPS)} /* [m/s] */",
            f"#define CTL_FAILSAFE_HEIGHT {_c(scenario.power.failsafe_height_m)} /* [m] */",
            f"#define CTL_FAILSAFE_HOLD {_c(scenario.power.failsafe_hold_s)} /* [s] */",
            f"#define CTL_LANDED_HEIGHT {_c(vehicle.rest_height + FAILSAFE_LANDED_MARGIN_M)} /* estimated height"
            " at which it disarms [m] */",
            f"#define CTL_LAND_FLOOR {_c(vehicle.rest_height - FAILSAFE_LANDED_MARGIN_M)} /* lowest setpoint [m] */",
        ]
    lines += [
        "",
        "#endif /* ROBOSOC_CONTROL_H */",
        "",
    ]
    return "\n".join(lines)


def write_control_header(
    folder: Path, vehicle: VehicleConfig | None = None, scenario: ScenarioConfig | None = None
) -> Path:
    """Write ``folder/robosoc_control.h`` (only if its text changed, so builds stay cached)."""
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / HEADER_NAME
    text = control_header(vehicle, scenario)
    if not path.is_file() or path.read_text() != text:
        path.write_text(text)
    return path


def control_include_dir(vehicle: VehicleConfig | None = None, scenario: ScenarioConfig | None = None) -> Path:
    """A folder in the project cache holding ``robosoc_control.h`` for this configuration (one
    folder per distinct header text); pass it as an include folder."""
    from robosoc.cache import cache_root

    text = control_header(vehicle, scenario)
    folder = cache_root() / "control" / hashlib.sha256(text.encode()).hexdigest()[:16]
    write_control_header(folder, vehicle, scenario)
    return folder


def main(argv: Sequence[str] | None = None) -> int:
    """Print the header for a vehicle preset (default: the default scenario's vehicle)."""
    args = list(sys.argv[1:] if argv is None else argv)
    vehicle = vehicle_preset(args[0]) if args else None
    sys.stdout.write(control_header(vehicle))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
