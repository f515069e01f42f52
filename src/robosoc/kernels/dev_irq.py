"""The HF-RISCV interrupt controller and the core's entry sequences (platform.md §3).

Register map:

==========  ==========  ======================================================================
0xe1000400  S0CAUSE     read-only: bit 2 = timer line (bit 1 GPIO, bit 3 UART: always 0 here)
0xf0000000  IRQ_VECTOR  address of the handler
0xf0000010  IRQ_CAUSE   read-only: bit 0 = S0CAUSE != 0, bits 1..7 external lines (bit 1: the
                        network interface of an MPSoC tile holds a packet)
0xf0000020  IRQ_MASK    8 bits
0xf0000030  IRQ_STATUS  8 bits, bit 0 = global enable (cleared by every entry)
0xf0000040  IRQ_EPC     address of the squashed instruction + 4 (traps: trap address + 8)
==========  ==========  ======================================================================

Two time frames.  *Instruction cycles* number the cycles as the core's timing does (the first
instruction executes in cycle 3); *device cycles* are what TIMER0 reads.  Device cycle x and
instruction cycle x + 1 are the same clock: a load starting in instruction cycle c reads device
cycle c - 1, and a device store starting in instruction cycle s writes at the end of its first
cycle, so the new value holds from device cycle s.

The controller (idle -> int -> req -> ack -> done in the RTL) is modelled by three numbers:

* ``S_IRQ_IDLE``: the device cycle from which it is idle.  0 after reset; NEVER after an entry
  (done) until a store starting in s sets IRQ_STATUS bit 0, which makes it idle from s + 2.
* ``S_IRQ_RISE``: the device cycle t in which, idle, it saw (IRQ_CAUSE & IRQ_MASK) != 0 with
  IRQ_STATUS bit 0 set.  From then on the request is latched: the line may drop and software may
  even clear IRQ_STATUS, the request still reaches the core in instruction cycle t + 4 (the RTL's
  int/req states do not look at either).
* ``S_IRQ_SCAN``: how far it has looked.  Device cycles before the current instruction boundary
  are final (no store can change them any more), so at a boundary the controller looks over
  [scan, boundary) with the registers as they are; a store to a register that feeds the line
  first brings it up to the store's cycle with the old values, then changes the register.

The core consults the controller only at boundaries >= ``S_IRQ_CHECK`` (the earliest boundary at
which an entry could happen), so an instruction costs one comparison for all of this.  Entry
happens at the first instruction boundary b >= t + 5, whatever instruction ended there: the
instruction that would start at b is squashed, IRQ_EPC <- its address + 4, IRQ_STATUS bit 0 <- 0,
the first vector instruction executes in b + 2 and again in b + 3, the second in b + 4.

A request that meets a multiply (r = t + 4 inside the multiply's cycles [m, m + L)) is the
core_rv32im_nodiv erratum: with r <= m + L - 3 the shadow instruction runs, then the vector once
(a taken jump or branch there drops the vector and leaves interrupts off); with r = m + L - 2 the
multiply executes again after the return.  ``ERRATA_RTL`` reproduces that; ``ERRATA_SPEC`` enters
at the boundary where the multiply ends and counts what the RTL would have done.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from robosoc.kernels.borrowed import UNCOUNTED
from robosoc.kernels.core_layout import (
    C_ENTRY_STALL,
    C_IRQ,
    C_IRQ_LOST,
    C_TRAP,
    DEV_READONLY,
    DEV_UNMAPPED,
    DEV_WRITTEN,
    ERRATA_RTL,
    NEVER,
    PH_NONE,
    PH_REPLAY,
    PH_SHADOW,
    PH_TRAP,
    S_ERRATA,
    S_EXT_IRQ,
    S_EXT_RISE,
    S_IRQ_CHECK,
    S_IRQ_EPC,
    S_IRQ_IDLE,
    S_IRQ_MASK,
    S_IRQ_PHASE,
    S_IRQ_RISE,
    S_IRQ_SCAN,
    S_IRQ_SHADOW_END,
    S_IRQ_STATUS,
    S_IRQ_VECTOR,
    S_IRQMUL_COUNT,
    S_IRQMUL_PC,
    S_MUL_END,
)
from robosoc.kernels.dev_timer import next_timer_change, timer_line

S0CAUSE = 0xE1000400
IRQ_VECTOR = 0xF0000000
IRQ_CAUSE = 0xF0000010
IRQ_MASK = 0xF0000020
IRQ_STATUS = 0xF0000030
IRQ_EPC = 0xF0000040

S0_TIMER_BIT = 4  # S0CAUSE bit of the timer block
CAUSE_PACKET = 2  # IRQ_CAUSE bit of a tile's network interface

REQUEST_DELAY = 4  # a line high in device cycle t raises the core's request in instruction cycle t + 4
ENTRY_DELAY = REQUEST_DELAY + 1  # entry at the first instruction boundary >= t + 5
IDLE_DELAY = 2  # done -> idle at device cycle s + 2 after a store starting in s sets IRQ_STATUS bit 0
VECTOR_BUBBLES = 2  # the first vector instruction executes in b + 2 (and again in b + 3)
M32 = 0xFFFFFFFF


@njit(**UNCOUNTED)
def s0_cause(st: np.ndarray, x: int) -> int:
    return S0_TIMER_BIT if timer_line(st, x) else 0


@njit(**UNCOUNTED)
def irq_cause(st: np.ndarray, x: int) -> int:
    """IRQ_CAUSE during device cycle ``x``."""
    ext = st[S_EXT_IRQ] & 0xFE
    if x >= st[S_EXT_RISE]:
        ext |= CAUSE_PACKET
    return (1 if s0_cause(st, x) != 0 else 0) | ext


@njit(**UNCOUNTED)
def irq_pending(st: np.ndarray, x: int) -> bool:
    """Whether an idle controller starts a request in device cycle ``x``."""
    return (st[S_IRQ_STATUS] & 1) != 0 and (irq_cause(st, x) & st[S_IRQ_MASK]) != 0


@njit(**UNCOUNTED)
def cause_enabled(st: np.ndarray, x: int) -> bool:
    """Whether (IRQ_CAUSE & IRQ_MASK) != 0 in device cycle ``x``, whatever IRQ_STATUS says."""
    return (irq_cause(st, x) & st[S_IRQ_MASK]) != 0


@njit(**UNCOUNTED)
def requests_possible(st: np.ndarray) -> bool:
    """Whether the controller can raise a request without a store first (enabled, not done)."""
    return (st[S_IRQ_STATUS] & 1) != 0 and st[S_IRQ_IDLE] < NEVER


@njit(**UNCOUNTED)
def hears_packets(st: np.ndarray) -> bool:
    """Whether a packet arriving now could start a request without a store first: IRQ_MASK bit 1
    set, the controller enabled and idle, and no request latched yet.  A core inside its handler
    (done until software sets IRQ_STATUS bit 0), with interrupts off, or with a request already on
    its way does not: the packet line reaches it only through an IRQ_CAUSE read, or after a store
    to IRQ_MASK or IRQ_STATUS, or a sleep (WFI-like wake-up); the chip loop's long quanta stop it
    before each of those (kernels/chip.py)."""
    return (st[S_IRQ_MASK] & CAUSE_PACKET) != 0 and st[S_IRQ_RISE] < 0 and requests_possible(st)


@njit(**UNCOUNTED)
def next_cause_change(st: np.ndarray, x: int) -> int:
    """Earliest device cycle > x at which ``irq_pending`` may change (NEVER if it cannot)."""
    if (st[S_IRQ_STATUS] & 1) == 0:
        return NEVER
    return next_masked_change(st, x)


@njit(**UNCOUNTED)
def next_masked_change(st: np.ndarray, x: int) -> int:
    """Earliest device cycle > x at which ``cause_enabled`` may change (NEVER if it cannot)."""
    best = NEVER
    if (st[S_IRQ_MASK] & CAUSE_PACKET) != 0 and st[S_EXT_RISE] > x:
        best = st[S_EXT_RISE]
    if (st[S_IRQ_MASK] & 1) != 0:
        best = min(best, next_timer_change(st, x))
    return best


@njit(**UNCOUNTED)
def irq_scan(st: np.ndarray, upto: int) -> None:
    """Let the controller look at device cycles [scan, upto) with the registers as they are now.

    Latches the first device cycle with a request (S_IRQ_RISE) and stops there; otherwise moves
    S_IRQ_SCAN to the first cycle at or after ``upto`` at which a request could start.
    """
    if st[S_IRQ_RISE] >= 0:
        return
    x = max(st[S_IRQ_SCAN], st[S_IRQ_IDLE])
    while x < upto:
        if irq_pending(st, x):
            st[S_IRQ_RISE] = x
            st[S_IRQ_SCAN] = x
            return
        x = next_cause_change(st, x)
    st[S_IRQ_SCAN] = x


@njit(**UNCOUNTED)
def earliest_entry(st: np.ndarray) -> int:
    """The first instruction boundary at which an entry can happen, as things stand (NEVER: none)."""
    t = st[S_IRQ_RISE]
    if t < 0:
        t = max(st[S_IRQ_SCAN], st[S_IRQ_IDLE])
    return NEVER if t >= NEVER else t + ENTRY_DELAY


@njit(**UNCOUNTED)
def irq_input_changed(st: np.ndarray, x: int) -> None:
    """A register feeding the controller changed from device cycle ``x`` on (after ``irq_scan(st, x)``)."""
    if st[S_IRQ_RISE] < 0 and st[S_IRQ_SCAN] > x:
        st[S_IRQ_SCAN] = x
    st[S_IRQ_CHECK] = min(st[S_IRQ_CHECK], earliest_entry(st))


@njit(**UNCOUNTED)
def irq_external_rise(st: np.ndarray, x: int) -> None:
    """IRQ_CAUSE bit 1 (a packet waits) rises in device cycle ``x`` (not before the core's present)."""
    st[S_EXT_RISE] = x
    irq_input_changed(st, x)


@njit(**UNCOUNTED)
def first_request(st: np.ndarray, horizon: int) -> int:
    """Device cycle of the next request if no store intervenes (NEVER if none before ``horizon``).

    Unlike :func:`irq_scan` this latches nothing: a sleeping core's wake-up is predicted with it,
    and a packet arriving meanwhile may still bring the request forward.
    """
    t = st[S_IRQ_RISE]
    if t >= 0:
        return t
    x = max(st[S_IRQ_SCAN], st[S_IRQ_IDLE])
    for _ in range(4096):
        if x >= horizon:
            return NEVER
        if irq_pending(st, x):
            return x
        x = next_cause_change(st, x)
    return x  # not found yet: a conservative wake-up that looks again from there


@njit(**UNCOUNTED)
def first_cause(st: np.ndarray, x: int) -> int:
    """First device cycle >= x with ``cause_enabled`` if no store intervenes (NEVER: none).

    Gives up after a bounded search and returns the cycle reached, a conservative point at which
    to look again.
    """
    for _ in range(4096):
        if x >= NEVER or cause_enabled(st, x):
            return x
        x = next_masked_change(st, x)
    return x


@njit(**UNCOUNTED)
def _enter(st: np.ndarray, epc: int) -> int:
    """Bookkeeping of an interrupt entry; returns the vector address."""
    st[S_IRQ_EPC] = epc & M32
    st[S_IRQ_STATUS] &= 0xFE
    st[S_IRQ_RISE] = -1
    st[S_IRQ_IDLE] = NEVER  # done until software sets IRQ_STATUS bit 0 again
    st[S_IRQ_SCAN] = NEVER
    return st[S_IRQ_VECTOR] & 0xFFFFFFFC


@njit(**UNCOUNTED)
def trap(st: np.ndarray, pc: int, cyc: int) -> None:
    """A SYSTEM instruction at ``pc`` executed in ``cyc``: EPC = pc + 8, the shadow at pc + 8 runs next.

    A trap clears IRQ_STATUS bit 0 but does not move the controller's state machine.
    """
    st[S_IRQ_EPC] = (pc + 8) & M32
    st[S_IRQ_STATUS] &= 0xFE
    st[S_IRQ_PHASE] = PH_TRAP
    st[S_IRQ_CHECK] = cyc + 1


@njit(**UNCOUNTED)
def irq_event(st: np.ndarray, ctr: np.ndarray, pc: int, cyc: int) -> tuple[int, int]:
    """The core is at instruction boundary ``cyc`` >= S_IRQ_CHECK, about to run ``pc``.

    Returns (pc, cyc) to go on with: unchanged, or the vector after an entry (``cyc`` then
    includes the vector-fetch bubbles).  Counts entries and their bubbles in ``ctr``.
    """
    phase = st[S_IRQ_PHASE]
    if phase == PH_REPLAY:
        # the first vector instruction executes a second time
        st[S_IRQ_PHASE] = PH_NONE
        st[S_IRQ_CHECK] = earliest_entry(st)
        return st[S_IRQ_VECTOR] & 0xFFFFFFFC, cyc
    if phase == PH_TRAP:
        # the shadow instruction at trap + 8 has executed: fetch the vector
        st[S_IRQ_PHASE] = PH_REPLAY
        st[S_IRQ_CHECK] = cyc + VECTOR_BUBBLES + 1
        ctr[C_TRAP] += 1
        ctr[C_ENTRY_STALL] += VECTOR_BUBBLES
        return st[S_IRQ_VECTOR] & 0xFFFFFFFC, cyc + VECTOR_BUBBLES
    if phase == PH_SHADOW:
        # RTL erratum: the shadow of the multiply has executed; the vector follows at once, unless
        # the shadow jumped, whose redirect drops it (interrupts stay off, EPC stays MUL + 8)
        st[S_IRQ_PHASE] = PH_NONE
        st[S_IRQ_CHECK] = earliest_entry(st)
        if pc == st[S_IRQ_SHADOW_END]:
            ctr[C_IRQ] += 1
            return st[S_IRQ_VECTOR] & 0xFFFFFFFC, cyc
        ctr[C_IRQ_LOST] += 1
        return pc, cyc
    irq_scan(st, cyc)
    t = st[S_IRQ_RISE]
    if t < 0 or cyc < t + ENTRY_DELAY:
        st[S_IRQ_CHECK] = earliest_entry(st)
        return pc, cyc
    r = t + REQUEST_DELAY
    if st[S_MUL_END] == cyc and r <= cyc - 2:
        # the request rose while the multiply ending here ran: the RTL mishandles this
        mul_pc = (pc - 4) & M32
        st[S_IRQMUL_COUNT] += 1
        if st[S_IRQMUL_PC] < 0:
            st[S_IRQMUL_PC] = mul_pc
        if st[S_ERRATA] == ERRATA_RTL:
            if r <= cyc - 3:
                _enter(st, pc + 4)  # EPC = MUL + 8: the shadow will run again after the return
                st[S_IRQ_PHASE] = PH_SHADOW
                st[S_IRQ_SHADOW_END] = (pc + 4) & M32
                st[S_IRQ_CHECK] = cyc + 1
                return pc, cyc
            # r = m + L - 2: EPC = MUL + 4, the vector one cycle early, the multiply runs again
            vector = _enter(st, mul_pc + 4)
            st[S_IRQ_PHASE] = PH_REPLAY
            st[S_IRQ_CHECK] = cyc + VECTOR_BUBBLES
            ctr[C_IRQ] += 1
            ctr[C_ENTRY_STALL] += VECTOR_BUBBLES - 1
            return vector, cyc + VECTOR_BUBBLES - 1
    vector = _enter(st, pc + 4)
    st[S_IRQ_PHASE] = PH_REPLAY
    st[S_IRQ_CHECK] = cyc + VECTOR_BUBBLES + 1
    ctr[C_IRQ] += 1
    ctr[C_ENTRY_STALL] += VECTOR_BUBBLES
    return vector, cyc + VECTOR_BUBBLES


@njit(**UNCOUNTED)
def irq_load(st: np.ndarray, a: int, x: int) -> tuple[int, bool]:
    """Read register ``a`` (word address) as it was in device cycle ``x``; (value, mapped)."""
    if a == IRQ_VECTOR:
        return st[S_IRQ_VECTOR], True
    if a == IRQ_CAUSE:
        return irq_cause(st, x), True
    if a == IRQ_MASK:
        return st[S_IRQ_MASK], True
    if a == IRQ_STATUS:
        return st[S_IRQ_STATUS], True
    if a == IRQ_EPC:
        return st[S_IRQ_EPC], True
    if a == S0CAUSE:
        return s0_cause(st, x), True
    return 0, False


@njit(**UNCOUNTED)
def irq_store(st: np.ndarray, a: int, v: int, s: int) -> int:
    """Write register ``a`` with a store starting in instruction cycle ``s`` (holds from device cycle s)."""
    if a == IRQ_VECTOR:
        st[S_IRQ_VECTOR] = v
        return DEV_WRITTEN
    if a == IRQ_EPC:
        st[S_IRQ_EPC] = v
        return DEV_WRITTEN
    if a == IRQ_MASK or a == IRQ_STATUS:
        irq_scan(st, s)  # the controller sees the old value up to here
        if a == IRQ_MASK:
            st[S_IRQ_MASK] = v & 0xFF
        else:
            st[S_IRQ_STATUS] = v & 0xFF
            if (v & 1) != 0 and st[S_IRQ_IDLE] >= NEVER:
                st[S_IRQ_IDLE] = s + IDLE_DELAY
        irq_input_changed(st, s)
        return DEV_WRITTEN
    if a == IRQ_CAUSE or a == S0CAUSE:
        return DEV_READONLY
    return DEV_UNMAPPED


__all__ = [
    "cause_enabled",
    "earliest_entry",
    "first_cause",
    "first_request",
    "hears_packets",
    "irq_event",
    "irq_external_rise",
    "irq_input_changed",
    "irq_load",
    "irq_pending",
    "irq_scan",
    "irq_store",
    "requests_possible",
    "trap",
]
