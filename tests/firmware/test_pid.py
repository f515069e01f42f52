"""The firmware PID task (PID loops, height control, mixer) and altitude filter against the float64
golden models, on a recorded host flight.

The issue's figure: the PID outputs within one PWM count of the golden model on at least 99 % of
samples in every build.  Host-native builds run 10 s of steps (the same C gives the same bits on the
core, which the core tests check); the core runs 2 s in each of the four builds {float, fixed} x
{mul, no-mul}.  A sample counts as matching when all four motors are within one count.
"""

import re
from pathlib import Path

import numpy as np
import pytest
from pid_data import (
    GoldenAltitude,
    GoldenPid,
    HarnessRun,
    PidRecord,
    build_harness_elf,
    build_harness_native,
    golden_altitude,
    golden_pid,
    parse_output,
    record_flight,
    write_data_header,
)

from robosoc.config.scenario import FlightPlan, ScenarioConfig
from robosoc.config.vehicle import MotorConfig, VehicleConfig, laser_vehicle, vehicle_preset
from robosoc.control.host import HostController
from robosoc.control.mixer import Mixer
from robosoc.firmware import APP_DIR, ARITHS, MATH_DIR, arith_defines, math_sources
from robosoc.host.control_params import ALT_P_SHIFT, control_header, control_include_dir
from robosoc.host.packets import Q16_ONE, q16
from robosoc.toolchain import compile_native, run_native

single = pytest.importorskip("robosoc.chip.single")

MATCH_SHARE = 0.99
"""Share of samples whose four PWM counts are all within one count of the golden model's."""
MIXER_CHECK = Path(__file__).resolve().parent / "mixer_check.c"
# Error bounds of the altitude filter against float64 (h [m], v [m/s], b [m/s²]); the fixed
# build's are mostly dt = 10 ms held as 655 LSB (-0.055 %), docs/firmware-libraries.md.
ALT_FLOAT_BOUND = 1e-5
ALT_FIXED_BOUND = np.array([1e-3, 3e-3, 3e-3])
# u_z [N], u_roll, u_pitch, u_yaw [N m] against float64
U_FLOAT_BOUND = np.array([1e-4, 1e-5, 1e-5, 1e-5])
U_FIXED_BOUND = np.array([2e-3, 2e-4, 2e-4, 2e-4])


class Flight:
    def __init__(self, record: PidRecord, folder: Path) -> None:
        self.record = record
        self.folder = folder
        write_data_header(record, folder)
        self.golden: GoldenPid = golden_pid(record)
        self.golden_alt: GoldenAltitude = golden_altitude(record)
        self._native: dict[str, HarnessRun] = {}

    def native(self, arith: str) -> HarnessRun:
        if arith not in self._native:
            code, out = run_native(build_harness_native(self.folder, arith), timeout=300)
            assert code == 0
            self._native[arith] = parse_output(out.decode(), arith, ALT_P_SHIFT)
        return self._native[arith]


@pytest.fixture(scope="module")
def flight_10s(tmp_path_factory: pytest.TempPathFactory) -> Flight:
    return Flight(record_flight(10.0), tmp_path_factory.mktemp("pid10"))


@pytest.fixture(scope="module")
def flight_2s(tmp_path_factory: pytest.TempPathFactory) -> Flight:
    return Flight(record_flight(2.0), tmp_path_factory.mktemp("pid2"))


def _match_share(pwm: np.ndarray, golden: np.ndarray) -> float:
    return float(np.mean(np.max(np.abs(pwm - golden), axis=1) <= 1))


def _check_accuracy(flight: Flight, arith: str, run: HarnessRun) -> None:
    steps = flight.record.steps
    assert run.pwm.shape == (steps, 4)
    assert _match_share(run.pwm, flight.golden.pwm) >= MATCH_SHARE
    assert np.all(np.abs(run.u - flight.golden.u) <= (U_FLOAT_BOUND if arith == "float" else U_FIXED_BOUND))
    alt_error = np.max(np.abs(run.alt - flight.golden_alt.states), axis=0)
    assert np.all(alt_error <= (ALT_FLOAT_BOUND if arith == "float" else ALT_FIXED_BOUND)), alt_error
    diag = np.diag(flight.golden_alt.covariance)
    tolerance = 1e-4 if arith == "float" else 5e-3
    assert np.all(np.abs(np.diag(run.covariance) - diag) <= tolerance * diag)


@pytest.mark.parametrize("arith", ARITHS)
def test_ten_seconds_host_native(flight_10s: Flight, arith: str) -> None:
    assert flight_10s.record.steps == 1000
    # the flight exercises the height profile's feed-forward (the mixer's limits: the mixer test)
    assert np.any(flight_10s.record.pid[:, 13] != 0) and np.any(flight_10s.record.pid[:, 14] != 0)
    _check_accuracy(flight_10s, arith, flight_10s.native(arith))


@pytest.mark.parametrize("mul", [True, False], ids=["mul", "no-mul"])
@pytest.mark.parametrize("arith", ARITHS)
def test_on_core_equals_host_native(flight_2s: Flight, arith: str, mul: bool) -> None:
    # errata="rtl": the core computes MULHSU as the RTL does (wrongly); the firmware must not use it
    elf = build_harness_elf(flight_2s.folder, arith, mul)
    result = single.run_elf(elf, mul=mul, max_cycles=2_000_000_000, errata="rtl")
    assert result.exit_code == 0
    assert result.errata["mulhsu"] == 0
    core = parse_output(result.output.decode(), arith, ALT_P_SHIFT)
    host = flight_2s.native(arith)
    assert np.array_equal(core.pwm, host.pwm)
    assert np.array_equal(core.u, host.u)
    assert np.array_equal(core.alt, host.alt)
    assert np.array_equal(core.covariance, host.covariance)
    assert np.all(core.pid_cycles > 0) and np.all(core.alt_cycles > 0)
    _check_accuracy(flight_2s, arith, core)


@pytest.mark.parametrize("arith", ARITHS)
def test_disarming_stops_the_motors_and_rearming_restarts_the_loops(flight_2s: Flight, arith: str) -> None:
    disarmed = range(60, 75)
    code, out = run_native(build_harness_native(flight_2s.folder, arith, disarmed=disarmed))
    assert code == 0
    run = parse_output(out.decode(), arith, ALT_P_SHIFT)
    golden = golden_pid(flight_2s.record, disarmed=disarmed)
    assert np.all(run.pwm[disarmed.start : disarmed.stop] == 0)
    assert np.all(golden.pwm[disarmed.start : disarmed.stop] == 0)
    assert _match_share(run.pwm, golden.pwm) >= MATCH_SHARE
    # the integrals restarted: the run differs from the uninterrupted one after re-arming
    assert not np.array_equal(golden.pwm[disarmed.stop :], flight_2s.golden.pwm[disarmed.stop :])


@pytest.mark.parametrize("arith", ARITHS)
def test_a_packet_of_another_kind_is_refused_and_changes_nothing(flight_2s: Flight, arith: str) -> None:
    code, out = run_native(build_harness_native(flight_2s.folder, arith, malformed_at=40))
    assert code == 0
    run = parse_output(out.decode(), arith, ALT_P_SHIFT)
    assert run.malformed == 1
    assert np.array_equal(run.pwm, flight_2s.native(arith).pwm)


def _mixer_inputs(count: int, seed: int = 3) -> np.ndarray:
    """Thrust [N] and torques [N m] over and beyond the controller's limits: every desaturation case."""
    rng = np.random.default_rng(seed)
    u = np.column_stack(
        (
            rng.uniform(-5.0, 50.0, count),
            rng.uniform(-4.0, 4.0, count) * rng.choice([0.05, 1.0], count),
            rng.uniform(-4.0, 4.0, count) * rng.choice([0.05, 1.0], count),
            rng.uniform(-0.4, 0.4, count) * rng.choice([0.05, 1.0], count),
        )
    )
    return np.vectorize(q16)(u).astype(np.int64)


@pytest.mark.parametrize("arith", ARITHS)
def test_mixer_against_the_golden_model(tmp_path: Path, arith: str) -> None:
    count = 3000
    table = _mixer_inputs(count)
    lines = ["#include <stdint.h>", f"#define MIXER_DATA_ROWS {count}", "static const int32_t mixer_data[][4] = {"]
    lines += ["    {" + ", ".join(str(int(v)) for v in row) + "}," for row in table]
    (tmp_path / "mixer_data.h").write_text("\n".join([*lines, "};", ""]))
    exe = compile_native(
        [MIXER_CHECK, *math_sources(), APP_DIR / "mixer.c"],
        defines=arith_defines(arith),
        include_dirs=[tmp_path, MATH_DIR, APP_DIR, control_include_dir()],
    )
    code, out = run_native(exe)
    assert code == 0
    rows = [line.split() for line in out.decode().splitlines()]
    pwm = np.array([[int(w) for w in row[2:6]] for row in rows])
    raw = np.array([[int(w, 16) for w in row[6:10]] for row in rows], dtype=np.uint32)
    forces = raw.view(np.float32).astype(float) if arith == "float" else raw.view(np.int32) / Q16_ONE
    host = HostController.for_scenario(ScenarioConfig(), vehicle_preset("default"))
    mixer: Mixer = host.mixer
    u = table / Q16_ONE
    golden_forces = np.array([mixer.forces(*row) for row in u])
    golden_pwm = np.array([mixer.pwm(*row) for row in u])
    saturated = np.any(np.isclose(golden_forces, mixer.min_force) | np.isclose(golden_forces, mixer.max_force), axis=1)
    assert 0.3 < np.mean(saturated) < 0.9  # both sides of the limits are exercised
    force_bound = 1e-5 if arith == "float" else 2e-4
    assert np.max(np.abs(forces - golden_forces)) <= force_bound
    assert np.all(forces >= mixer.min_force - force_bound) and np.all(forces <= mixer.max_force + force_bound)
    assert np.max(np.abs(pwm - golden_pwm)) <= 1
    assert np.mean(np.abs(pwm - golden_pwm) == 0) >= 0.99
    assert np.all((pwm >= mixer.idle_pwm) & (pwm <= 255))


def _defines(text: str) -> dict[str, float]:
    return {m[1]: float(m[2]) for m in re.finditer(r"^#define (\w+) (\S+)", text, re.MULTILINE)}


@pytest.mark.parametrize("vehicle", [vehicle_preset("default"), laser_vehicle()], ids=["default", "laser"])
def test_parameters_are_the_golden_models(vehicle: VehicleConfig) -> None:
    scenario = ScenarioConfig(flight=FlightPlan(climb_rate_mps=1.5, descent_rate_mps=0.5))
    defines = _defines(control_header(vehicle, scenario))
    host = HostController.for_scenario(scenario, vehicle)
    for name in ("roll", "pitch", "yaw", "height"):
        gains = getattr(host.gains, name)
        upper = name.upper()
        assert defines[f"CTL_{upper}_KP"] == gains.kp
        assert defines[f"CTL_{upper}_KI"] == gains.ki
        assert defines[f"CTL_{upper}_KD"] == gains.kd
        assert defines[f"CTL_{upper}_INTEGRAL_LIMIT"] == gains.integral_limit
        assert defines[f"CTL_{upper}_OUTPUT_LIMIT"] == gains.output_limit
        assert bool(defines[f"CTL_{upper}_HAS_BAND"]) == np.isfinite(gains.integral_band)
    assert defines["CTL_HEIGHT_INTEGRAL_BAND"] == host.gains.height.integral_band
    assert (defines["CTL_CLIMB_RATE"], defines["CTL_DESCENT_RATE"]) == (1.5, 0.5)
    assert defines["CTL_MASS"] == vehicle.mass
    assert defines["CTL_MAX_TILT_GAIN"] == host.gains.max_tilt_gain
    assert defines["MIX_IDLE_PWM"] == vehicle.idle_pwm
    assert defines["MIX_MIN_FORCE"] == host.mixer.min_force
    assert defines["MIX_MAX_FORCE"] == host.mixer.max_force
    assert defines["MIX_YAW_GAIN"] == pytest.approx(1.0 / (4.0 * host.mixer.yaw_k), rel=1e-15)
    assert defines["ALT_ACCEL_NOISE"] == host.altitude.params.accel_noise
    assert defines["ALT_REST_HEIGHT"] == vehicle.rest_height


def test_a_parameter_outside_its_fixed_point_unit_is_an_error() -> None:
    vehicle = VehicleConfig(motor=MotorConfig(k_m=10.0))  # in its range, but k_m / (Psi sqrt(CT0s)) is too large
    with pytest.raises(ValueError, match=r"MIX_CURRENT_PER_ROOT_FORCE: .* does not fit Q16\.16"):
        control_header(vehicle)


def test_the_include_folder_follows_the_configuration() -> None:
    default = control_include_dir()
    assert default == control_include_dir()
    assert control_include_dir(laser_vehicle()) != default
    assert (default / "robosoc_control.h").read_text() == control_header()
