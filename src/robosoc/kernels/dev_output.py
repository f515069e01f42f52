"""The devices through which a program talks to the host: exit trap, debug port and UART0.

Register map (platform.md §2):

==========  ==========  ======================================================================
0xe0000000  EXIT        store: end the run, the value is the exit code
0xe1030400  UARTCAUSE   read-only 0 (transmission is instantaneous, there is no receiver)
0xe1034000  UART0       store: transmit a byte (copied to the output)
0xe1034010  UART0_DIV   baud divider (kept, no effect)
0xf00000d0  DEBUG       store: print a byte
==========  ==========  ======================================================================

Output bytes go to the tile's buffer ``out``; the run loop stops to drain it when it is nearly full.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from robosoc.kernels.borrowed import UNCOUNTED
from robosoc.kernels.core_layout import (
    DEV_EXIT,
    DEV_READONLY,
    DEV_UNMAPPED,
    DEV_WRITTEN,
    S_EXIT_CODE,
    S_OUT_LEN,
    S_UART_DIV,
)

EXIT_ADDR = 0xE0000000
UARTCAUSE = 0xE1030400
UART0 = 0xE1034000
UART0_DIV = 0xE1034010
DEBUG = 0xF00000D0


@njit(**UNCOUNTED)
def output_load(st: np.ndarray, a: int) -> tuple[int, bool]:
    """Read register ``a`` (word address); (value, mapped)."""
    if a == UART0_DIV:
        return st[S_UART_DIV], True
    if a == UARTCAUSE or a == UART0 or a == DEBUG:
        return 0, True
    return 0, False


@njit(**UNCOUNTED)
def output_store(st: np.ndarray, out: np.ndarray, a: int, value: int) -> int:
    """Write register ``a`` (``value`` as the store put it on the bus).  A DEV_* code."""
    if a == DEBUG or a == UART0:
        n = st[S_OUT_LEN]
        out[n] = value & 0xFF
        st[S_OUT_LEN] = n + 1
        return DEV_WRITTEN
    if a == EXIT_ADDR:
        st[S_EXIT_CODE] = value
        return DEV_EXIT
    if a == UART0_DIV:
        st[S_UART_DIV] = value & 0xFFFFFFFF
        return DEV_WRITTEN
    if a == UARTCAUSE:
        return DEV_READONLY
    return DEV_UNMAPPED


__all__ = ["output_load", "output_store"]
