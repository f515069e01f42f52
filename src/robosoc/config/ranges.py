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

import math
import numbers

__all__ = [
    "DEVICE_MAP_BASE",
    "MAX_CYCLES",
    "MAX_SEED",
    "MAX_SRAM_BYTES",
    "MIN_SRAM_BYTES",
    "check_float",
    "check_int",
    "check_seed",
    "check_sram_bytes",
    "describe",
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


def describe(value: float) -> str:
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
        else:
            rule = f"must be <= {describe(hi)}{_unit(unit)}"  # type: ignore[arg-type]
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
