"""Replaying a recorded sensor stream into the control firmware on the chip.

The harness behind ``robosoc firmware replay``: every sensor sample of a flight log becomes a
message from the I/O tile, injected at the cycle of its timestamp, and the firmware runs on the
chip (:class:`robosoc.cosim.firmware_run.FirmwareRun`, whose docstring says how time and energy
are accounted); what comes back is the PWM command of each sample with the cycle it reached the
I/O tile, and one record per job of each task.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from robosoc.chip.energy import EnergyModel
from robosoc.config.chip import ChipConfig
from robosoc.config.firmware import FirmwareConfig
from robosoc.config.scenario import ScenarioConfig
from robosoc.config.vehicle import VehicleConfig, vehicle_preset
from robosoc.control.flight import ROW_FIELDS, fly
from robosoc.control.host import HostController
from robosoc.cosim.firmware_run import DEFAULT_FIRST_CYCLE, FirmwareRun, ReplayResult
from robosoc.host import packets
from robosoc.host.scenario_image import firmware_image
from robosoc.physics import PositionFix
from robosoc.records import SampleInput

Vector3 = tuple[float, float, float]

# --- the sensor stream --------------------------------------------------------------------------


#: the sensor packet's array fields and their flight-row columns
_SENSOR_COLUMNS = {
    "gyro": [ROW_FIELDS.index(f"gyro_{a}") for a in "xyz"],
    "accel": [ROW_FIELDS.index(f"accel_{a}") for a in "xyz"],
    "mag": [ROW_FIELDS.index(f"mag_{a}") for a in "xyz"],
    "setpoint": [ROW_FIELDS.index(f"sp_{n}") for n in ("roll", "pitch", "yaw", "height")],
    "height_feedforward": [ROW_FIELDS.index("sp_height_rate"), ROW_FIELDS.index("sp_height_accel")],
}
_ARMED, _T, _BARO = (ROW_FIELDS.index(name) for name in ("armed", "t", "baro_altitude"))


#: the q16 fields' flight-row columns in the packet's field order (they follow its five header fields)
_Q16_OF_FIELD = {**_SENSOR_COLUMNS, "baro_altitude": [_BARO]}
_Q16_COLUMNS = [c for f in packets.SENSOR.fields if f.type == "q16" for c in _Q16_OF_FIELD[f.name]]
_U32 = 0xFFFFFFFF


def sensor_packet(row: np.ndarray, seq: int, dt_us: int, low_battery: bool = False) -> bytes:
    """The sensor packet of one flight row (columns :data:`ROW_FIELDS`): its sample and setpoint
    (``low_battery``: the pack is below its reserve, :data:`packets.FLAG_LOW_BATTERY`).

    The bytes of :meth:`packets.PacketFormat.pack` (:func:`packed_sensor_packet`), made from the
    row's Python floats in one pass (a flight packs one per sample, and small numpy steps cost it
    more): a value times 2**16 is exact in float64 and ``round`` rounds half to even.  A value the
    packet cannot hold goes the long way, which names it."""
    col = row.tolist()
    t = col[_T]
    time_us = round(t * 1e6) if math.isfinite(t) else -1
    try:
        scaled = [round(col[c] * packets.Q16_ONE) for c in _Q16_COLUMNS]
    except (ValueError, OverflowError):  # NaN, infinite
        return packed_sensor_packet(row, seq, dt_us, low_battery)
    if (
        0 <= seq <= _U32
        and 0 <= time_us <= _U32
        and 0 <= dt_us <= _U32
        and min(scaled) >= packets.Q16_MIN
        and max(scaled) <= packets.Q16_MAX
    ):
        flags = (packets.FLAG_ARMED if col[_ARMED] > 0.5 else 0) | (packets.FLAG_LOW_BATTERY if low_battery else 0)
        return packets.SENSOR.pack_words((packets.SENSOR.kind, flags, seq, time_us, dt_us, *scaled))
    return packed_sensor_packet(row, seq, dt_us, low_battery)


def packed_sensor_packet(row: np.ndarray, seq: int, dt_us: int, low_battery: bool = False) -> bytes:
    """:func:`sensor_packet` made field by field with :meth:`packets.PacketFormat.pack` (its errors
    name the field that does not fit)."""
    col = row.tolist()  # Python floats
    values: dict[str, packets.Value] = {
        "kind": packets.SENSOR.kind,
        "flags": (packets.FLAG_ARMED if col[_ARMED] > 0.5 else 0) | (packets.FLAG_LOW_BATTERY if low_battery else 0),
        "seq": seq,
        "time_us": round(col[_T] * 1e6),
        "dt_us": dt_us,
        **{name: tuple(col[c] for c in columns) for name, columns in _SENSOR_COLUMNS.items()},
        "baro_altitude": col[_BARO],
    }
    return packets.SENSOR.pack(values)


def position_packet(
    fix: PositionFix,
    setpoint: tuple[Vector3, Vector3, Vector3],
    seq: int,
    time_s: float,
    armed: bool,
) -> bytes:
    """The position packet sent with sensor sample ``seq`` (taken at ``time_s``): the newest ``fix``
    and the position setpoint (world-frame position, velocity and acceleration)."""
    position, velocity, accel = setpoint
    values: dict[str, packets.Value] = {
        "flags": packets.FLAG_ARMED if armed else 0,
        "seq": seq,
        "time_us": round(time_s * 1e6),
        "fix_time_us": round(fix.time * 1e6),
        "fix_number": fix.number,
        "position": fix.position,
        "velocity": fix.velocity,
        "setpoint": position,
        "setpoint_velocity": velocity,
        "setpoint_accel": accel,
    }
    return packets.POSITION.pack(values)


def samples_from_rows(rows: np.ndarray, clock_ns: float, first_cycle: int = DEFAULT_FIRST_CYCLE) -> list[SampleInput]:
    """Sensor messages of a flight (rows with the columns of :data:`ROW_FIELDS`, e.g. a flight log).

    Raises:
        ValueError: a column is missing (an old log without the sensor columns), a value is not
            finite, or a time is out of range or goes back (:func:`robosoc.control.flight_log.check_flight_rows`).
    """
    from robosoc.control.flight_log import check_flight_rows

    rows = check_flight_rows(rows, "rows")  # finite, times in 0..3600 s and increasing
    times = rows[:, ROW_FIELDS.index("t")]
    out = []
    for k in range(len(rows)):
        t = float(times[k])
        dt = float(times[k] - times[k - 1]) if k else float(times[1] - times[0]) if len(times) > 1 else 0.01
        cycle = first_cycle + round(t * 1e9 / clock_ns)
        out.append(SampleInput(k, t, cycle, sensor_packet(rows[k], k, round(dt * 1e6))))
    return out


def built_in_rows(seconds: float = 10.0, seed: int = 1) -> np.ndarray:
    """The built-in sensor stream: the default scenario flown by the host controller."""
    return scenario_rows(ScenarioConfig(duration_s=seconds, seed=seed))


def scenario_rows(scenario: ScenarioConfig) -> np.ndarray:
    """The sensor stream of ``scenario`` (its sensors, noise or none, wind, plan and seed) flown by the
    host controller."""
    vehicle = vehicle_preset(scenario.vehicle)
    return fly(scenario, vehicle, HostController.for_scenario(scenario, vehicle))


def replay(
    rows: np.ndarray,
    fw: FirmwareConfig | None = None,
    *,
    vehicle: VehicleConfig | None = None,
    scenario: ScenarioConfig | None = None,
    chip: ChipConfig | None = None,
    energy: EnergyModel | None = None,
    first_cycle: int = DEFAULT_FIRST_CYCLE,
    on_sample: Callable[[int, int], None] | None = None,
    profile: bool = False,
) -> ReplayResult:
    """Run the firmware on the chip against the sensor samples of ``rows`` (a flight's rows).

    Args:
        rows: a flight (:func:`robosoc.control.flight.fly` or a flight log read back).
        fw: the firmware build and task mapping (default: fixed point with the multiplier).
        vehicle, scenario: the configuration the firmware's control parameters come from.
        chip: the chip (default: the seed's 2×2 for the mapping, :meth:`FirmwareConfig.seed_chip`).
        energy: the energy model (default: the packaged coefficients).
        first_cycle: cycle of the first sample's injection.
        on_sample: called with (samples done, samples in all) as the replay goes (progress bars).
        profile: count every instruction per function, tile and task (:attr:`ReplayResult.profile`).

    Raises:
        ValueError: the mapping does not fit the chip, or the rows are not a flight.
        robosoc.chip.mpsoc.ChipError / CoreError: the firmware faulted (names tile, pc, symbol).
    """
    fw = fw or FirmwareConfig()
    image = firmware_image(fw, vehicle, scenario, chip or fw.default_chip())
    run = FirmwareRun(fw, image, chip=chip, energy=energy, first_cycle=first_cycle, profile=profile)
    samples = samples_from_rows(rows, run.clock_ns, first_cycle)
    period = samples[1].cycle - samples[0].cycle if len(samples) > 1 else round(10e6 / run.clock_ns)
    for k, sample in enumerate(samples):
        run.inject(sample)
        run.run_to(samples[k + 1].cycle if k + 1 < len(samples) else sample.cycle + period)
        run.close_period()
        if on_sample is not None:
            on_sample(k + 1, len(samples))
    return run.result()
