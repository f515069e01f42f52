"""The ranges of the numbers users give robosoc, checked the same way everywhere.

One rule per kind of value (cycle budgets, counts, sizes, durations, seeds), used by the public
library functions that take such values and by the command line (:mod:`robosoc.cli.options`,
which passes the option name, ``--seed``, where the library passes its argument name, ``seed``).
Errors are ``ValueError("<name>: <reason>, got <value>")``, the style of the configuration
validator (:mod:`robosoc.config.validate`)::

    check_int("--seed", -1, 0, MAX_SEED)     # ValueError: --seed: must be between 0 and 2**63-1, got -1
    check_float("seconds", math.nan, 0.0)    # ValueError: seconds: must be a finite number, got nan
"""

from __future__ import annotations

import dataclasses
import math
import numbers
import os
from typing import TYPE_CHECKING, NamedTuple

if TYPE_CHECKING:
    from _typeshed import DataclassInstance

__all__ = [
    "CLOCK_PERIOD_NS",
    "DEVICE_MAP_BASE",
    "FLOAT_FIELDS",
    "MAX_CHIP_SRAM_BYTES",
    "MAX_CYCLES",
    "MAX_SEED",
    "MAX_SRAM_BYTES",
    "MIN_SRAM_BYTES",
    "FloatRange",
    "check_fields",
    "check_float",
    "check_int",
    "check_memory",
    "check_seed",
    "check_sram_bytes",
    "describe",
    "format_bytes",
    "host_memory_bytes",
]

#: Largest cycle budget or cycle count: counters are 64-bit and the simulator adds slices to them.
MAX_CYCLES = 2**62
#: Seeds feed ``numpy.random.SeedSequence``; kept to what a signed 64-bit integer holds.
MAX_SEED = 2**63 - 1
#: SRAM of a tile (and of the single-core SoC on the command line): 4 KiB .. 1 GiB, whole words.
MIN_SRAM_BYTES = 4096
MAX_SRAM_BYTES = 2**30
#: Lowest device address (the exit trap, platform.md §2): SRAM at 0x40000000 must end below it.
DEVICE_MAP_BASE = 0xE000_0000
#: Most SRAM a chip may simulate in all (the simulator gives every tile the largest tile's SRAM):
#: 16 GiB, e.g. 256 tiles of 64 MiB or 16 tiles of 1 GiB.
MAX_CHIP_SRAM_BYTES = 2**34


def format_bytes(n: int) -> str:
    """``256 GiB``, ``1.5 MiB``, ``4096 bytes``: a size as people read it."""
    for unit, size in (("TiB", 2**40), ("GiB", 2**30), ("MiB", 2**20), ("KiB", 2**10)):
        if n >= size:
            return f"{n / size:.4g} {unit}"
    return f"{n} bytes"


def host_memory_bytes() -> int | None:
    """This machine's physical memory in bytes (``None`` if the system does not say)."""
    try:
        return os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (AttributeError, ValueError, OSError):
        return None


def check_memory(name: str, needed: int, what: str) -> None:
    """Refuse to allocate ``needed`` bytes (for ``what``) that this machine does not have.

    Raises:
        ValueError: ``"<name>: <what> needs 256 GiB of memory, more than this machine's 23.4 GiB"``.
    """
    total = host_memory_bytes()
    if total is not None and needed > total:
        raise ValueError(
            f"{name}: {what} needs {format_bytes(needed)} of memory, more than this machine's {format_bytes(total)}"
        )


def describe(value: int | float) -> str:
    """A bound as people read it: ``2**62``, ``2**63-1``, ``10**10``, ``4096``, ``0.001``."""
    if isinstance(value, int) and value >= 10**7 and str(value).rstrip("0") == "1":
        return f"10**{len(str(value)) - 1}"
    if isinstance(value, int) and value >= 1 << 20:
        if value & (value - 1) == 0:
            return f"2**{value.bit_length() - 1}"
        if (value + 1) & value == 0:
            return f"2**{value.bit_length()}-1"
    if isinstance(value, float):
        return f"{value:g}"
    return str(value)


def _unit(unit: str) -> str:
    return f" {unit}" if unit else ""


def check_int(name: str, value: object, lo: int | None = None, hi: int | None = None, unit: str = "") -> int:
    """``value`` as an int if it is an integer (not a bool) in ``[lo, hi]`` (``None``: unbounded).

    Raises:
        ValueError: ``"<name>: must be between <lo> and <hi> <unit>, got <value>"`` (or ``>=``/``<=``).
    """
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise ValueError(f"{name}: expected an integer, got {value!r}")
    v = int(value)
    if (lo is not None and v < lo) or (hi is not None and v > hi):
        if lo is not None and hi is not None:
            rule = f"must be between {describe(lo)} and {describe(hi)}{_unit(unit)}"
        elif lo is not None:
            rule = f"must be >= {describe(lo)}{_unit(unit)}"
        elif hi is not None:
            rule = f"must be <= {describe(hi)}{_unit(unit)}"
        raise ValueError(f"{name}: {rule}, got {v}")
    return v


def check_float(
    name: str,
    value: object,
    lo: float | None = None,
    hi: float | None = None,
    *,
    lo_open: bool = False,
    unit: str = "",
) -> float:
    """``value`` as a float if it is a finite number in ``[lo, hi]`` (``(lo, hi]`` with ``lo_open``).

    Raises:
        ValueError: NaN, an infinity, a bool or a non-number, or out of range; the message names
            ``name`` and the allowed range.
    """
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise ValueError(f"{name}: expected a number, got {value!r}")
    v = float(value)
    if not math.isfinite(v):
        raise ValueError(f"{name}: must be a finite number, got {v}")
    low_bad = lo is not None and (v <= lo if lo_open else v < lo)
    if low_bad or (hi is not None and v > hi):
        if lo is not None and hi is not None:
            rule = f"must be in {'(' if lo_open else '['}{lo:g}, {hi:g}]{_unit(unit)}"
        elif lo is not None:
            rule = f"must be {'>' if lo_open else '>='} {lo:g}{_unit(unit)}"
        else:
            rule = f"must be <= {hi:g}{_unit(unit)}"
        raise ValueError(f"{name}: {rule}, got {v:g}")
    return v


def check_seed(name: str, value: object) -> int:
    """A random seed: an integer in ``[0, 2**63-1]``."""
    return check_int(name, value, 0, MAX_SEED)


def check_sram_bytes(name: str, value: object) -> int:
    """An SRAM size for the command line and the chip configuration: a multiple of 4 in 4 KiB .. 1 GiB."""
    v = check_int(name, value, MIN_SRAM_BYTES, MAX_SRAM_BYTES, "bytes")
    if v % 4:
        raise ValueError(f"{name}: must be a multiple of 4 bytes, got {v}")
    return v


# --- the float fields of the configuration files ------------------------------------------------------


class FloatRange(NamedTuple):
    """The finite range of a float field, with its unit: ``[lo, hi]`` (``(lo, hi]`` with ``lo_open``)."""

    lo: float
    hi: float
    unit: str = ""
    lo_open: bool = False

    def check(self, name: str, value: object) -> float:
        """``value`` if it is a finite number in the range (:func:`check_float`)."""
        return check_float(name, value, self.lo, self.hi, lo_open=self.lo_open, unit=self.unit)


#: A core's clock period: 0.5 ns (2 GHz) .. 1000 ns (1 MHz).  Shorter would simulate millions of cycles
#: per physics step (1e-9 ns never finishes a step), longer leaves no cycle for a job.
CLOCK_PERIOD_NS = FloatRange(0.5, 1000.0, "ns")
_RATE = FloatRange(0.0, 1.0, "(a rate)")
_SECONDS = FloatRange(0.0, 3600.0, "s")
_WIND = FloatRange(-30.0, 30.0, "m/s")

FLOAT_FIELDS: dict[str, FloatRange] = {
    # chip files ([tile], [[tiles]]) and the energy coefficients
    "TileConfig.clock_period_ns": CLOCK_PERIOD_NS,
    "TileOverride.clock_period_ns": CLOCK_PERIOD_NS,
    "EnergyModel.clock_ns": CLOCK_PERIOD_NS,
    "Coefficient.pj": FloatRange(0.0, 1e6, "pJ"),
    "DvfsConfig.reference_v": FloatRange(0.1, 5.0, "V"),
    # link files
    "LinkFaults.loss": _RATE,
    "LinkFaults.duplicate": _RATE,
    "LinkFaults.reorder": _RATE,
    "LinkFaults.truncate": _RATE,
    "LinkFaults.garbage": _RATE,
    "LinkConfig.peer_timeout_s": FloatRange(0.05, 3600.0, "s"),
    "LinkConfig.connect_timeout_s": FloatRange(0.05, 3600.0, "s"),
    "LinkConfig.heartbeat_s": FloatRange(0.001, 1.0, "s"),
    # scenario files
    "ScenarioConfig.duration_s": FloatRange(0.0, 3600.0, "s", lo_open=True),
    "SensorConfig.rate_hz": FloatRange(0.1, 1000.0, "Hz"),
    "SensorConfig.accel_sigma": FloatRange(0.0, 20.0, "m/s²"),
    "SensorConfig.accel_bias": FloatRange(0.0, 20.0, "m/s²"),
    "SensorConfig.gyro_sigma": FloatRange(0.0, 10.0, "rad/s"),
    "SensorConfig.gyro_bias": FloatRange(0.0, 10.0, "rad/s"),
    "SensorConfig.mag_sigma": FloatRange(0.0, 2.0, "(of the unit field)"),
    "SensorConfig.mag_bias": FloatRange(0.0, 2.0, "(of the unit field)"),
    "SensorConfig.baro_sigma": FloatRange(0.0, 100.0, "m"),
    "SensorConfig.baro_bias": FloatRange(0.0, 1000.0, "m"),
    "SensorConfig.bias_tau_s": FloatRange(0.001, 1e6, "s"),
    "PositionSensorConfig.rate_hz": FloatRange(0.1, 1000.0, "Hz"),
    "PositionSensorConfig.position_sigma": FloatRange(0.0, 100.0, "m"),
    "PositionSensorConfig.velocity_sigma": FloatRange(0.0, 100.0, "m/s"),
    "GustConfig.start_s": _SECONDS,
    "GustConfig.duration_s": FloatRange(0.0, 3600.0, "s", lo_open=True),
    "GustConfig.rise_s": FloatRange(0.0, 1800.0, "s"),
    "GustConfig.velocity": _WIND,
    "WindConfig.constant": _WIND,
    "WindConfig.gust_sigma": FloatRange(0.0, 10.0, "m/s"),
    "WindConfig.gust_tau_s": FloatRange(0.001, 3600.0, "s"),
    "WindConfig.update_s": FloatRange(0.001, 3600.0, "s"),
    "SetpointStep.time_s": _SECONDS,
    "SetpointStep.value": FloatRange(-45.0, 45.0, "degrees (m for height)"),
    "FlightPlan.takeoff_s": FloatRange(0.1, 3600.0, "s"),
    "FlightPlan.height_m": FloatRange(0.3, 5.0, "m"),
    "FlightPlan.climb_s": _SECONDS,
    "FlightPlan.climb_rate_mps": FloatRange(0.1, 10.0, "m/s"),
    "FlightPlan.descent_rate_mps": FloatRange(0.1, 10.0, "m/s"),
    "MissionPlan.hold_s": FloatRange(0.0, 600.0, "s"),
    "MissionPlan.acceptance_m": FloatRange(0.0, 10.0, "m", lo_open=True),
    "MissionPlan.speed_mps": FloatRange(0.1, 10.0, "m/s"),
    "MissionPlan.land_settle_s": FloatRange(0.0, 60.0, "s"),
    # vehicle files
    "VehicleConfig.mass": FloatRange(0.05, 100.0, "kg"),
    "VehicleConfig.inertia": FloatRange(1e-5, 10.0, "kg·m²"),
    "VehicleConfig.com": FloatRange(-0.2, 0.2, "m"),
    "VehicleConfig.arm_length": FloatRange(0.05, 2.0, "m"),
    "VehicleConfig.skid_half_length": FloatRange(0.001, 2.0, "m"),
    "VehicleConfig.skid_offset_y": FloatRange(0.001, 2.0, "m"),
    "VehicleConfig.skid_bottom_z": FloatRange(-2.0, -0.001, "m"),
    "VehicleConfig.skid_radius": FloatRange(0.0001, 0.5, "m"),
    "VehicleConfig.body_half_extents": FloatRange(0.001, 2.0, "m"),
    "VehicleConfig.spawn_position": FloatRange(-1000.0, 1000.0, "m"),
    "VehicleConfig.spawn_yaw_deg": FloatRange(-360.0, 360.0, "degrees"),
    "MotorConfig.psi": FloatRange(1e-4, 1.0, "V·s/rad"),
    "MotorConfig.j_m": FloatRange(1e-7, 0.01, "kg·m²"),
    "MotorConfig.r_a": FloatRange(0.001, 10.0, "Ω"),
    "MotorConfig.k_t": FloatRange(0.0, 1.0, "N·m/N"),
    "MotorConfig.k_m": FloatRange(-10.0, 10.0, "N·m·s/rad"),
    "MotorConfig.alpha_m": FloatRange(0.001, 10.0),
    "MotorConfig.beta_m": FloatRange(0.001, 10.0),
    "MotorConfig.ct0s": FloatRange(1e-7, 1e-3),
    "MotorConfig.ct1s": FloatRange(-10.0, 10.0),
    "MotorConfig.ct2s": FloatRange(-10.0, 10.0),
    "MotorConfig.supply_voltage": FloatRange(1.0, 100.0, "V"),
    "DragConfig.c_wxy": FloatRange(0.0, 10.0),
    "DragConfig.c_wz": FloatRange(0.0, 10.0),
    "DragConfig.c_mxy": FloatRange(0.0, 10.0),
    "DragConfig.c_mz": FloatRange(0.0, 10.0),
    # firmware project files: published reference figures (config/project.py)
    "ReferenceFigure.response_ms": FloatRange(0.0, 1e9, "ms", lo_open=True),
    "ReferenceFigure.energy_nj": FloatRange(0.0, 1e12, "nJ", lo_open=True),
    # the power system (config/power.py)
    "BatteryConfig.capacity_ah": FloatRange(0.001, 1000.0, "Ah"),
    "BatteryConfig.full_v": FloatRange(0.5, 10.0, "V"),
    "BatteryConfig.exp_v": FloatRange(0.5, 10.0, "V"),
    "BatteryConfig.exp_fraction": FloatRange(0.0, 1.0, "(a fraction of the capacity)", lo_open=True),
    "BatteryConfig.nominal_v": FloatRange(0.5, 10.0, "V"),
    "BatteryConfig.nominal_fraction": FloatRange(0.0, 1.0, "(a fraction of the capacity)", lo_open=True),
    "BatteryConfig.curve_c": FloatRange(0.0, 100.0, "C", lo_open=True),
    "BatteryConfig.resistance_ohm": FloatRange(0.0, 10.0, "Ω"),
    "BatteryConfig.cutoff_v": FloatRange(0.5, 10.0, "V"),
    "BatteryConfig.initial_soc": FloatRange(0.0, 1.0, "(state of charge)"),
    "PowerConfig.avionics_w": FloatRange(0.0, 1000.0, "W"),
    "PowerConfig.reserve_soc": FloatRange(0.0, 1.0, "(state of charge)"),
    "PowerConfig.failsafe_height_m": FloatRange(0.0, 100.0, "m (the body's height above the ground)", lo_open=True),
    "PowerConfig.failsafe_hold_s": FloatRange(0.0, 60.0, "s"),
}
"""Every float field of every configuration file, ``"<dataclass>.<field>"``, and its range (a tuple of
floats, a vector, has the range for each element).  Checked in each dataclass's ``__post_init__``
(:func:`check_fields`), so a file, a sweep value and the library meet the same rule; a test checks
that every float field of every configuration dataclass is listed."""


def check_fields(obj: DataclassInstance) -> None:
    """Check every field of the dataclass ``obj`` listed in :data:`FLOAT_FIELDS` (``None`` passes:
    an optional field left out).

    Raises:
        ValueError: ``"<field>: must be in [lo, hi] unit, got v"`` (``"<field>[i]: ..."`` in a vector).
    """
    owner = type(obj).__name__
    for f in dataclasses.fields(obj):
        rule = FLOAT_FIELDS.get(f"{owner}.{f.name}")
        if rule is None:
            continue
        value = getattr(obj, f.name)
        if value is None:
            continue
        if isinstance(value, tuple | list):
            for i, item in enumerate(value):
                rule.check(f"{f.name}[{i}]", item)
        else:
            rule.check(f.name, value)
