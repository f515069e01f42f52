"""A recorded PID and altitude-filter input sequence from a host flight, the C data header for
the harness, the float64 golden replays, and the harness's output parsed back.

The host controller is wrapped so that every armed step records what the PID task and the
altitude filter receive on the chip: the EKF's quaternion, the bias-corrected body rates, the
altitude filter's height and vertical velocity, the setpoint (with the height profile's rate and
acceleration), and for the filter its calibration (the last reset before arming), the calibrated
accelerometer and the barometer.  Every value is quantised to Q16.16 (as the packets carry it)
and the golden models are replayed on exactly those values: the PID through
:meth:`HostController.step` itself, with the filters replaced by the recorded values, so that
every difference between the builds and float64 is arithmetic.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from pathlib import Path
from types import SimpleNamespace

import numpy as np

from robosoc.config.scenario import ScenarioConfig
from robosoc.config.vehicle import vehicle_preset
from robosoc.control import quaternion as quat
from robosoc.control.altitude import AltitudeFilter
from robosoc.control.flight import fly
from robosoc.control.host import HostController
from robosoc.control.setpoint import Setpoint
from robosoc.firmware import ALTITUDE_SOURCES, APP_DIR, MATH_DIR, arith_defines, pid_sources
from robosoc.host.control_params import control_include_dir
from robosoc.host.packets import ESTIMATE, FLAG_ARMED, Q16_ONE, q16, to_flits
from robosoc.toolchain import build_elf, compile_native

HARNESS = Path(__file__).resolve().parent / "pid_harness.c"
TAKEOFF_S = 3.0
"""The default flight plan arms at 3 s."""
PID_COLUMNS = 15
"""Per step: q (4), rate (3), height, velocity, setpoint roll, pitch, yaw, height, rate, accel."""
ALT_COLUMNS = 4
"""Per step: calibrated accelerometer (3), barometer altitude."""


@dataclass(frozen=True)
class PidRecord:
    """The PID's and the altitude filter's inputs, as Q16.16 integers, one row per step."""

    pid: np.ndarray
    alt: np.ndarray
    alt_reset: tuple[int, int, int]
    """baro_ground, rest_height (Q16.16) and the number of calibration samples."""
    dt_us: np.ndarray

    @property
    def steps(self) -> int:
        return len(self.dt_us)

    def values(self, table: np.ndarray) -> np.ndarray:
        return table / Q16_ONE


class _RecordingAltitude(AltitudeFilter):
    def reset(self, baro_ground: float, rest_height: float, samples: int = 1) -> None:
        self.reset_args = (baro_ground, rest_height, samples)
        super().reset(baro_ground, rest_height, samples)


class _RecordingController(HostController):
    def __init__(self, *args: object, **kwargs: object) -> None:
        super().__init__(*args, **kwargs)  # type: ignore[arg-type]
        self.altitude = _RecordingAltitude(self.altitude.params)
        self.reset()
        self.pid_rows: list[list[float]] = []
        self.alt_rows: list[list[float]] = []
        self.alt_reset_args: tuple[float, float, int] | None = None

    def step(self, sample, setpoint: Setpoint) -> tuple[int, int, int, int]:
        reset_args = self.altitude.reset_args
        pwm = super().step(sample, setpoint)
        if setpoint.armed:
            if self.alt_reset_args is None:
                self.alt_reset_args = reset_args
            rate = np.asarray(sample.gyro) - self.ekf.gyro_bias
            sp = setpoint
            self.pid_rows.append(
                [
                    *self.ekf.quaternion,
                    *rate,
                    self.altitude.height,
                    self.altitude.velocity,
                    sp.roll,
                    sp.pitch,
                    sp.yaw,
                    sp.height,
                    sp.height_rate,
                    sp.height_accel,
                ]
            )
            self.alt_rows.append([*(np.asarray(sample.accel) - self.accel_bias), sample.baro_altitude])
        return pwm


def _controller(seconds: float) -> tuple[ScenarioConfig, HostController]:
    scenario = ScenarioConfig(duration_s=TAKEOFF_S + seconds)
    return scenario, HostController.for_scenario(scenario, vehicle_preset(scenario.vehicle))


def record_flight(seconds: float, seed: int = 1) -> PidRecord:
    """Fly the default scenario with the host controller for ``seconds`` after take-off."""
    scenario = ScenarioConfig(duration_s=TAKEOFF_S + seconds)
    vehicle = vehicle_preset(scenario.vehicle)
    recorder = _RecordingController(vehicle, scenario.sensors.period_steps * 0.001)
    fly(dataclasses.replace(scenario, seed=seed), vehicle, recorder)
    assert recorder.alt_reset_args is not None
    ground, rest, samples = recorder.alt_reset_args

    def table(rows: list[list[float]]) -> np.ndarray:
        return np.array([[q16(v) for v in row] for row in rows], dtype=np.int64)

    dt_us = np.full(len(recorder.pid_rows), round(recorder.dt * 1e6), dtype=np.int64)
    return PidRecord(table(recorder.pid_rows), table(recorder.alt_rows), (q16(ground), q16(rest), samples), dt_us)


def write_data_header(record: PidRecord, folder: Path) -> Path:
    """``folder/pid_data.h``: the PID task's inputs as estimate-packet flits, the altitude filter's
    as Q16.16 integers."""
    folder.mkdir(parents=True, exist_ok=True)
    lines = [
        "/* generated by tests/firmware/pid_data.py */",
        "#include <stdint.h>",
        '#include "robosoc_packets.h"',
        f"#define PID_DATA_STEPS {record.steps}",
        "static const int32_t alt_data_reset[3] = {" + ", ".join(str(int(v)) for v in record.alt_reset) + "};",
        "static const uint16_t pid_data_flits[PID_DATA_STEPS][ROBOSOC_ESTIMATE_FLITS] = {",
    ]
    time_us = 0
    for k, row in enumerate(record.values(record.pid)):
        time_us += int(record.dt_us[k])
        packet = ESTIMATE.pack(
            {
                "flags": FLAG_ARMED,
                "seq": k,
                "time_us": time_us,
                "dt_us": int(record.dt_us[k]),
                "quaternion": tuple(row[0:4]),
                "rate": tuple(row[4:7]),
                "height": row[7],
                "vertical_velocity": row[8],
                "setpoint": tuple(row[9:13]),
                "height_feedforward": tuple(row[13:15]),
            }
        )
        lines.append("    {" + ", ".join(str(f) for f in to_flits(packet)) + "},")
    lines += [
        "};",
        f"static const int32_t alt_data[PID_DATA_STEPS][{ALT_COLUMNS}] = {{",
        *("    {" + ", ".join(str(int(v)) for v in row) + "}," for row in record.alt),
        "};",
    ]
    path = folder / "pid_data.h"
    path.write_text("\n".join(lines) + "\n")
    return path


class _ReplayEkf:
    """Stands in for the EKF: the recorded quaternion of step ``k``; the rates come bias-free."""

    def __init__(self, quaternions: np.ndarray) -> None:
        self.quaternions = quaternions
        self.k = 0
        self.gyro_bias = np.zeros(3)

    @property
    def quaternion(self) -> np.ndarray:
        return self.quaternions[self.k]

    def reset(self, *args: object, **kwargs: object) -> None:
        pass

    def step(self, gyro: np.ndarray, accel: np.ndarray, mag: np.ndarray, dt: float) -> np.ndarray:
        return self.quaternion


class _ReplayAltitude:
    """Stands in for the altitude filter: the recorded height and vertical velocity of step ``k``."""

    def __init__(self, heights: np.ndarray, velocities: np.ndarray) -> None:
        self.heights = heights
        self.velocities = velocities
        self.k = 0

    @property
    def height(self) -> float:
        return float(self.heights[self.k])

    @property
    def velocity(self) -> float:
        return float(self.velocities[self.k])

    def reset(self, *args: object, **kwargs: object) -> None:
        pass

    def step(self, rotation: np.ndarray, accel: np.ndarray, baro_altitude: float, dt: float) -> float:
        return self.height


@dataclass(frozen=True)
class GoldenPid:
    pwm: np.ndarray
    """steps × 4 counts."""
    u: np.ndarray
    """steps × 4: u_z, u_roll, u_pitch, u_yaw (0 while disarmed)."""


def golden_pid(record: PidRecord, disarmed: range = range(0)) -> GoldenPid:
    """The float64 PID and mixer on the quantised inputs, run by HostController.step itself with the
    filters replaced by the recorded values (disarmed at the steps in ``disarmed``)."""
    _, host = _controller(record.steps * 0.01)
    values = record.values(record.pid)
    ekf = _ReplayEkf(values[:, 0:4])
    altitude = _ReplayAltitude(values[:, 7], values[:, 8])
    host.ekf = ekf  # type: ignore[assignment]
    host.altitude = altitude  # type: ignore[assignment]
    host.reset()
    outputs: list[tuple[float, float, float, float]] = []
    mixer_pwm = host.mixer.pwm

    def pwm_recorded(u_z: float, u_roll: float, u_pitch: float, u_yaw: float) -> tuple[int, int, int, int]:
        outputs.append((u_z, u_roll, u_pitch, u_yaw))
        return mixer_pwm(u_z, u_roll, u_pitch, u_yaw)

    host.mixer.pwm = pwm_recorded  # type: ignore[method-assign]
    pwm = np.zeros((record.steps, 4), dtype=np.int64)
    u = np.zeros((record.steps, 4))
    level = np.array([0.0, 0.0, 9.8])
    for k, row in enumerate(values):
        ekf.k = altitude.k = k
        armed = k not in disarmed
        assert record.dt_us[k] * 1e-6 == host.dt
        setpoint = Setpoint(row[9], row[10], row[11], row[12], armed, row[13], row[14])
        sample = SimpleNamespace(gyro=row[4:7], accel=level, mag=np.array([0.5, 0.0, -0.866]), baro_altitude=0.0)
        pwm[k] = host.step(sample, setpoint)
        if armed:
            u[k] = outputs[-1]
    return GoldenPid(pwm, u)


@dataclass(frozen=True)
class GoldenAltitude:
    states: np.ndarray
    """steps × 3: h, v, b."""
    covariance: np.ndarray
    """The final P (3 × 3)."""


def golden_altitude(record: PidRecord) -> GoldenAltitude:
    """The float64 altitude filter on the quantised inputs, called as host.py calls it (R(q))."""
    _, host = _controller(record.steps * 0.01)
    filt = AltitudeFilter(host.altitude.params)
    ground, rest, samples = record.alt_reset
    filt.reset(ground / Q16_ONE, rest / Q16_ONE, samples)
    q = record.values(record.pid[:, 0:4])
    alt = record.values(record.alt)
    states = np.empty((record.steps, 3))
    for k in range(record.steps):
        filt.step(quat.to_matrix(q[k]), alt[k, 0:3], alt[k, 3], int(record.dt_us[k]) * 1e-6)
        states[k] = (filt.h, filt.v, filt.b)
    return GoldenAltitude(states, filt.covariance)


def decode(words: list[str], arith: str) -> np.ndarray:
    """real_t bit patterns (hex words) as float64 values."""
    raw = np.array([int(w, 16) for w in words], dtype=np.uint32)
    if arith == "float":
        return raw.view(np.float32).astype(np.float64)
    return raw.view(np.int32).astype(np.float64) / Q16_ONE


@dataclass(frozen=True)
class HarnessRun:
    """The harness's output, parsed."""

    pwm: np.ndarray
    u: np.ndarray
    alt: np.ndarray
    """h, v, b per step."""
    covariance: np.ndarray
    """The final P in natural units (3 × 3)."""
    pid_cycles: np.ndarray
    mix_cycles: np.ndarray
    alt_cycles: np.ndarray
    malformed: int
    """Packets of another kind refused."""


def parse_output(text: str, arith: str, p_shift: int) -> HarnessRun:
    pwm, u, alt, cycles = [], [], [], []
    covariance = np.zeros((3, 3))
    malformed = -1
    for line in text.splitlines():
        words = line.split()
        if words[0] == "step":
            assert int(words[1]) == len(pwm)
            cycles.append([int(w) for w in words[2:5]])
            pwm.append([int(w) for w in words[5:9]])
            u.append(decode(words[9:13], arith))
            alt.append(decode(words[13:16], arith))
        elif words[0] == "p":
            p00, p01, p02, p11, p12, p22 = decode(words[1:7], arith) / 2.0**p_shift
            covariance = np.array([[p00, p01, p02], [p01, p11, p12], [p02, p12, p22]])
        elif words[0] == "malformed":
            malformed = int(words[1])
    c = np.array(cycles, dtype=np.int64).reshape(-1, 3)
    return HarnessRun(np.array(pwm), np.array(u), np.array(alt), covariance, c[:, 0], c[:, 1], c[:, 2], malformed)


def include_dirs(data_dir: Path) -> list[Path]:
    return [data_dir, MATH_DIR, APP_DIR, control_include_dir()]


def harness_sources() -> list[Path]:
    return [HARNESS, *ALTITUDE_SOURCES, *pid_sources()]


def build_harness_elf(data_dir: Path, arith: str, mul: bool) -> Path:
    return build_elf(harness_sources(), mul=mul, defines=arith_defines(arith), include_dirs=include_dirs(data_dir))


def build_harness_native(
    data_dir: Path, arith: str, disarmed: range = range(0), malformed_at: int | None = None
) -> Path:
    defines = arith_defines(arith)
    if disarmed:
        defines["DISARM_FROM"] = disarmed.start
        defines["DISARM_TO"] = disarmed.stop
    if malformed_at is not None:
        defines["MALFORMED_AT"] = malformed_at
    return compile_native(harness_sources(), defines=defines, include_dirs=include_dirs(data_dir))
