"""numpy references for real_check.c's lines (matrices and quaternions over real_t).

:func:`errors` returns, per routine, the largest error of a run: in LSB (2^-16) for the fixed
build, and in units of the float32 rounding bound for the float build (an error of 1.0 means
(terms + 1) · 2^-24 · Σ|products|, the classic bound on a sum of products), except the solve and
inverse, whose float errors are relative to the largest element of the result.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path

import numpy as np
from flight_data import decode

from robosoc.control import quaternion as quat
from robosoc.firmware import MATH_DIR, math_sources

REAL_CHECK = Path(__file__).resolve().parent / "real_check.c"
LSB = 2.0**-16
U32 = 2.0**-24

#: op -> largest allowed error (fixed: LSB; float: see the module docstring)
BOUNDS: dict[str, dict[str, float]] = {
    "fixed": {
        "mul": 0.5,
        "mul_bt": 0.5,
        "mul_at": 0.5,
        "solve": 6.0,
        "inverse": 4.0,
        "norm": 0.5,
        "qmul": 0.5,
        "qnormalize": 1.0,
        "qrotate": 2.0,
        "qrotate_to_body": 2.0,
        "qjacobian": 0.5,
        "qintegrate": 0.6,
        "qeuler": 4.0,
        "qtriad": 4.0,
    },
    "float": {
        "mul": 1.0,
        "mul_bt": 1.0,
        "mul_at": 1.0,
        "solve": 1e-5,
        "inverse": 1e-5,
        "norm": 1.0,
        "qmul": 1.0,
        "qnormalize": 1.0,
        "qrotate": 1.0,
        "qrotate_to_body": 1.0,
        "qjacobian": 1.0,
        "qintegrate": 1.0,
        "qeuler": 1.0,
        "qtriad": 1.0,
    },
}


def real_check_sources() -> list[Path]:
    return [REAL_CHECK, *math_sources()]


def _product_error(ref: np.ndarray, bound_terms: np.ndarray, n: int, out: np.ndarray, arith: str) -> float:
    """Largest error of a sum-of-products result (LSB, or float units of (n+1)·u·Σ|products|)."""
    if arith == "fixed":
        return float(np.max(np.abs(out - ref)) / LSB)
    scale = (n + 1) * U32 * np.maximum(bound_terms, 2.0**-126)
    return float(np.max(np.abs(out - ref) / scale))


def _matrix_products(ins: np.ndarray, out: np.ndarray, op: str, arith: str) -> float:
    a = ins[:49].reshape(7, 7)
    b = ins[49:98].reshape(7, 7)
    scale = 2.0 ** ins[98]
    if op == "mul":
        x, y = a, b
    elif op == "mul_bt":
        x, y = a, b.T
    else:
        x, y = a.T, b
    ref = x @ y * scale
    return _product_error(ref, np.abs(x) @ np.abs(y) * scale, 7, out.reshape(7, 7), arith)


def _solve(ins: np.ndarray, out: np.ndarray, arith: str) -> float:
    a = ins[:36].reshape(6, 6)
    b = ins[36:78].reshape(6, 7)
    assert out[42] == 0
    ref = np.linalg.solve(a, b)
    err = np.max(np.abs(out[:42].reshape(6, 7) - ref))
    return float(err / LSB) if arith == "fixed" else float(err / np.max(np.abs(ref)))


def _inverse(ins: np.ndarray, out: np.ndarray, arith: str) -> float:
    assert out[16] == 0
    ref = np.linalg.inv(ins.reshape(4, 4))
    err = np.max(np.abs(out[:16].reshape(4, 4) - ref))
    return float(err / LSB) if arith == "fixed" else float(err / np.max(np.abs(ref)))


def _elementwise(ref: np.ndarray, out: np.ndarray, terms: int, magnitude: np.ndarray, arith: str) -> float:
    return _product_error(ref, magnitude, terms, out, arith)


def _norm(ins: np.ndarray, out: np.ndarray, arith: str) -> float:
    ref = math.sqrt(float(ins @ ins))
    # float: squares summed (7 terms), then a correctly rounded root
    return _elementwise(np.array([ref]), out, 7, np.array([ref]), arith)


def _qmul(ins: np.ndarray, out: np.ndarray, arith: str) -> float:
    a, b = ins[:4], ins[4:8]
    mag = np.full(4, np.abs(a).sum() * np.abs(b).max())
    return _elementwise(quat.multiply(a, b), out, 4, mag, arith)


def _qnormalize(ins: np.ndarray, out: np.ndarray, arith: str) -> float:
    return _elementwise(quat.normalize(ins), out, 8, np.ones(4), arith)


def _rotation_magnitude(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    return (np.abs(quat.to_matrix(np.abs(q))) + 1.0) @ np.abs(v) + 1.0


def _qrotate(ins: np.ndarray, out: np.ndarray, arith: str) -> float:
    q, v = ins[:4], ins[4:7]
    return _elementwise(quat.to_matrix(q) @ v, out, 6, _rotation_magnitude(q, v), arith)


def _qrotate_to_body(ins: np.ndarray, out: np.ndarray, arith: str) -> float:
    q, v = ins[:4], ins[4:7]
    return _elementwise(quat.rotate_to_body(q, v), out, 6, _rotation_magnitude(q, v), arith)


def _qjacobian(ins: np.ndarray, out: np.ndarray, arith: str) -> float:
    q, v = ins[:4], ins[4:7]
    ref = quat.rotate_to_body_jacobian(q, v)
    mag = 4.0 * np.abs(q).max() * np.abs(v).sum() * np.ones_like(ref)
    return _elementwise(ref, out.reshape(3, 4), 3, mag, arith)


def _qintegrate(ins: np.ndarray, out: np.ndarray, arith: str) -> float:
    q, rate, dt = ins[:4], ins[4:7], ins[7]
    ref = (np.eye(4) + 0.5 * dt * quat.omega_matrix(rate)) @ q
    return _elementwise(ref, out, 6, np.abs(q).sum() * np.ones(4), arith)


def _qeuler(ins: np.ndarray, out: np.ndarray, arith: str) -> float:
    w, x, y, z = ins
    if abs(2 * (w * y - z * x)) > 0.9:
        return 0.0  # near pitch +-90 degrees roll and yaw are ill-conditioned: not a library error
    ref = quat.to_euler(ins)
    if arith == "fixed":
        return float(np.max(np.abs(out - ref)) / LSB)
    # atan2/asin of sums of products: a few float roundings of arguments of size ~1
    return float(np.max(np.abs(out - ref)) / (16 * U32))


def _qtriad(ins: np.ndarray, out: np.ndarray, arith: str) -> float:
    acc, field = ins[:3], ins[3:6]
    na, nf = np.linalg.norm(acc), np.linalg.norm(field)
    if na < 1.0 or nf < 0.2 or np.linalg.norm(np.cross(acc, field)) < 0.3 * na * nf:
        return 0.0  # a short or nearly parallel pair is ill-conditioned: not a library error
    ref = quat.from_accel_mag(acc, field)
    error = min(np.max(np.abs(out - ref)), np.max(np.abs(out + ref)))  # q and -q where w is near 0
    if arith == "fixed":
        return float(error / LSB)
    # normalisations, cross products, a root and divisions: a few float roundings of size ~1
    return float(error / (16 * U32))


CHECKS: dict[str, Callable[[np.ndarray, np.ndarray, str], float]] = {
    "solve": _solve,
    "inverse": _inverse,
    "norm": _norm,
    "qmul": _qmul,
    "qnormalize": _qnormalize,
    "qrotate": _qrotate,
    "qrotate_to_body": _qrotate_to_body,
    "qjacobian": _qjacobian,
    "qintegrate": _qintegrate,
    "qeuler": _qeuler,
    "qtriad": _qtriad,
}


def parse(text: str, arith: str) -> list[tuple[str, np.ndarray, np.ndarray, int]]:
    """(op, inputs, outputs, cycles) per line, values decoded from real_t bits."""
    rows = []
    for line in text.splitlines():
        head, outs, spent = line.split("|")
        words = head.split()
        ins = decode([int(w, 16) for w in words[1:]], arith)
        rows.append((words[0], ins, decode([int(w, 16) for w in outs.split()], arith), int(spent)))
    return rows


def errors(text: str, arith: str) -> dict[str, float]:
    """op -> largest error over the run."""
    worst: dict[str, float] = {}
    for op, ins, outs, _ in parse(text, arith):
        if op in ("mul", "mul_bt", "mul_at"):
            err = _matrix_products(ins, outs, op, arith)
        else:
            err = CHECKS[op](ins, outs, arith)
        worst[op] = max(worst.get(op, 0.0), err)
    return worst


def mean_cycles(text: str, arith: str) -> dict[str, float]:
    sums: dict[str, list[int]] = {}
    for op, _, _, spent in parse(text, arith):
        sums.setdefault(op, []).append(spent)
    return {op: float(np.mean(v)) for op, v in sums.items()}


INCLUDE_DIRS = [MATH_DIR]
