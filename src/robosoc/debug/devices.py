"""Device registers as GDB reads them: the value a load would see now, with no side effect.

A load starting in instruction cycle c reads the devices as they were in device cycle c - 1
(docs/platform.md §3).  GDB reads with the core's current cycle (the cycle its next instruction
executes in), so ``x/wx 0xe1024000`` shows what a ``lw`` at the pc would load.  None of the SoC's
registers changes when read (no read-to-clear register exists), so the same functions the core
uses serve here; they are pure and touch no counter.

On an MPSoC tile the network-interface registers come from the chip's arrays the way the chip
loop computes them (:func:`robosoc.kernels.chip.ni_access`), with one difference: inside a time
quantum the network may not yet have been brought up to the core's cycle, so NI_STATUS bit 0
(send memory busy) can read 1 where the program's own load, which brings the network up to its
cycle first, would read 0.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from robosoc.kernels import chip as kc
from robosoc.kernels import ni_registers as ni
from robosoc.kernels.soc_bus import LD_OK, mmio_load

if TYPE_CHECKING:
    from robosoc.chip.mpsoc import MPSoC

M32 = 0xFFFFFFFF


def soc_register(st_row: np.ndarray, addr: int, cycle: int) -> int | None:
    """The word of the SoC device register at ``addr`` (word aligned) for a load in ``cycle``.

    None for an unmapped address and for the network-interface registers (see :func:`ni_register`).
    """
    value, code = mmio_load(st_row, addr, cycle)
    return int(value) & M32 if code == LD_OK else None


def ni_register(chip: MPSoC, t: int, addr: int, cycle: int) -> int | None:
    """The word of tile ``t``'s network-interface register at ``addr`` for a load in ``cycle``.

    None outside the NI's registers.  Write-only registers (NI_CMD, SLEEP) read 0, as in the chip.
    """
    off = addr - ni.NI_BASE
    cst = chip.cst[t]
    width = chip.config.width
    x = cycle - 1  # registered read: the value of the cycle before the load
    if off == ni.NI_STATUS:
        busy = kc._send_done(chip.noc.tile, t) > x  # the chip loop's own (pure) function, as ni_access uses it
        waiting = cst[kc.K_RX_READY] <= x
        return (ni.STATUS_SEND_BUSY if busy else 0) | (ni.STATUS_PACKET_WAITING if waiting else 0)
    if off == ni.RECV_SIZE:
        return int(cst[kc.K_RX_LEN]) if cst[kc.K_RX_READY] <= x else 0
    if off == ni.NI_TILE:
        return ((t % width) << 4) | (t // width)
    if off == ni.NI_MESH:
        return width | (chip.config.height << 8)
    if off == ni.IO_TILE:
        return ((chip.io % width) << 4) | (chip.io // width)
    columns = {ni.SEND_ADDR: kc.K_SEND_ADDR, ni.SEND_SIZE: kc.K_SEND_SIZE, ni.RECV_ADDR: kc.K_RECV_ADDR,
               ni.TASK_ID: kc.K_TASK}  # fmt: skip
    if off in columns:
        return int(cst[columns[off]]) & M32
    if off in (ni.NI_CMD, ni.SLEEP):
        return 0
    return None
