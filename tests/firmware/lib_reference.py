"""float64 references and error bounds for lib_check.c's lines (fix16_ and flt_ functions).

Each checker takes the operands and the result as printed (32-bit words) and returns the error in
the function's unit: LSB of Q16.16 for fix16_, radians (or an exact-match 0/1) for flt_.  The
bounds are the ones docs/firmware-libraries.md states.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from robosoc.firmware import math_sources

LIB_CHECK = Path(__file__).resolve().parent / "lib_check.c"
Q = 65536.0
FIX_MAX = 2**31 - 1
FIX_MIN = -(2**31)


def s32(word: int) -> int:
    """A 32-bit word as a signed integer."""
    return word - (1 << 32) if word & 0x80000000 else word


def f32(word: int) -> float:
    """A 32-bit word as the float32 it encodes, widened to float64."""
    return float(np.array([word], dtype=np.uint32).view(np.float32)[0])


def saturate(v: float) -> int:
    """The Q16.16 integer a saturating operation must give when the exact value is out of range."""
    return FIX_MAX if v > FIX_MAX else FIX_MIN


def _in_range(exact_lsb: float) -> bool:
    return FIX_MIN - 0.5 <= exact_lsb <= FIX_MAX + 0.5


def _fixed_error(exact_lsb: float, result: int) -> float:
    """|result - exact| in LSB, or 0 / inf for an out-of-range exact value (saturated or not)."""
    if not _in_range(exact_lsb):
        return 0.0 if result == saturate(exact_lsb) else math.inf
    # a rounded value just past the ends saturates too
    return abs(min(max(exact_lsb, FIX_MIN), FIX_MAX) - result)


def err_add(a: int, b: int, r: int) -> float:
    return _fixed_error(float(s32(a) + s32(b)), s32(r))


def err_sub(a: int, b: int, r: int) -> float:
    return _fixed_error(float(s32(a) - s32(b)), s32(r))


def err_mul(a: int, b: int, r: int) -> float:
    return _fixed_error(s32(a) * s32(b) / Q, s32(r))


def err_div(a: int, b: int, r: int) -> float:
    if s32(b) == 0:
        return 0.0 if s32(r) == (FIX_MAX if s32(a) >= 0 else FIX_MIN) else math.inf
    return _fixed_error(s32(a) * Q / s32(b), s32(r))


def err_divdi3(a: int, b: int, r: int) -> float:
    """compiler-rt's truncating 64-bit division: error < 1 LSB (b == 0 is skipped, result 0)."""
    if s32(b) == 0:
        return 0.0 if r == 0 else math.inf
    return _fixed_error(s32(a) * Q / s32(b), s32(r))


def err_sqrt(a: int, _b: int, r: int) -> float:
    if s32(a) <= 0:
        return 0.0 if r == 0 else math.inf
    return abs(math.sqrt(s32(a) * Q) - s32(r))


def err_sin(a: int, _b: int, r: int) -> float:
    return abs(math.sin(s32(a) / Q) * Q - s32(r))


def err_cos(a: int, _b: int, r: int) -> float:
    return abs(math.cos(s32(a) / Q) * Q - s32(r))


def err_atan2(a: int, b: int, r: int) -> float:
    if s32(a) == 0 and s32(b) == 0:
        return 0.0 if r == 0 else math.inf
    exact = math.atan2(s32(a), s32(b)) * Q
    # at y = 0, x < 0 both +pi and -pi are right
    return min(abs(exact - s32(r)), abs(-exact - s32(r))) if s32(a) == 0 else abs(exact - s32(r))


def err_asin(a: int, _b: int, r: int) -> float:
    x = max(-1.0, min(1.0, s32(a) / Q))
    return abs(math.asin(x) * Q - s32(r))


def err_from_int(a: int, _b: int, r: int) -> float:
    return _fixed_error(float(s32(a)) * Q, s32(r))


def err_to_int(a: int, _b: int, r: int) -> float:
    return abs(s32(a) / Q - s32(r)) if s32(r) == math.floor(s32(a) / Q + 0.5) else math.inf


def err_from_float(a: int, _b: int, r: int) -> float:
    f = f32(a)
    if math.isnan(f):
        return 0.0 if r == 0 else math.inf
    if math.isinf(f):
        return 0.0 if s32(r) == (FIX_MAX if f > 0 else FIX_MIN) else math.inf
    return _fixed_error(f * Q, s32(r))


def err_to_float(a: int, _b: int, r: int) -> float:
    """0 when the result is the correctly rounded float32 of the value, else inf."""
    return 0.0 if f32(r) == float(np.float32(s32(a) / Q)) else math.inf


def err_fsqrt(a: int, _b: int, r: int) -> float:
    """0 for the bits of IEEE sqrtf (correct rounding), else inf."""
    expected = np.sqrt(np.array([a], dtype=np.uint32).view(np.float32)).view(np.uint32)[0]
    return 0.0 if int(expected) == r else math.inf


def err_fsin(a: int, _b: int, r: int) -> float:
    return abs(math.sin(f32(a)) - f32(r))


def err_fcos(a: int, _b: int, r: int) -> float:
    return abs(math.cos(f32(a)) - f32(r))


def err_fatan2(a: int, b: int, r: int) -> float:
    return abs(math.atan2(f32(a), f32(b)) - f32(r))


def err_fasin(a: int, _b: int, r: int) -> float:
    return abs(math.asin(max(-1.0, min(1.0, f32(a)))) - f32(r))


def _soft_float(op: Callable[[np.ndarray, np.ndarray], np.ndarray]) -> Callable[[int, int, int], float]:
    def check(a: int, b: int, r: int) -> float:
        x = np.array([a], dtype=np.uint32).view(np.float32)
        y = np.array([b], dtype=np.uint32).view(np.float32)
        with np.errstate(all="ignore"):
            expected = int(op(x, y).view(np.uint32)[0])
        return 0.0 if expected == r else math.inf

    return check


@dataclass(frozen=True)
class Bound:
    check: Callable[[int, int, int], float]
    bound: float
    unit: str


#: op -> (checker, bound, unit of the bound)
BOUNDS: dict[str, Bound] = {
    "add": Bound(err_add, 0.0, "LSB"),
    "sub": Bound(err_sub, 0.0, "LSB"),
    "mul": Bound(err_mul, 0.5, "LSB"),
    "div": Bound(err_div, 0.5, "LSB"),
    "divdi3": Bound(err_divdi3, 1.0, "LSB"),
    "sqrt": Bound(err_sqrt, 0.5, "LSB"),
    "sin": Bound(err_sin, 0.65, "LSB"),
    "cos": Bound(err_cos, 0.65, "LSB"),
    "atan2": Bound(err_atan2, 0.55, "LSB"),
    "asin": Bound(err_asin, 1.1, "LSB"),
    "from_int": Bound(err_from_int, 0.0, "LSB"),
    "to_int": Bound(err_to_int, 0.5, "units"),
    "from_float": Bound(err_from_float, 0.5, "LSB"),
    "to_float": Bound(err_to_float, 0.0, "exact"),
    "fsqrt": Bound(err_fsqrt, 0.0, "exact"),
    "fsin": Bound(err_fsin, 1.2e-7, "abs"),
    "fcos": Bound(err_fcos, 1.2e-7, "abs"),
    "fatan2": Bound(err_fatan2, 3.6e-7, "rad"),
    "fasin": Bound(err_fasin, 3.6e-7, "rad"),
    "fadd": Bound(_soft_float(np.add), 0.0, "exact"),
    "fmul": Bound(_soft_float(np.multiply), 0.0, "exact"),
    "fdiv": Bound(_soft_float(np.divide), 0.0, "exact"),
}


@dataclass(frozen=True)
class CheckLine:
    op: str
    a: int
    b: int
    result: int
    cycles: int


def parse_lines(text: str) -> list[CheckLine]:
    out = []
    for line in text.splitlines():
        op, a, b, r, c = line.split()
        out.append(CheckLine(op, int(a, 16), int(b, 16), int(r, 16), int(c)))
    return out


def max_errors(lines: list[CheckLine]) -> dict[str, tuple[float, int]]:
    """op -> (largest error, number of calls) over the checked ops (mul64 must be exact)."""
    worst: dict[str, tuple[float, int]] = {}
    for line in lines:
        if line.op == "base":
            continue
        if line.op == "mul64":
            exact = (s32(line.a) * s32(line.b)) & 0xFFFFFFFFFFFFFFFF
            err = 0.0 if exact == line.result else math.inf
        else:
            err = BOUNDS[line.op].check(line.a, line.b, line.result)
        prev, n = worst.get(line.op, (0.0, 0))
        worst[line.op] = (max(prev, err), n + 1)
    return worst


def mean_cycles(lines: list[CheckLine]) -> dict[str, float]:
    """op -> mean cycles per call, the call overhead (the "base" line) subtracted."""
    sums: dict[str, list[int]] = {}
    for line in lines:
        sums.setdefault(line.op, []).append(line.cycles)
    base = float(np.mean(sums.pop("base")))
    return {op: float(np.mean(v)) - base for op, v in sums.items()}


def lib_check_sources() -> list[Path]:
    return [LIB_CHECK, *math_sources()]
