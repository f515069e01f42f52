"""A recorded host flight as the I/O tile sends it to the flight application, and the float64
golden replay of :class:`HostController` on exactly those samples.

The host controller is wrapped so that every step records its sensor sample and setpoint,
calibration phase included.  Every value is quantised to what the sensor packet carries (Q16.16,
microseconds) and the golden model is :meth:`HostController.step` itself on the quantised values,
so that every difference between the firmware and float64 is arithmetic.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from pathlib import Path
from types import SimpleNamespace

import numpy as np

from robosoc.config.scenario import ScenarioConfig
from robosoc.config.vehicle import vehicle_preset
from robosoc.control.flight import fly
from robosoc.control.host import HostController
from robosoc.control.setpoint import Setpoint
from robosoc.host.packets import FLAG_ARMED, Q16_ONE, SENSOR, q16, to_flits

TAKEOFF_S = 3.0
"""The default flight plan arms at 3 s."""
SENSOR_COLUMNS = 10
"""gyro (3), accel (3), mag (3), barometer altitude."""
SETPOINT_COLUMNS = 6
"""roll, pitch, yaw, height, height rate, height acceleration."""


@dataclass(frozen=True)
class SensorRecord:
    """What the sensor packets carry, one row per sample (Q16.16 integers)."""

    sensors: np.ndarray
    setpoints: np.ndarray
    armed: np.ndarray
    dt_us: int

    @property
    def steps(self) -> int:
        return len(self.armed)

    def window(self, start: int, stop: int) -> SensorRecord:
        """Samples start..stop-1 as a flight of their own (numbered from 0)."""
        return SensorRecord(self.sensors[start:stop], self.setpoints[start:stop], self.armed[start:stop], self.dt_us)

    def packet(self, k: int) -> bytes:
        """Sensor packet k (seq k, time k * dt)."""
        s = self.sensors[k] / Q16_ONE
        sp = self.setpoints[k] / Q16_ONE
        return SENSOR.pack(
            {
                "flags": FLAG_ARMED if self.armed[k] else 0,
                "seq": k,
                "time_us": k * self.dt_us,
                "dt_us": self.dt_us,
                "gyro": tuple(s[0:3]),
                "accel": tuple(s[3:6]),
                "mag": tuple(s[6:9]),
                "baro_altitude": s[9],
                "setpoint": tuple(sp[0:4]),
                "height_feedforward": tuple(sp[4:6]),
            }
        )


class _Recorder(HostController):
    def __init__(self, *args: object, **kwargs: object) -> None:
        super().__init__(*args, **kwargs)  # type: ignore[arg-type]
        self.rows: list[tuple[list[float], list[float], bool]] = []

    def step(self, sample, setpoint: Setpoint) -> tuple[int, int, int, int]:
        sp = setpoint
        self.rows.append(
            (
                [*sample.gyro, *sample.accel, *sample.mag, sample.baro_altitude],
                [sp.roll, sp.pitch, sp.yaw, sp.height, sp.height_rate, sp.height_accel],
                sp.armed,
            )
        )
        return super().step(sample, setpoint)


def _scenario(seconds: float) -> ScenarioConfig:
    return ScenarioConfig(duration_s=seconds)


def record_flight(seconds: float, seed: int = 1) -> SensorRecord:
    """The default scenario flown by the host controller for ``seconds`` (arming at 3 s)."""
    scenario = _scenario(seconds)
    recorder = _Recorder.for_scenario(scenario, vehicle_preset(scenario.vehicle))
    assert isinstance(recorder, _Recorder)
    fly(dataclasses.replace(scenario, seed=seed), vehicle_preset(scenario.vehicle), recorder)
    sensors = np.array([[q16(v) for v in row[0]] for row in recorder.rows], dtype=np.int64)
    setpoints = np.array([[q16(v) for v in row[1]] for row in recorder.rows], dtype=np.int64)
    armed = np.array([row[2] for row in recorder.rows], dtype=bool)
    return SensorRecord(sensors, setpoints, armed, round(recorder.dt * 1e6))


@dataclass(frozen=True)
class Golden:
    """HostController's outputs after each sample."""

    quaternion: np.ndarray
    rate: np.ndarray
    height: np.ndarray
    velocity: np.ndarray
    pwm: np.ndarray


def golden(record: SensorRecord) -> Golden:
    """The float64 controller (HostController.step) on the quantised samples."""
    scenario = _scenario(record.steps * record.dt_us * 1e-6)
    host = HostController.for_scenario(scenario, vehicle_preset(scenario.vehicle))
    assert host.dt == record.dt_us * 1e-6
    host.reset()
    q, rate, h, v, pwm = [], [], [], [], []
    for k in range(record.steps):
        s = record.sensors[k] / Q16_ONE
        sp = record.setpoints[k] / Q16_ONE
        sample = SimpleNamespace(gyro=s[0:3], accel=s[3:6], mag=s[6:9], baro_altitude=float(s[9]))
        setpoint = Setpoint(sp[0], sp[1], sp[2], sp[3], bool(record.armed[k]), sp[4], sp[5])
        pwm.append(host.step(sample, setpoint))
        q.append(host.ekf.quaternion)
        rate.append(s[0:3] - host.ekf.gyro_bias)
        h.append(host.altitude.height)
        v.append(host.altitude.velocity)
    return Golden(np.array(q), np.array(rate), np.array(h), np.array(v), np.array(pwm, dtype=np.int64))


def write_data_header(record: SensorRecord, folder: Path, name: str = "est_data.h") -> Path:
    """``folder/<name>``: the samples as sensor-packet flits."""
    folder.mkdir(parents=True, exist_ok=True)
    lines = [
        "/* generated by tests/firmware/app_data.py */",
        "#include <stdint.h>",
        '#include "robosoc_packets.h"',
        f"#define EST_DATA_STEPS {record.steps}",
        "static const uint16_t est_data_flits[EST_DATA_STEPS][ROBOSOC_SENSOR_FLITS] = {",
        *("    {" + ", ".join(str(f) for f in to_flits(record.packet(k))) + "}," for k in range(record.steps)),
        "};",
    ]
    path = folder / name
    path.write_text("\n".join(lines) + "\n")
    return path
