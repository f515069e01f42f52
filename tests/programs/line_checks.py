"""Independent recomputation of the test programs' report lines (``op a b result`` in hex).

Every operation is recomputed here from its operands with Python integers, ``struct`` and numpy
float32 (IEEE single with correct rounding), never with the C compiler, so a line that matches
shows the compiled code computed the right thing.
"""

import math
import struct
from collections.abc import Callable

import numpy as np

M32 = (1 << 32) - 1
M64 = (1 << 64) - 1


def s32(x: int) -> int:
    """Unsigned 32-bit pattern → signed value."""
    x &= M32
    return x - (1 << 32) if x >> 31 else x


def s64(x: int) -> int:
    """Unsigned 64-bit pattern → signed value."""
    x &= M64
    return x - (1 << 64) if x >> 63 else x


def cdiv(a: int, b: int) -> int:
    """C division: truncates toward zero."""
    q = abs(a) // abs(b)
    return q if (a < 0) == (b < 0) else -q


def crem(a: int, b: int) -> int:
    """C remainder: the sign of the dividend."""
    return a - cdiv(a, b) * b


def f32(bits: int) -> np.float32:
    """float32 from its bit pattern."""
    return np.frombuffer(struct.pack("<I", bits), dtype=np.float32)[0]


def bits32(x: np.float32 | float) -> int:
    """Bit pattern of a float32 (every NaN as the canonical quiet NaN, as the programs print it)."""
    if np.isnan(x):
        return 0x7FC00000
    return struct.unpack("<I", np.float32(x).tobytes())[0]


def f64(bits: int) -> float:
    """float64 from its bit pattern."""
    return struct.unpack("<d", struct.pack("<Q", bits))[0]


def bits64(x: float) -> int:
    """Bit pattern of a float64 (every NaN as the canonical quiet NaN)."""
    if math.isnan(x):
        return 0x7FF8000000000000
    return struct.unpack("<Q", struct.pack("<d", x))[0]


def newton_sqrtf(a: np.float32) -> np.float32:
    """The program's float Newton loop, step for step in float32."""
    half = np.float32(0.5)
    x = a * half if a > np.float32(1.0) else np.float32(1.0)
    for _ in range(20):
        x = half * (x + a / x)
    return x


def newton_sqrt(a: float) -> float:
    """The program's double Newton loop."""
    x = a * 0.5 if a > 1.0 else 1.0
    for _ in range(40):
        x = 0.5 * (x + a / x)
    return x


def qmul(a: int, b: int) -> int:
    """Q16.16 product through 64 bits, as the program computes it."""
    return s32((s32(a) * s32(b)) >> 16)


def qdiv(a: int, b: int) -> int:
    """Q16.16 division through the reciprocal 2^32 / b."""
    return qmul(a, s32(cdiv(1 << 32, s32(b))))


def _with_errstate(fn: Callable[[int, int], int]) -> Callable[[int, int], int]:
    def wrapped(a: int, b: int) -> int:
        with np.errstate(all="ignore"):
            return fn(a, b)

    return wrapped


#: op -> exact expected result from (a, b) bit patterns.
EXACT: dict[str, Callable[[int, int], int]] = {
    "add": lambda a, b: (a + b) & M32,
    "sub": lambda a, b: (a - b) & M32,
    "mul": lambda a, b: (a * b) & M32,
    "mulh": lambda a, b: ((s32(a) * s32(b)) >> 32) & M32,
    "mulhu": lambda a, b: (a * b) >> 32,
    "divu": lambda a, b: a // b,
    "remu": lambda a, b: a % b,
    "div": lambda a, b: cdiv(s32(a), s32(b)) & M32,
    "rem": lambda a, b: crem(s32(a), s32(b)) & M32,
    "slt": lambda a, b: int(s32(a) < s32(b)),
    "sltu": lambda a, b: int(a < b),
    "sll": lambda a, b: (a << b) & M32,
    "srl": lambda a, b: a >> b,
    "sra": lambda a, b: (s32(a) >> b) & M32,
    "add64": lambda a, b: (a + b) & M64,
    "sub64": lambda a, b: (a - b) & M64,
    "mul64": lambda a, b: (a * b) & M64,
    "divu64": lambda a, b: a // b,
    "remu64": lambda a, b: a % b,
    "div64": lambda a, b: cdiv(s64(a), s64(b)) & M64,
    "rem64": lambda a, b: crem(s64(a), s64(b)) & M64,
    "slt64": lambda a, b: int(s64(a) < s64(b)),
    "sll64": lambda a, b: (a << b) & M64,
    "srl64": lambda a, b: a >> b,
    "sra64": lambda a, b: (s64(a) >> b) & M64,
    "wmulu": lambda a, b: a * b,
    "wmul": lambda a, b: (s64(a) * s64(b)) & M64,
    "fadd": _with_errstate(lambda a, b: bits32(f32(a) + f32(b))),
    "fsub": _with_errstate(lambda a, b: bits32(f32(a) - f32(b))),
    "fmul": _with_errstate(lambda a, b: bits32(f32(a) * f32(b))),
    "fdiv": _with_errstate(lambda a, b: bits32(f32(a) / f32(b))),
    "flt": lambda a, b: int(bool(f32(a) < f32(b))),
    "f2d": lambda a, b: bits64(float(f32(a))),
    "fsqrt": _with_errstate(lambda a, b: bits32(newton_sqrtf(f32(a)))),
    "f2i": lambda a, b: int(float(f32(a))) & M32,
    "dadd": lambda a, b: bits64(f64(a) + f64(b)),
    "dsub": lambda a, b: bits64(f64(a) - f64(b)),
    "dmul": lambda a, b: bits64(f64(a) * f64(b)),
    "ddiv": lambda a, b: bits64(f64(a) / f64(b)),
    "d2f": _with_errstate(lambda a, b: bits32(np.float32(f64(a)))),
    "dsqrt": lambda a, b: bits64(newton_sqrt(f64(a))),
    "d2l": lambda a, b: int(f64(a)) & M64,
    "i2f": lambda a, b: bits32(np.float32(float(s32(a)))),
    "u2f": lambda a, b: bits32(np.float32(float(a))),
    "i2d": lambda a, b: bits64(float(s32(a))),
    "l2d": lambda a, b: bits64(float(s64(a))),
    "qmul": lambda a, b: qmul(a, b) & M32,
    "qdiv": lambda a, b: qdiv(a, b) & M32,
}

#: op -> (reference function of the real value, allowed absolute error) for approximations.
APPROXIMATE: dict[str, tuple[Callable[[float], float], float]] = {
    "qsqrt": (math.sqrt, 2 / 65536),
    "qsin": (math.sin, 0.0015),
    "qcos": (math.cos, 0.0015),
}


def check_line(line: str) -> str | None:
    """None when the report line is right, else a description of the mismatch.

    Lines whose op is not known here (e.g. ``checksum``, ``crc32``) are not checked by this
    function and return None.
    """
    parts = line.split()
    if len(parts) != 4:
        return None
    op, a_hex, b_hex, r_hex = parts
    a, b, r = int(a_hex, 16), int(b_hex, 16), int(r_hex, 16)
    if op in EXACT:
        expected = EXACT[op](a, b)
        return None if expected == r else f"{line}: expected {expected:x}"
    if op in APPROXIMATE:
        ref, tol = APPROXIMATE[op]
        want = ref(s32(a) / 65536)
        got = s32(r) / 65536
        return None if abs(got - want) <= tol * max(1.0, abs(want)) else f"{line}: {got} vs {want}"
    return None
