"""The HF-RISCV timer block: TIMER0, TIMER1 with prescaler and compare, and the timer causes.

Register map (platform.md §2):

==========  ==============  ==================================================================
0xe1020400  TIMERCAUSE      read-only: bit0 T0[16], bit1 T0[18], bit2 T1 compare flag, bit3
                            T1 < OCR, bit4 T1[15]
0xe1020800  TIMERCAUSE_INV  5 bits: the timer line is ((cause ^ inv) & mask) != 0
0xe1020c00  TIMERMASK       5 bits
0xe1024000  TIMER0          read-only free-running counter
0xe1024400  TIMER1          16-bit; a write in a cycle with a count pulse is lost
0xe1024410  TIMER1_PRE      3 bits: pulse on toggles of TIMER0 bit 0,2,4,...,14
0xe1024420  TIMER1_CTC      clear-on-compare value (reset 0xffff)
0xe1024430  TIMER1_OCR      output compare
==========  ==============  ==================================================================

Everything here counts in **device cycles** x (the value TIMER0 holds; platform.md §3): TIMER0
in device cycle x is x.  TIMER1 advances on a pulse in device cycle y >= 2 when (y - 1) is a
multiple of the prescaler period P (TIMER0 bit b differs between cycles y - 1 and y - 2, seen
through two registers that reset to 0); the new value holds from y + 1.  TIMER1 is kept in closed
form from a reference cycle, with the three hand-stepped cycles around the last write kept as
history, so reading it or predicting its next compare costs no per-cycle work.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from robosoc.kernels.borrowed import UNCOUNTED
from robosoc.kernels.core_layout import (
    DEV_READONLY,
    DEV_UNMAPPED,
    DEV_WRITTEN,
    NEVER,
    S_T1_CTC,
    S_T1_FLAG,
    S_T1_HIST,
    S_T1_OCR,
    S_T1_PRE,
    S_T1_REF,
    S_T1_VAL,
    S_TINV,
    S_TMASK,
)

TIMERCAUSE = 0xE1020400
TIMERCAUSE_INV = 0xE1020800
TIMERMASK = 0xE1020C00
TIMER0 = 0xE1024000
TIMER1 = 0xE1024400
TIMER1_PRE = 0xE1024410
TIMER1_CTC = 0xE1024420
TIMER1_OCR = 0xE1024430

CAUSE_BITS = 0x1F  # five timer causes
T1_CAUSES = 0x1C  # the causes that depend on TIMER1 (flag, compare, bit 15)


@njit(cache=True, inline="always")
def _ceil_shift(a: int, s: int) -> int:
    """ceil(a / 2**s) for any integer a (an arithmetic shift rounds towards minus infinity)."""
    return -((-a) >> s)


@njit(cache=True, inline="always")
def _t1_shift(st: np.ndarray) -> int:
    """log2 of the prescaler period: the period is a power of two, so pulses are counted by shifts."""
    return 2 * st[S_T1_PRE]


@njit(**UNCOUNTED)
def t1_pulses(st: np.ndarray, x0: int, x1: int) -> int:
    """Number of TIMER1 pulses in device cycles [x0, x1)."""
    if x1 <= x0:
        return 0
    # the selected TIMER0 bit is compared through two reset-to-zero registers: the first pulse
    # can come in cycle 2 (the bit's value in cycle 1 against cycle 0)
    x0 = max(x0, 2)
    if x1 <= x0:
        return 0
    sh = _t1_shift(st)
    # pulse in cycle y  <=>  (y - 1) % p == 0: count multiples of p = 2**sh in [x0 - 1, x1 - 1)
    return _ceil_shift(x1 - 1, sh) - _ceil_shift(x0 - 1, sh)


@njit(**UNCOUNTED)
def t1_advance(val: int, flag: int, ctc: int, k: int) -> tuple[int, int]:
    """TIMER1 value and compare flag after ``k`` pulses from (val, flag)."""
    if k <= 0:
        return val, flag
    to_ctc = (ctc - val) & 0xFFFF
    if k <= to_ctc:
        return (val + k) & 0xFFFF, flag
    k -= to_ctc + 1  # the pulse at CTC clears to 0 and toggles the flag
    if k <= ctc:  # no further clearing pulse (the common case: read within one period)
        return k, flag ^ 1
    period = ctc + 1
    q = k // period  # k >= 0, period > 0: one division, the remainder from it
    return k - q * period, flag ^ ((1 + q) & 1)


@njit(**UNCOUNTED)
def t1_at(st: np.ndarray, x: int) -> tuple[int, int]:
    """TIMER1 value and compare flag during device cycle ``x`` (x >= the reference cycle - 3)."""
    ref = st[S_T1_REF]
    if x < ref:
        h = st[S_T1_HIST + 3 - min(ref - x, 3)]
        return h & 0xFFFF, (h >> 16) & 1
    k = t1_pulses(st, ref, x)
    return t1_advance(st[S_T1_VAL], st[S_T1_FLAG], st[S_T1_CTC], k)


@njit(**UNCOUNTED)
def _ocr_at(st: np.ndarray, x: int) -> int:
    ref = st[S_T1_REF]
    if x < ref:
        return st[S_T1_HIST + 3 - min(ref - x, 3)] >> 17
    return st[S_T1_OCR]


@njit(cache=True, inline="always")
def _sel_bit(n: int, pre: int) -> int:
    """The prescaler's TIMER0 bit in cycle n (the sampling registers read 0 before reset)."""
    return 0 if n < 0 else (n >> (2 * pre)) & 1


@njit(cache=True, inline="always")
def _t1_count(v: int, f: int, ctc: int) -> tuple[int, int]:
    if v != ctc:
        return (v + 1) & 0xFFFF, f
    return 0, f ^ 1


@njit(**UNCOUNTED)
def t1_write(st: np.ndarray, w: int, reg: int, value: int) -> None:
    """Apply a bus write to the TIMER1 block at the end of device cycle w - 1 (it holds from w).

    The cycles around a write follow the two-register sampling of the prescaler bit: the pulses
    of cycles w - 1 and w still compare bits selected by the old prescaler, the pulse of cycle
    w + 1 compares the new selection (cycle w) with the old one (cycle w - 1).  The values of
    cycles w - 1, w and w + 1 are kept so that loads and the interrupt controller see them, and
    the closed form restarts at cycle w + 2.
    """
    old_pre = st[S_T1_PRE]
    v_prev, f_prev = t1_at(st, w - 1)
    ocr_prev = _ocr_at(st, w - 1)
    v, f = t1_at(st, w)  # includes the pulse of cycle w - 1 (old prescaler, old CTC)
    if reg == TIMER1:
        if _sel_bit(w - 2, old_pre) == _sel_bit(w - 3, old_pre):
            v = value & 0xFFFF  # no pulse in the write cycle: the write lands
    elif reg == TIMER1_PRE:
        st[S_T1_PRE] = value & 7
    elif reg == TIMER1_CTC:
        st[S_T1_CTC] = value & 0xFFFF
    else:
        st[S_T1_OCR] = value & 0xFFFF
    new_pre = st[S_T1_PRE]
    ctc = st[S_T1_CTC]
    ocr = st[S_T1_OCR]
    st[S_T1_HIST] = v_prev | (f_prev << 16) | (ocr_prev << 17)
    st[S_T1_HIST + 1] = v | (f << 16) | (ocr << 17)
    if _sel_bit(w - 1, old_pre) != _sel_bit(w - 2, old_pre):  # pulse in cycle w
        v, f = _t1_count(v, f, ctc)
    st[S_T1_HIST + 2] = v | (f << 16) | (ocr << 17)
    if _sel_bit(w, new_pre) != _sel_bit(w - 1, old_pre):  # pulse in cycle w + 1
        v, f = _t1_count(v, f, ctc)
    st[S_T1_REF] = w + 2
    st[S_T1_VAL] = v
    st[S_T1_FLAG] = f


@njit(**UNCOUNTED)
def timer_cause(st: np.ndarray, x: int) -> int:
    """TIMERCAUSE during device cycle ``x``."""
    v, f = t1_at(st, x)
    cause = (x >> 16) & 1
    cause |= ((x >> 18) & 1) << 1
    cause |= f << 2
    cause |= (1 if v < _ocr_at(st, x) else 0) << 3
    cause |= ((v >> 15) & 1) << 4
    return cause


@njit(**UNCOUNTED)
def timer_line(st: np.ndarray, x: int) -> bool:
    """The timer block's interrupt line during device cycle ``x``."""
    return ((timer_cause(st, x) ^ st[S_TINV]) & st[S_TMASK]) != 0


@njit(**UNCOUNTED)
def _t1_steps_to(val: int, target: int, ctc: int) -> int:
    """Pulses until TIMER1 first equals ``target`` (-1 if it never does before a wrap)."""
    if val <= ctc:
        return target - val if val < target <= ctc else -1
    # above CTC: counts to 0xffff, overflows to 0, then climbs to CTC
    if target > val:
        return target - val
    if target <= ctc:
        return 0x10000 - val + target
    return -1


@njit(**UNCOUNTED)
def next_timer_change(st: np.ndarray, x: int) -> int:
    """Earliest device cycle > x at which an unmasked timer cause may change (NEVER if none can)."""
    mask = st[S_TMASK]
    best = NEVER
    if mask & 1:
        best = min(best, ((x >> 16) + 1) << 16)
    if mask & 2:
        best = min(best, ((x >> 18) + 1) << 18)
    if mask & T1_CAUSES and x < st[S_T1_REF]:
        best = min(best, x + 1)  # inside the hand-stepped cycles around a timer write
    elif mask & T1_CAUSES:
        val, _ = t1_at(st, x)
        ctc = st[S_T1_CTC]
        k = NEVER
        if val <= ctc:
            k = ctc - val + 1  # the clearing pulse
        for target in (st[S_T1_OCR], 0x8000, 0):
            s = _t1_steps_to(val, target, ctc)
            if s > 0:
                k = min(k, s)
        if k < NEVER:
            sh = _t1_shift(st)
            first = 1 + (_ceil_shift(max(x, 2) - 1, sh) << sh)  # first pulse cycle >= x
            best = min(best, first + ((k - 1) << sh) + 1)
    return best


@njit(**UNCOUNTED)
def timer_load(st: np.ndarray, a: int, x: int) -> tuple[int, bool]:
    """Read timer register ``a`` (word address) as it was in device cycle ``x``; (value, mapped)."""
    if a == TIMER0:
        return x & 0xFFFFFFFF, True
    if a == TIMER1:
        return t1_at(st, x)[0], True
    if a == TIMER1_PRE:
        return st[S_T1_PRE], True
    if a == TIMER1_CTC:
        return st[S_T1_CTC], True
    if a == TIMER1_OCR:
        return st[S_T1_OCR], True
    if a == TIMERCAUSE:
        return timer_cause(st, x), True
    if a == TIMERCAUSE_INV:
        return st[S_TINV], True
    if a == TIMERMASK:
        return st[S_TMASK], True
    return 0, False


@njit(**UNCOUNTED)
def timer_store(st: np.ndarray, a: int, v: int, w: int) -> int:
    """Write timer register ``a``; the value holds from device cycle ``w``.  A DEV_* code."""
    if a == TIMERMASK:
        st[S_TMASK] = v & CAUSE_BITS
    elif a == TIMERCAUSE_INV:
        st[S_TINV] = v & CAUSE_BITS
    elif a == TIMER1 or a == TIMER1_PRE or a == TIMER1_CTC or a == TIMER1_OCR:
        t1_write(st, w, a, v)
    elif a == TIMER0 or a == TIMERCAUSE:
        return DEV_READONLY
    else:
        return DEV_UNMAPPED
    return DEV_WRITTEN


__all__ = ["next_timer_change", "t1_at", "timer_line", "timer_load", "timer_store"]
