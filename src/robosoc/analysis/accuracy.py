"""Accuracy of the firmware's outputs: its estimates against the float64 golden model, against the
truth and between builds; its PWM commands against the golden model's on the same inputs.

The seed's terms (seed paper §V): "mean error ... of 0.19 %, that is, each component of the
resulting quaternion has a mean value error from its reference of 0.0019" — the mean over samples
and the four components of |q_a − q_b| (:attr:`QuaternionError.mean_component`, printed as a
percentage of a unit quaternion's norm).  Beside it the mean and largest rotation angle between
the two attitudes in degrees, which does not depend on how the quaternion is written (q and −q are
one attitude: components are compared after aligning the sign).

The golden model runs on exactly what the chip received: each flight row is packed into its sensor
packet (:func:`robosoc.cosim.replay.sensor_packet`, Q16.16 and microseconds) and unpacked again,
so every difference between the firmware and float64 is arithmetic.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from types import SimpleNamespace

import numpy as np

from robosoc.config.scenario import ScenarioConfig
from robosoc.config.vehicle import VehicleConfig, vehicle_preset
from robosoc.control.flight import ROW_FIELDS
from robosoc.control.host import HostController
from robosoc.control.setpoint import Setpoint
from robosoc.host.packets import FLAG_ARMED, SENSOR, array, scalar

TRUTH_QUATERNION = tuple(ROW_FIELDS.index(c) for c in ("qw", "qx", "qy", "qz"))
"""Columns of the true attitude in a flight row."""


@dataclass(frozen=True)
class GoldenRun:
    """The float64 controller after each sample of a flight (rows of :data:`ROW_FIELDS`)."""

    quaternion: np.ndarray  # (n, 4)
    height: np.ndarray  # (n,)
    vertical_velocity: np.ndarray  # (n,)
    pwm: np.ndarray  # (n, 4) int
    armed: np.ndarray  # (n,) bool


def golden_replay(
    rows: np.ndarray, scenario: ScenarioConfig | None = None, vehicle: VehicleConfig | None = None
) -> GoldenRun:
    """:class:`HostController` (float64) on the sensor packets of ``rows``, as the chip gets them.

    Args:
        rows: a flight (columns :data:`ROW_FIELDS`), sample period from its first two times.
        scenario, vehicle: the controller's parameters (default: the default scenario and preset).
    """
    from robosoc.cosim.replay import sensor_packet

    scenario = scenario or ScenarioConfig()
    vehicle = vehicle or vehicle_preset(scenario.vehicle)
    host = HostController.for_scenario(scenario, vehicle)
    host.reset()
    times = rows[:, ROW_FIELDS.index("t")]
    dt_us = round(float(times[1] - times[0]) * 1e6) if len(rows) > 1 else round(host.dt * 1e6)
    n = len(rows)
    q, h, v = np.empty((n, 4)), np.empty(n), np.empty(n)
    pwm, armed = np.empty((n, 4), dtype=np.int64), np.empty(n, dtype=bool)
    for k in range(n):
        p = SENSOR.unpack(sensor_packet(rows[k], k, dt_us))
        sample = SimpleNamespace(
            gyro=np.array(p["gyro"]), accel=np.array(p["accel"]), mag=np.array(p["mag"]),
            baro_altitude=float(scalar(p, "baro_altitude")),
        )  # fmt: skip
        sp, ff = array(p, "setpoint"), array(p, "height_feedforward")
        on = bool(int(scalar(p, "flags")) & FLAG_ARMED)
        setpoint = Setpoint(sp[0], sp[1], sp[2], sp[3], on, ff[0], ff[1])
        pwm[k] = host.step(sample, setpoint)
        q[k], h[k], v[k], armed[k] = host.ekf.quaternion, host.altitude.height, host.altitude.velocity, on
    return GoldenRun(q, h, v, pwm, armed)


@dataclass(frozen=True)
class QuaternionError:
    """How far attitude series ``a`` lies from reference ``b`` (NaN when there are no samples)."""

    samples: int
    mean_component: float  # mean |a_i - b_i| over samples and components (the seed's 0.0019)
    max_component: float
    mean_deg: float  # mean rotation angle between a and b
    max_deg: float

    @property
    def mean_percent(self) -> float:
        """The seed's "0.19 %": the mean component error as a percentage of a unit quaternion."""
        return 100.0 * self.mean_component


def quaternion_error(a: np.ndarray, b: np.ndarray) -> QuaternionError:
    """Errors of the quaternions ``a`` (n, 4) against ``b`` (n, 4), sign-aligned sample by sample.

    Raises:
        ValueError: the shapes differ or are not (n, 4).
    """
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    if a.shape != b.shape or a.ndim != 2 or a.shape[1] != 4:
        raise ValueError(f"two (n, 4) quaternion series expected, got {a.shape} and {b.shape}")
    if len(a) == 0:
        return QuaternionError(0, math.nan, math.nan, math.nan, math.nan)
    sign = np.where(np.einsum("ij,ij->i", a, b) < 0, -1.0, 1.0)
    diff = np.abs(a * sign[:, None] - b)
    dot = np.abs(np.einsum("ij,ij->i", a, b)) / np.sqrt(np.einsum("ij,ij->i", a, a) * np.einsum("ij,ij->i", b, b))
    angles = np.degrees(2.0 * np.arccos(np.clip(dot, 0.0, 1.0)))
    return QuaternionError(len(a), float(diff.mean()), float(diff.max()), float(angles.mean()), float(angles.max()))


@dataclass(frozen=True)
class PwmAgreement:
    """The chip's PWM commands against the golden model's for the same samples."""

    samples: int  # samples with a command from the chip
    within_one: float  # fraction of them whose four counts are all within one of the golden model's
    max_diff: int  # largest count difference
    mean_abs_diff: float  # mean over samples and motors

    @staticmethod
    def of(chip: dict[int, Sequence[int]], golden: np.ndarray, samples: Sequence[int]) -> PwmAgreement:
        """``chip``: seq -> four counts; ``golden``: (n, 4); compared on ``samples`` (indices)."""
        both = [k for k in samples if k in chip]
        if not both:
            return PwmAgreement(0, math.nan, 0, math.nan)
        diff = np.abs(np.array([chip[k] for k in both], dtype=np.int64) - golden[both])
        return PwmAgreement(len(both), float((diff.max(axis=1) <= 1).mean()), int(diff.max()), float(diff.mean()))


__all__ = [
    "TRUTH_QUATERNION",
    "GoldenRun",
    "PwmAgreement",
    "QuaternionError",
    "golden_replay",
    "quaternion_error",
]
