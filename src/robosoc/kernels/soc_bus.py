"""The core's device bus: which device answers a load or store outside SRAM, and when.

Devices (one file each, register map on top): :mod:`~robosoc.kernels.dev_timer` (timers),
:mod:`~robosoc.kernels.dev_irq` (interrupt controller), :mod:`~robosoc.kernels.dev_output` (exit
trap, debug port, UART), and on an MPSoC tile the network interface, whose registers the chip
loop performs itself (:mod:`~robosoc.kernels.ni_registers`, :mod:`~robosoc.kernels.chip`).

Timing (platform.md §3): a load starting in instruction cycle c reads the registers as they were
in device cycle c - 1; a store starting in instruction cycle s writes at the end of its first
cycle, so the value holds from device cycle s.  Before a store changes a register that feeds the
interrupt line, the controller is brought up to date with the old value.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from robosoc.kernels.borrowed import UNCOUNTED
from robosoc.kernels.core_layout import (
    DEV_NI,
    DEV_UNMAPPED,
    DEV_WRITTEN,
    S_EXT_FINAL,
    S_IRQ_MASK,
    S_MASK_LOCK,
    S_NI,
)
from robosoc.kernels.dev_irq import (
    CAUSE_PACKET,
    IRQ_CAUSE,
    IRQ_MASK,
    IRQ_STATUS,
    irq_input_changed,
    irq_load,
    irq_scan,
    irq_store,
)
from robosoc.kernels.dev_output import output_load, output_store
from robosoc.kernels.dev_timer import timer_load, timer_store
from robosoc.kernels.ni_registers import NI_BASE, NI_END

TIMER_BLOCK = 0xE1020000  # TIMERCAUSE .. TIMER1_OCR
TIMER_BLOCK_END = 0xE1025000

# load results
LD_OK = 0
LD_UNMAPPED = 1
LD_NI = 2


@njit(**UNCOUNTED)
def mmio_load(st: np.ndarray, addr: int, c: int) -> tuple[int, int]:
    """Read a device register with a load that starts in instruction cycle ``c``.

    Returns (value, LD_OK), (0, LD_UNMAPPED), or (0, LD_NI) for a network-interface register,
    which the chip loop reads itself in global time order, and on an MPSoC tile for an IRQ_CAUSE
    read of a device cycle the chip loop does not yet vouch for (``S_EXT_FINAL``): the core
    stops before it and reads it again once the chip has caught up.
    """
    a = addr & 0xFFFFFFFC
    x = c - 1
    if NI_BASE <= a < NI_END:
        return 0, LD_NI if st[S_NI] != 0 else LD_UNMAPPED
    if a == IRQ_CAUSE and st[S_NI] != 0 and x >= st[S_EXT_FINAL]:
        return 0, LD_NI
    v, ok = timer_load(st, a, x)
    if not ok:
        v, ok = irq_load(st, a, x)
    if not ok:
        v, ok = output_load(st, a)
    return (v, LD_OK) if ok else (0, LD_UNMAPPED)


@njit(**UNCOUNTED)
def mmio_store(st: np.ndarray, out: np.ndarray, addr: int, value: int, s: int) -> int:
    """Write a device register with a store starting in instruction cycle ``s``.  A DEV_* code.

    DEV_NI: a network-interface register, or on an MPSoC tile under ``S_MASK_LOCK`` a store that
    would let the packet line reach the controller (IRQ_MASK bit 1 set, or IRQ_STATUS bit 0 set
    with IRQ_MASK bit 1 set): the core stops before it (see kernels/chip.py).
    """
    a = addr & 0xFFFFFFFC
    v = value & 0xFFFFFFFF
    if NI_BASE <= a < NI_END:
        return DEV_NI if st[S_NI] != 0 else DEV_UNMAPPED
    if st[S_MASK_LOCK] != 0:
        if a == IRQ_MASK and (v & ~st[S_IRQ_MASK] & CAUSE_PACKET) != 0:
            return DEV_NI
        if a == IRQ_STATUS and (v & 1) != 0 and (st[S_IRQ_MASK] & CAUSE_PACKET) != 0:
            return DEV_NI
    if TIMER_BLOCK <= a < TIMER_BLOCK_END:
        irq_scan(st, s)  # every writable timer register can move the timer line
        r = timer_store(st, a, v, s)
        if r == DEV_WRITTEN:
            irq_input_changed(st, s)
        return r
    r = irq_store(st, a, v, s)
    if r == DEV_UNMAPPED:
        r = output_store(st, out, a, value)
    return r


__all__ = ["LD_NI", "LD_OK", "LD_UNMAPPED", "mmio_load", "mmio_store"]
