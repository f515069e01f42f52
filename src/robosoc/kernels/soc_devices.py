"""The HF-RISCV SoC devices seen by one core, as njit functions over the ``st`` array.

Register map (platform.md §2):

==========  ============  ====================================================================
0xe0000000  EXIT          store: end the run, the value is the exit code
0xe1000400  S0CAUSE       read-only: bit 2 = timer line (bit 1 GPIO, bit 3 UART: always 0 here)
0xe1020400  TIMERCAUSE    read-only: bit0 T0[16], bit1 T0[18], bit2 T1 compare flag, bit3 T1<OCR, bit4 T1[15]
0xe1020800  TIMERCAUSE_INV
0xe1020c00  TIMERMASK
0xe1024000  TIMER0        read-only free-running counter: a load starting in cycle c reads c-1
0xe1024400  TIMER1        16-bit; a write in a cycle with a count pulse is lost
0xe1024410  TIMER1_PRE    3 bits: pulse on toggles of TIMER0 bit 0,2,4,...,14
0xe1024420  TIMER1_CTC    clear-on-compare value (reset 0xffff)
0xe1024430  TIMER1_OCR    output compare
0xe1030400  UARTCAUSE     read-only 0 (transmission is instantaneous, no receiver)
0xe1034000  UART0         store: transmit a byte (copied to the output)
0xe1034010  UART0_DIV
0xf0000000  IRQ_VECTOR
0xf0000010  IRQ_CAUSE     read-only: bit 0 = S0CAUSE != 0, bits 1..7 external lines
0xf0000020  IRQ_MASK      8 bits
0xf0000030  IRQ_STATUS    8 bits, bit 0 = global enable
0xf0000040  IRQ_EPC
0xf00000d0  DEBUG         store: print a byte
==========  ============  ====================================================================

Timing conventions: TIMER0 in cycle x is x.  TIMER1 advances on a pulse in cycle y >= 2 when
(y - 1) is a multiple of the prescaler period P (TIMER0 bit b differs between cycles y - 1 and
y - 2, seen through two registers that reset to 0); the new value holds from y + 1.  Device
reads return the value of the cycle before the load starts; a store's write takes effect at the
end of its last cycle.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from robosoc.kernels.core_layout import NEVER as NEVER_CYCLE
from robosoc.kernels.core_layout import (
    OUT_CAPACITY,
    PH_ARMED,
    PH_NONE,
    PH_REPLAY,
    PH_TRAP,
    S_EXIT_CODE,
    S_EXT_IRQ,
    S_EXT_RISE,
    S_IRQ_ARMED,
    S_IRQ_CHECK,
    S_IRQ_EPC,
    S_IRQ_MASK,
    S_IRQ_PHASE,
    S_IRQ_RISE,
    S_IRQ_STATUS,
    S_IRQ_VECTOR,
    S_NI,
    S_OUT_LEN,
    S_T1_CTC,
    S_T1_FLAG,
    S_T1_HIST,
    S_T1_OCR,
    S_T1_PRE,
    S_T1_REF,
    S_T1_VAL,
    S_TINV,
    S_TMASK,
    S_UART_DIV,
)

EXIT_ADDR = 0xE0000000
S0CAUSE = 0xE1000400
TIMERCAUSE = 0xE1020400
TIMERCAUSE_INV = 0xE1020800
TIMERMASK = 0xE1020C00
TIMER0 = 0xE1024000
TIMER1 = 0xE1024400
TIMER1_PRE = 0xE1024410
TIMER1_CTC = 0xE1024420
TIMER1_OCR = 0xE1024430
UARTCAUSE = 0xE1030400
UART0 = 0xE1034000
UART0_DIV = 0xE1034010
IRQ_VECTOR = 0xF0000000
IRQ_CAUSE = 0xF0000010
IRQ_MASK = 0xF0000020
IRQ_STATUS = 0xF0000030
IRQ_EPC = 0xF0000040
DEBUG = 0xF00000D0
NI_BASE = 0xE1040000  # network interface, task id and sleep registers of an MPSoC tile (kernels/chip.py)
NI_END = 0xE1040040

NEVER = np.int64(NEVER_CYCLE)

# load results
LD_OK = 0
LD_UNMAPPED = 1
LD_NI = 2

# store results
ST_OK = 0
ST_IRQ_CHANGED = 1  # interrupt-relevant state changed: re-evaluate the controller
ST_EXIT = 2
ST_OUTPUT = 3  # a byte was output (the buffer may need draining)
ST_NI = 4  # a network-interface register: the chip simulator performs the access
ST_UNMAPPED = -1
ST_READONLY = -2


@njit(cache=True, inline="always")
def _ceil_div(a: int, b: int) -> int:
    return -((-a) // b)


@njit(cache=True)
def t1_period(st: np.ndarray) -> int:
    """Cycles between TIMER1 count pulses for the current prescaler."""
    return np.int64(1) << (2 * st[S_T1_PRE])


@njit(cache=True)
def t1_pulses(st: np.ndarray, x0: int, x1: int) -> int:
    """Number of TIMER1 pulses in cycles [x0, x1)."""
    if x1 <= x0:
        return 0
    # the selected TIMER0 bit is compared through two reset-to-zero registers: the first pulse
    # can come in cycle 2 (the bit's value in cycle 1 against cycle 0)
    x0 = max(x0, 2)
    if x1 <= x0:
        return 0
    p = t1_period(st)
    # pulse in cycle y  <=>  (y - 1) % p == 0: count multiples of p in [x0 - 1, x1 - 1)
    return _ceil_div(x1 - 1, p) - _ceil_div(x0 - 1, p)


@njit(cache=True)
def t1_advance(val: int, flag: int, ctc: int, k: int) -> tuple[int, int]:
    """TIMER1 value and compare flag after ``k`` pulses from (val, flag)."""
    if k <= 0:
        return val, flag
    to_ctc = (ctc - val) & 0xFFFF
    if k <= to_ctc:
        return (val + k) & 0xFFFF, flag
    k -= to_ctc + 1  # the pulse at CTC clears to 0 and toggles the flag
    period = ctc + 1
    wraps = 1 + k // period
    return k % period, flag ^ (wraps & 1)


@njit(cache=True)
def t1_at(st: np.ndarray, x: int) -> tuple[int, int]:
    """TIMER1 value and compare flag during cycle ``x`` (x >= the reference cycle - 3)."""
    ref = st[S_T1_REF]
    if x < ref:
        h = st[S_T1_HIST + 3 - min(ref - x, 3)]
        return h & 0xFFFF, (h >> 16) & 1
    k = t1_pulses(st, ref, x)
    return t1_advance(st[S_T1_VAL], st[S_T1_FLAG], st[S_T1_CTC], k)


@njit(cache=True)
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


@njit(cache=True)
def t1_write(st: np.ndarray, w: int, reg: int, value: int) -> None:
    """Apply a bus write to the TIMER1 block at the end of cycle w - 1.

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


@njit(cache=True)
def timer_cause(st: np.ndarray, x: int) -> int:
    v, f = t1_at(st, x)
    cause = (x >> 16) & 1
    cause |= ((x >> 18) & 1) << 1
    cause |= f << 2
    cause |= (1 if v < _ocr_at(st, x) else 0) << 3
    cause |= ((v >> 15) & 1) << 4
    return cause


@njit(cache=True)
def s0_cause(st: np.ndarray, x: int) -> int:
    timer_line = ((timer_cause(st, x) ^ st[S_TINV]) & st[S_TMASK]) != 0
    return 4 if timer_line else 0


@njit(cache=True)
def irq_cause(st: np.ndarray, x: int) -> int:
    ext = st[S_EXT_IRQ] & 0xFE
    if x >= st[S_EXT_RISE]:
        ext |= 2
    return (1 if s0_cause(st, x) != 0 else 0) | ext


@njit(cache=True)
def irq_pending(st: np.ndarray, x: int) -> bool:
    return (st[S_IRQ_STATUS] & 1) != 0 and (irq_cause(st, x) & st[S_IRQ_MASK]) != 0


@njit(cache=True)
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


@njit(cache=True)
def next_cause_change(st: np.ndarray, x: int) -> int:
    """Earliest cycle > x at which an unmasked timer cause bit may change (NEVER if none can)."""
    if (st[S_IRQ_STATUS] & 1) == 0:
        return NEVER
    best = NEVER
    if (st[S_IRQ_MASK] & 2) != 0 and st[S_EXT_RISE] > x:
        best = st[S_EXT_RISE]
    if (st[S_IRQ_MASK] & 1) == 0:
        return best
    mask = st[S_TMASK]
    if mask & 1:
        best = min(best, ((x >> 16) + 1) << 16)
    if mask & 2:
        best = min(best, ((x >> 18) + 1) << 18)
    if mask & 0x1C and x < st[S_T1_REF]:
        best = min(best, x + 1)  # inside the hand-stepped cycles around a timer write
    elif mask & 0x1C:
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
            p = t1_period(st)
            first = 1 + _ceil_div(max(x, 2) - 1, p) * p  # first pulse cycle >= x
            best = min(best, first + (k - 1) * p + 1)
    return best


@njit(cache=True)
def irq_event(st: np.ndarray, pc: int, cyc: int) -> tuple[int, int, int]:
    """Advance the interrupt controller at an instruction boundary.

    Called when ``cyc >= st[S_IRQ_CHECK]``.  Returns (pc, cyc, entered) where ``entered`` is 1
    when an interrupt or trap entry happened (pc then points to the vector and cyc includes the
    two vector-fetch bubbles).
    """
    phase = st[S_IRQ_PHASE]
    if phase == PH_REPLAY:
        # the first vector instruction executes a second time
        st[S_IRQ_PHASE] = PH_NONE
        st[S_IRQ_CHECK] = cyc
        return st[S_IRQ_VECTOR] & 0xFFFFFFFC, cyc, 0
    if phase == PH_TRAP:
        # the shadow instruction at trap + 8 has executed: fetch the vector
        st[S_IRQ_PHASE] = PH_REPLAY
        st[S_IRQ_CHECK] = cyc + 3
        return st[S_IRQ_VECTOR] & 0xFFFFFFFC, cyc + 2, 1
    if phase == PH_ARMED:
        if irq_pending(st, cyc):
            if cyc == st[S_IRQ_ARMED] + 1:
                # the instruction started in the armed cycle took one cycle: acknowledged then
                st[S_IRQ_EPC] = (pc + 4) & 0xFFFFFFFF
                st[S_IRQ_STATUS] &= 0xFE
                st[S_IRQ_PHASE] = PH_REPLAY
                st[S_IRQ_RISE] = -1
                st[S_IRQ_CHECK] = cyc + 3
                return st[S_IRQ_VECTOR] & 0xFFFFFFFC, cyc + 2, 2
            st[S_IRQ_ARMED] = cyc
            st[S_IRQ_CHECK] = cyc + 1
            return pc, cyc, 0
        st[S_IRQ_PHASE] = PH_NONE
        st[S_IRQ_RISE] = -1
    # PH_NONE: find the first cycle in [check, cyc] at which the request is pending
    if st[S_IRQ_RISE] < 0:
        x = min(st[S_IRQ_CHECK], cyc)
        while not irq_pending(st, x):
            x = next_cause_change(st, x)
            if x > cyc:
                st[S_IRQ_CHECK] = x
                return pc, cyc, 0
        st[S_IRQ_RISE] = x
    if not irq_pending(st, cyc):
        st[S_IRQ_RISE] = -1
        st[S_IRQ_CHECK] = next_cause_change(st, cyc)
        return pc, cyc, 0
    ready = st[S_IRQ_RISE] + 3
    if cyc >= ready:
        st[S_IRQ_PHASE] = PH_ARMED
        st[S_IRQ_ARMED] = cyc
        st[S_IRQ_CHECK] = cyc + 1
    else:
        st[S_IRQ_CHECK] = ready
    return pc, cyc, 0


@njit(cache=True)
def mmio_load(st: np.ndarray, addr: int, c: int) -> tuple[int, int]:
    """Read a device register with a load that starts in cycle ``c`` (value of cycle c - 1).

    Returns (value, LD_OK), (0, LD_UNMAPPED), or (0, LD_NI) for a network-interface register,
    which the chip simulator reads itself in global time order.
    """
    a = addr & 0xFFFFFFFC
    x = c - 1
    if NI_BASE <= a < NI_END:
        return 0, LD_NI if st[S_NI] != 0 else LD_UNMAPPED
    if a == TIMER0:
        return x & 0xFFFFFFFF, LD_OK
    if a == TIMER1:
        return t1_at(st, x)[0], LD_OK
    if a == TIMER1_PRE:
        return st[S_T1_PRE], LD_OK
    if a == TIMER1_CTC:
        return st[S_T1_CTC], LD_OK
    if a == TIMER1_OCR:
        return st[S_T1_OCR], LD_OK
    if a == TIMERCAUSE:
        return timer_cause(st, x), LD_OK
    if a == TIMERCAUSE_INV:
        return st[S_TINV], LD_OK
    if a == TIMERMASK:
        return st[S_TMASK], LD_OK
    if a == S0CAUSE:
        return s0_cause(st, x), LD_OK
    if a == IRQ_VECTOR:
        return st[S_IRQ_VECTOR], LD_OK
    if a == IRQ_CAUSE:
        return irq_cause(st, x), LD_OK
    if a == IRQ_MASK:
        return st[S_IRQ_MASK], LD_OK
    if a == IRQ_STATUS:
        return st[S_IRQ_STATUS], LD_OK
    if a == IRQ_EPC:
        return st[S_IRQ_EPC], LD_OK
    if a == UARTCAUSE:
        return 0, LD_OK
    if a == UART0_DIV:
        return st[S_UART_DIV], LD_OK
    if a == UART0 or a == DEBUG:
        return 0, LD_OK
    return 0, LD_UNMAPPED


@njit(cache=True)
def _emit(st: np.ndarray, out: np.ndarray, value: int) -> int:
    n = st[S_OUT_LEN]
    out[n] = value & 0xFF
    st[S_OUT_LEN] = n + 1
    return ST_OUTPUT


@njit(cache=True)
def mmio_store(st: np.ndarray, out: np.ndarray, addr: int, value: int, s: int) -> int:
    """Write a device register with a store that starts in cycle ``s``.

    The write happens at the end of the store's last cycle (s + 2) and holds from s + 3.
    Returns one of the ST_* codes.
    """
    a = addr & 0xFFFFFFFC
    v = value & 0xFFFFFFFF
    w = s + 3
    if NI_BASE <= a < NI_END:
        return ST_NI if st[S_NI] != 0 else ST_UNMAPPED
    if a == DEBUG or a == UART0:
        return _emit(st, out, v)
    if a == EXIT_ADDR:
        st[S_EXIT_CODE] = value
        return ST_EXIT
    if a == IRQ_STATUS:
        st[S_IRQ_STATUS] = v & 0xFF
        return ST_IRQ_CHANGED
    if a == IRQ_MASK:
        st[S_IRQ_MASK] = v & 0xFF
        return ST_IRQ_CHANGED
    if a == IRQ_VECTOR:
        st[S_IRQ_VECTOR] = v
        return ST_OK
    if a == IRQ_EPC:
        st[S_IRQ_EPC] = v
        return ST_OK
    if a == TIMERMASK:
        st[S_TMASK] = v & 0x1F
        return ST_IRQ_CHANGED
    if a == TIMERCAUSE_INV:
        st[S_TINV] = v & 0x1F
        return ST_IRQ_CHANGED
    if a == TIMER1 or a == TIMER1_PRE or a == TIMER1_CTC or a == TIMER1_OCR:
        t1_write(st, w, a, v)
        return ST_IRQ_CHANGED
    if a == UART0_DIV:
        st[S_UART_DIV] = v
        return ST_OK
    if a in (TIMER0, TIMERCAUSE, S0CAUSE, IRQ_CAUSE, UARTCAUSE):
        return ST_READONLY
    return ST_UNMAPPED


__all__ = ["OUT_CAPACITY", "irq_event", "mmio_load", "mmio_store", "next_cause_change"]
