"""The whole MPSoC in one numba loop: cores, network interfaces, NoC, sleep, per-task accounting.

The network-interface registers of a tile (:mod:`robosoc.kernels.ni_registers`, word accesses
only) are performed here, in global time order: a core stops just before accessing them.

IRQ_CAUSE bit 1 is "a packet waits in the receive memory"; it rises the cycle after the last
flit was written and stays up until RECV has copied the packet.

Time (exact, deterministic): all tiles and the NoC advance in quanta [T, H).  While the NoC is
idle, a packet sent in the quantum cannot be seen by any tile before T + G_LOOK_IDLE (store, DMA
of at least 3 flits, two routers, the flits behind the header: docs/noc.md), so cores run first
and the NoC catches up after them with the new injections at their exact cycles.  While the NoC
carries flits, quanta are G_LOOK_ACTIVE = 6 cycles (the earliest a SEND or RECV started in the
quantum can change the NoC), the NoC runs first, and the deliveries
it makes are scheduled on the receiving cores before they run.  With one core awake and an idle
NoC, the quantum stretches to the next wake-up.  An access to NI registers stops the core just
before it (run_cores returns RUN_NI) and is performed here.  Sleeping cores cost nothing; their
wake-up cycle is computed from their timers and the deliveries.

Divided core clocks (docs/power.md, "Per-tile clock"): a tile whose core runs at the chip's clock
divided by d (``cst[t, K_DIV]``) keeps its core's own cycles in ``st`` (S_CYCLE, its timers, its
interrupt controller, its counters and sleep cycles: the core kernels and the translated code are
unchanged); its core cycle c begins in chip cycle c·d.  The chip loop converts at the boundary:
the core runs to the first core cycle at or after a chip horizon (:func:`core_until`), stops and
sleeps are ordered at c·d (:func:`chip_cycle`), and an event of chip cycle r (a packet's arrival, a
receive memory's state) is seen by the core from its first cycle c with c·d >= r.  With every
divider 1 (the default) each conversion is the identity.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from robosoc.isa.table import MEMORY_CYCLES
from robosoc.kernels import ni_registers as ni
from robosoc.kernels import noc as nk
from robosoc.kernels import stop_queue
from robosoc.kernels.borrowed import UNCOUNTED, borrow, item, row
from robosoc.kernels.core import LW, SW, U1, U2, CoreArrays, fields, run_cores
from robosoc.kernels.core_layout import (
    C_MMIO,
    CTR_SIZE,
    NEVER,
    OPC_SIZE,
    RUN_BREAK,
    RUN_ENTRY,
    RUN_ERROR,
    RUN_EXIT,
    RUN_NI,
    RUN_OUTPUT,
    S_CODE_SIZE,
    S_CYCLE,
    S_EXT_FINAL,
    S_EXT_RISE,
    S_IRQ_CHECK,
    S_IRQ_MASK,
    S_MASK_LOCK,
    S_MEM_BASE,
    S_MEM_SIZE,
    S_OUT_LEN,
    S_PC,
    S_PROF_BASE,
    S_PROF_STRIDE,
    S_RUN,
)
from robosoc.kernels.dev_irq import (
    CAUSE_PACKET,
    ENTRY_DELAY,
    IRQ_MASK,
    IRQ_STATUS,
    cause_enabled,
    earliest_entry,
    first_cause,
    first_request,
    hears_packets,
    irq_external_rise,
    irq_scan,
    requests_possible,
)
from robosoc.kernels.host_ticks import ticks
from robosoc.kernels.jit_dispatch import (
    RUN_TRANSLATE,
    forget_if_changed,
    run_translated,
)

# tile states
K_OFF, K_RUN, K_SLEEP, K_EXITED, K_FAULT, K_IO = 0, 1, 2, 3, 4, 5

# cst columns
K_STATE = 0
K_WAKE = 1  # cycle a sleeping core resumes (NEVER: only a packet can wake it)
K_SEND_ADDR = 2
K_SEND_SIZE = 3
K_RECV_ADDR = 4
K_RX_READY = 5  # cycle from which a received packet waits (NEVER if none)
K_RX_LEN = 6
K_RX_FREE_AT = 7  # cycle the NoC may refill the receive memory after a RECV (NEVER if none)
K_TASK = 8
K_SLEEP_CYCLES = 9
K_DMA_CYCLES = 10
K_SLEEP_FROM = 11
K_ERR = 12  # CE_* code of a network-interface misuse
K_ERR_ADDR = 13
K_ERR_INFO = 14
K_OUT_LEN = 15  # bytes waiting in xout
K_SENT = 16
K_RECEIVED = 17
K_DIV = 18  # the core's clock divider: one core cycle every K_DIV chip (NoC) cycles (1: the chip's clock)
CST_SIZE = 20

# gst: global scalars
G_TIME = 0
G_STATUS = 1  # CHIP_* reason of the last return
G_ERR_TILE = 2
G_IO_TILE = 3
G_LOOK_IDLE = 4
G_LOOK_ACTIVE = 5
G_LOOK_SINGLE = 8  # longest quantum of a lone awake core
G_QUANTA = 6
G_IO_COUNT = 7  # rows used in io_out
G_SUSPEND_H = 9  # > 0: a breakpoint suspended the quantum ending here; the next call continues it
G_SUSPEND_FLAGS = 10  # 1: that quantum is active (NoC first), 2: quiet
G_BREAK_TILE = 11  # the tile that stopped at a breakpoint (CHIP_BREAK)
G_REC_COUNT = 12  # rows used in rec (the timeline recorder; the host drains it)
G_REC_LOST = 13  # events that found rec full
G_NO_LONG = 14  # 1: the next quantum may not be long (a core waits to set IRQ_MASK bit 1)
G_LONG_OFF = 15  # 1: no long quanta at all (a debugger holds a tile: nobody may run far ahead of it)
# the loop's breakdown of its own host time (``robosoc bench fly --breakdown``), kept only while G_PROF
# is 1: host cycle-counter ticks (:mod:`robosoc.kernels.host_ticks`) per part, and counts
G_PROF = 16
G_TK_CALL = 17  # ticks from the loop's entry to its return
G_TK_INTERP = 18  # in the interpreter (run_cores, the tiles without translated code)
G_TK_JIT = 19  # in the dispatch loop (translated code and its interpreter steps)
G_TK_NI = 20  # network-interface accesses (ni_access)
G_TK_WAKE = 21  # waking sleeping cores (_wake_if_due)
G_TK_NOC = 22  # the NoC: running it, taking its deliveries
G_N_INTERP = 23  # run_cores calls
G_N_JIT = 24  # dispatch-loop calls
G_N_NI = 25  # network-interface accesses
G_N_WAKE = 26  # cores woken
G_N_SLEEP = 27  # SLEEP stores
GST_SIZE = 28

# timeline events (rec rows: kind, tile, cycle, then five values; cosim/chip_timeline.py reads them)
R_TASK = 1  # a TASK_ID store took effect in `cycle`: new id, old id, pc, sleep cycles so far
R_SLEEP = 2  # a SLEEP store: the core sleeps from `cycle`; 0, 0, pc, sleep cycles so far
R_SEND = 3  # a packet starts leaving in `cycle`: flit 0 (destination), length, flits 2, 3 and 5
R_DELIVER = 4  # a packet became visible to the core in `cycle`: first-flit cycle, length, flits 2, 3 and 5
REC_COLS = 8

# return reasons
CHIP_UNTIL = 0
CHIP_DONE = 1  # every core has exited
CHIP_OUTPUT = 2  # some tile's output needs draining
CHIP_ERROR = 3
CHIP_IO_FULL = 4  # io_out needs draining
CHIP_STUCK = 5  # nothing can happen any more, but not every core has exited
CHIP_BREAK = 6  # a core stopped before an instruction a debugger marked (tile in G_BREAK_TILE)
CHIP_TRANSLATE = 7  # a core's pc turned hot: translate a region there and call again (tile in G_BREAK_TILE)

# the translated-code parameters of run_chip (``jit_params``)
J_THRESHOLD = 0  # arrivals at a word before the host is asked to translate there
J_STRETCH = 1  # cycles the interpreter runs between arrivals (auto)
J_SIZE = 2
#: a translating tile whose stretch of the quantum is shorter than this runs on the interpreter with
#: the others (a call of the dispatch loop costs more than a few interpreted instructions: with two
#: cores awake a quantum is G_LOOK_IDLE cycles), unless it stopped before a translated block
JIT_MIN_SLICE = 64

# network-interface misuse (K_ERR)
CE_NONE = 0
CE_WIDTH = 1
CE_UNKNOWN_REG = 2
CE_SEND_BUSY = 3
CE_NO_PACKET = 4
CE_BAD_PACKET = 5  # K_ERR_INFO holds the NoC STATUS_* code
CE_DMA_RANGE = 6
CE_TASK_RANGE = 7
CE_BAD_COMMAND = 8
CE_READONLY = 9

NTASKS = ni.NTASKS
# accounting vector: per-operation counters, core counters, cycles, sleep and DMA cycles
A_CTR = OPC_SIZE
A_CYCLES = OPC_SIZE + CTR_SIZE
A_SLEEP = A_CYCLES + 1
A_DMA = A_CYCLES + 2
ACC_SIZE = A_CYCLES + 4

IO_COLS = 3 + nk.MEM_FLITS  # io_out rows: cycle, length, first-flit cycle, flits
SINGLE_QUANTUM = 1 << 20  # default G_LOOK_SINGLE (bounds the output of one quantum)
SLEEP_ADDRESS = ni.NI_BASE + ni.SLEEP  # the NI register a core stores to to sleep


@njit("int64(int64, int64)", cache=True, inline="always")
def chip_cycle(c, d):
    """The chip cycle in which core cycle ``c`` of a core at divider ``d`` begins (NEVER stays NEVER)."""
    return c if d == 1 or c >= NEVER else c * d


@njit("int64(int64, int64)", cache=True, inline="always")
def core_until(h, d):
    """The first core cycle (divider ``d``) beginning at or after chip cycle ``h``: a core run to it
    executes exactly the instructions that begin before ``h`` (NEVER stays NEVER)."""
    return h if d == 1 or h >= NEVER else (h + d - 1) // d


class ChipBook(NamedTuple):
    """The chip loop's own arrays (built by ``MPSoC``).

    ``cst`` per-tile chip state (K_* columns), ``acc`` per-task accounting vectors (A_*), ``snap``
    the counters at the last attribution, ``gst`` global scalars (G_*), ``xout`` per-tile output
    kept for the host, ``io_out`` packets that reached the I/O tile (IO_COLS per row), ``rec``
    timeline events (R_* rows of REC_COLS; no rows: not recording), ``work`` WORK_ROWS rows of one
    entry per tile, the chip loop's scratch lists (held by the host, so the loop borrows them:
    :mod:`robosoc.kernels.borrowed`).
    """

    cst: np.ndarray
    acc: np.ndarray
    snap: np.ndarray
    gst: np.ndarray
    xout: np.ndarray
    io_out: np.ndarray
    rec: np.ndarray
    work: np.ndarray


WORK_ROWS = 8


# Explicit signatures on the small helpers called with constants: numba would otherwise compile
# one specialisation per literal argument (18 of _fault, 7 of record), a tenth of a cold start.
@njit("void(int64[:, ::1], int64[::1], int64, int64, int64, int64, int64, int64, int64, int64)", cache=True)
def record(rec, gst, kind, t, cycle, a, b, c, d, e):
    """Append one timeline event to ``rec`` (counted as lost when it is full; nothing without rows)."""
    if rec.shape[0] == 0:
        return
    n = gst[G_REC_COUNT]
    if n >= rec.shape[0]:
        gst[G_REC_LOST] += 1
        return
    rec[n, 0] = kind
    rec[n, 1] = t
    rec[n, 2] = cycle
    rec[n, 3] = a
    rec[n, 4] = b
    rec[n, 5] = c
    rec[n, 6] = d
    rec[n, 7] = e
    gst[G_REC_COUNT] = n + 1


@njit(cache=True)
def account(t, core, book, now):
    """Attribute everything since the last snapshot to the current task of tile t."""
    ctr, opc = core.ctr, core.opc
    cst, acc, snap = book.cst, book.acc, book.snap
    task = cst[t, K_TASK]
    for k in range(OPC_SIZE):
        v = opc[t, k]
        acc[t, task, k] += v - snap[t, k]
        snap[t, k] = v
    for k in range(CTR_SIZE):
        v = ctr[t, k]
        acc[t, task, A_CTR + k] += v - snap[t, A_CTR + k]
        snap[t, A_CTR + k] = v
    acc[t, task, A_CYCLES] += now - snap[t, A_CYCLES]
    snap[t, A_CYCLES] = now
    acc[t, task, A_SLEEP] += cst[t, K_SLEEP_CYCLES] - snap[t, A_SLEEP]
    snap[t, A_SLEEP] = cst[t, K_SLEEP_CYCLES]
    acc[t, task, A_DMA] += cst[t, K_DMA_CYCLES] - snap[t, A_DMA]
    snap[t, A_DMA] = cst[t, K_DMA_CYCLES]


@njit(cache=True)
def bad_pcs(st: np.ndarray, cst: np.ndarray) -> np.ndarray:
    """The tiles that run or sleep with a pc outside their loaded code's words (the host's check
    before each step: numpy's seven passes over the tiles cost more than a flight's step)."""
    bad = np.zeros(0, dtype=np.int64)
    for t in range(cst.shape[0]):
        state = cst[t, K_STATE]
        if state == K_RUN or state == K_SLEEP:
            off = st[t, S_PC] - st[t, S_MEM_BASE]
            if off % 4 != 0 or off < 0 or off >= st[t, S_CODE_SIZE]:
                bad = np.append(bad, t)
    return bad


@njit(cache=True)
def account_all(core, book):
    """:func:`account` for every tile with a core (not off, not the I/O tile), up to its present cycle.

    One call from the host for the whole chip: a call per tile costs more in argument unboxing
    (about 0.15 ms for the arrays of the chip) than the accounting itself.
    """
    cst, st = book.cst, core.st
    for t in range(cst.shape[0]):
        if cst[t, K_STATE] != K_OFF and cst[t, K_STATE] != K_IO:
            account(t, core, book, st[t, S_CYCLE])


@njit(**UNCOUNTED)
def wake_time(st_t: np.ndarray, x: int) -> int:
    """The cycle a core asleep since instruction cycle ``x`` resumes (NEVER if nothing is due).

    With interrupts enabled it resumes at the boundary where its interrupt is entered: t + 5 for
    a request the controller raises in device cycle t (platform.md §3).  Otherwise (IRQ_STATUS
    bit 0 clear, or inside a handler) it resumes like RISC-V's WFI when an enabled cause rises,
    in the clock of that device cycle y, i.e. instruction cycle y + 1, without an entry.  Never
    before ``x``.  The value may be a point at which to look again (see :func:`_wake_if_due`).
    """
    if requests_possible(st_t):
        t = first_request(st_t, NEVER)
        return NEVER if t >= NEVER else max(x, t + ENTRY_DELAY)
    y = first_cause(st_t, x - 1)
    return NEVER if y >= NEVER else max(x, y + 1)


@njit(**UNCOUNTED)
def _send_done(tile, t):
    """First cycle at which tile t's send memory is free again (NEVER while it cannot be known).

    An injection armed in this quantum has not been simulated yet (the NoC catches up at the
    end of an idle quantum); with the router's local buffer empty it takes one cycle per flit.
    """
    state = tile[t, nk.T_SEND_STATE]
    if state == nk.SEND_IDLE:
        return tile[t, nk.T_SEND_DONE]
    if state == nk.SEND_PENDING and tile[t, nk.T_NI_CREDIT] >= tile[t, nk.T_SEND_LEN]:
        return tile[t, nk.T_SEND_START] + tile[t, nk.T_SEND_LEN]
    return NEVER


@njit("void(int64[:, ::1], int64, int64, int64, int64)", cache=True)
def _fault(cst, t, code, addr, info):
    cst[t, K_STATE] = K_FAULT
    cst[t, K_ERR] = code
    cst[t, K_ERR_ADDR] = addr
    cst[t, K_ERR_INFO] = info


@njit(**UNCOUNTED)
def ni_access(t, core, book, noc):
    """Perform the NI-register load or store tile t stopped before; returns False on a fault."""
    st, ctr, opc, regs, m16, dec = core.st, core.ctr, core.opc, core.regs, core.m16, core.dec
    cst, gst = book.cst, book.gst
    cfg, glob, tile, mem = noc.cfg, noc.glob, noc.tile, noc.mem
    base = st[t, S_MEM_BASE]
    size = st[t, S_MEM_SIZE]
    pc = st[t, S_PC]
    s = st[t, S_CYCLE]
    i = np.uint64(pc - base) >> U2
    op, rd, rs1, rs2, imm = fields(row(dec, t), i)
    addr = (regs[t, rs1] + imm) & 0xFFFFFFFF
    off = addr - ni.NI_BASE
    if op != LW and op != SW:
        _fault(cst, t, CE_WIDTH, addr, 0)
        return False
    opc[t, (op << U1) | (i & U1)] += 1
    ctr[t, C_MMIO] += 1
    if st[t, S_PROF_STRIDE] != 0:  # the profile's flow (kernels/core.py): word i runs here, the core goes on after it
        pb = np.uint64(st[t, S_PROF_BASE]) + i
        opc[t, pb] += 1
        opc[t, pb + U1] -= 1
    width = cfg[nk.C_WIDTH]
    d = cst[t, K_DIV]
    if op == LW:
        x = chip_cycle(s - 1, d)  # registered read: the value of the (core) cycle before the load
        v = 0
        if off == ni.NI_STATUS:
            busy = _send_done(tile, t) > x
            v = (ni.STATUS_SEND_BUSY if busy else 0) | (ni.STATUS_PACKET_WAITING if cst[t, K_RX_READY] <= x else 0)
        elif off == ni.SEND_ADDR:
            v = cst[t, K_SEND_ADDR]
        elif off == ni.SEND_SIZE:
            v = cst[t, K_SEND_SIZE]
        elif off == ni.NI_CMD:
            v = 0
        elif off == ni.RECV_ADDR:
            v = cst[t, K_RECV_ADDR]
        elif off == ni.RECV_SIZE:
            v = cst[t, K_RX_LEN] if cst[t, K_RX_READY] <= x else 0
        elif off == ni.NI_TILE:
            v = ((t % width) << 4) | (t // width)
        elif off == ni.NI_MESH:
            v = width | (cfg[nk.C_HEIGHT] << 8)
        elif off == ni.TASK_ID:
            v = cst[t, K_TASK]
        elif off == ni.IO_TILE:
            io = gst[G_IO_TILE]
            v = ((io % width) << 4) | (io // width)
        elif off == ni.SLEEP:
            v = 0
        else:
            _fault(cst, t, CE_UNKNOWN_REG, addr, 0)
            return False
        regs[t, rd] = v
        st[t, S_CYCLE] = s + MEMORY_CYCLES
        st[t, S_PC] = pc + 4
        return True
    v = np.int64(regs[t, rs2]) & 0xFFFFFFFF
    end = s + MEMORY_CYCLES
    if off == ni.SEND_ADDR:
        cst[t, K_SEND_ADDR] = v
    elif off == ni.SEND_SIZE:
        cst[t, K_SEND_SIZE] = v
    elif off == ni.RECV_ADDR:
        cst[t, K_RECV_ADDR] = v
    elif off == ni.TASK_ID:
        if v >= NTASKS:
            _fault(cst, t, CE_TASK_RANGE, addr, v)
            return False
        st[t, S_CYCLE] = end
        st[t, S_PC] = pc + 4
        account(t, core, book, end)
        slept = chip_cycle(cst[t, K_SLEEP_CYCLES], d)
        record(book.rec, gst, R_TASK, t, chip_cycle(end, d), v, cst[t, K_TASK], pc, slept, 0)
        cst[t, K_TASK] = v
        st[t, S_PROF_BASE] = OPC_SIZE + v * st[t, S_PROF_STRIDE]  # the task's profile bank (kernels/core.py)
        return True
    elif off == ni.SLEEP:
        st[t, S_CYCLE] = end
        st[t, S_PC] = pc + 4
        cst[t, K_STATE] = K_SLEEP
        cst[t, K_SLEEP_FROM] = end
        cst[t, K_WAKE] = chip_cycle(wake_time(row(st, t), end), d)
        record(book.rec, gst, R_SLEEP, t, chip_cycle(end, d), 0, 0, pc, chip_cycle(cst[t, K_SLEEP_CYCLES], d), 0)
        return True
    elif off == ni.NI_CMD:
        if v == ni.CMD_SEND:
            n = cst[t, K_SEND_SIZE]
            a = cst[t, K_SEND_ADDR] - base
            if n < nk.MIN_PACKET_FLITS:
                _fault(cst, t, CE_BAD_PACKET, cst[t, K_SEND_ADDR], nk.STATUS_SHORT_PACKET)
                return False
            if n > nk.MEM_FLITS or a < 0 or a + 2 * n > size or (a & 1):
                _fault(cst, t, CE_DMA_RANGE, cst[t, K_SEND_ADDR], n)
                return False
            if _send_done(tile, t) > chip_cycle(s, d):
                _fault(cst, t, CE_SEND_BUSY, addr, 0)
                return False
            h = a >> 1
            for k in range(n):
                mem[t, nk.SEND, k] = m16[t, h + k]
            start = end + n  # the DMA copies a flit per core cycle
            code = nk.noc_send(cfg, glob, tile, mem, t, n, chip_cycle(start, d))
            if code != nk.STATUS_OK:
                _fault(cst, t, CE_BAD_PACKET, cst[t, K_SEND_ADDR], code)
                return False
            cst[t, K_DMA_CYCLES] += n
            cst[t, K_SENT] += 1
            st[t, S_CYCLE] = start
            record(book.rec, gst, R_SEND, t, chip_cycle(start, d), mem[t, nk.SEND, 0], n, mem[t, nk.SEND, 2],
                   mem[t, nk.SEND, 3], mem[t, nk.SEND, 5] if n > 5 else 0)  # fmt: skip
        elif v == ni.CMD_RECV:
            if cst[t, K_RX_READY] > chip_cycle(s - 1, d):
                _fault(cst, t, CE_NO_PACKET, addr, 0)
                return False
            n = cst[t, K_RX_LEN]
            a = cst[t, K_RECV_ADDR] - base
            if a < 0 or a + 2 * n > size or (a & 1):
                _fault(cst, t, CE_DMA_RANGE, cst[t, K_RECV_ADDR], n)
                return False
            h = a >> 1
            for k in range(n):
                m16[t, h + k] = mem[t, nk.RECV, k]
            # the copied words are data now: forget any predecoded instructions there
            for k in range(a >> 2, min((a + 2 * n + 3) >> 2, st[t, S_CODE_SIZE] >> 2)):
                dec[t, 2 * k] = 0
            cst[t, K_DMA_CYCLES] += n
            cst[t, K_RECEIVED] += 1
            cst[t, K_RX_READY] = NEVER
            cst[t, K_RX_LEN] = 0
            cst[t, K_RX_FREE_AT] = chip_cycle(end + n, d)
            st[t, S_EXT_RISE] = NEVER
            st[t, S_CYCLE] = end + n
        else:
            _fault(cst, t, CE_BAD_COMMAND, addr, v)
            return False
        st[t, S_PC] = pc + 4
        return True
    elif off in ni.READ_ONLY:
        _fault(cst, t, CE_READONLY, addr, 0)
        return False
    else:
        _fault(cst, t, CE_UNKNOWN_REG, addr, 0)
        return False
    st[t, S_CYCLE] = end
    st[t, S_PC] = pc + 4
    return True


@njit(**UNCOUNTED)
def _stop_address(t, core):
    """The address of the load or store tile t stopped before (RUN_NI)."""
    st, regs, dec = core.st, core.regs, core.dec
    i = np.uint64(st[t, S_PC] - st[t, S_MEM_BASE]) >> U2
    _, _, rs1, _, imm = fields(row(dec, t), i)
    return (regs[t, rs1] + imm) & 0xFFFFFFFC


@njit(**UNCOUNTED)
def _wake(t, st, cst, w):
    """A sleeping core resumes in cycle w."""
    cst[t, K_STATE] = K_RUN
    cst[t, K_SLEEP_CYCLES] += w - cst[t, K_SLEEP_FROM]
    st[t, S_CYCLE] = w
    if st[t, S_IRQ_CHECK] > w:
        st[t, S_IRQ_CHECK] = w


@njit(**UNCOUNTED)
def _wake_if_due(t, st, cst, H):
    """Wake sleeping core t if its interrupt is entered before cycle H, else refresh its wake-up.

    Called while the chip works on the quantum ending at H, when every input of the core's
    interrupt controller before H is known (deliveries of the quantum are scheduled, and no
    packet sent in it can arrive before H), so the controller may look up to H for good.
    """
    d = cst[t, K_DIV]
    h = core_until(H, d)  # in the core's cycles
    start = cst[t, K_SLEEP_FROM]
    st_t = row(st, t)
    if requests_possible(st_t):
        irq_scan(st_t, h)
        w = max(earliest_entry(st_t), start)
        if w < h:
            _wake(t, st, cst, w)
            return
    else:
        w = cst[t, K_WAKE]
        if w < NEVER:
            w //= d  # K_WAKE is a chip cycle, a multiple of d
        if w < h and cause_enabled(st_t, w - 1):
            _wake(t, st, cst, w)
            return
        start = max(start, w)  # a point the search reached without finding the cause
    cst[t, K_WAKE] = chip_cycle(wake_time(st_t, start), d)


@njit(cache=True)
def _keep_output(t, st, cst, out, xout):
    """Move a core's output bytes into its large host buffer (drained by the host between calls)."""
    used = cst[t, K_OUT_LEN]
    m = min(st[t, S_OUT_LEN], xout.shape[1] - used)
    for b in range(m):
        xout[t, used + b] = out[t, b]
    cst[t, K_OUT_LEN] = used + m
    st[t, S_OUT_LEN] = 0


@njit(cache=True)
def _noc_advance(noc, cst, to):
    """Run the NoC up to cycle ``to``, freeing receive memories at the cycles RECV made them free."""
    cfg, glob, buf, port, tile, mem, ev, queue = noc
    n = cfg[nk.C_NTILES]
    while glob[nk.G_CYCLE] < to:
        nxt = to
        for t in range(n):
            f = cst[t, K_RX_FREE_AT]
            if f < nxt:
                nxt = f
        if nxt > glob[nk.G_CYCLE]:
            nk.noc_run(cfg, glob, buf, port, tile, mem, ev, queue, nxt, 1 << 40)
            if glob[nk.G_STATUS] != nk.STATUS_OK or glob[nk.G_CYCLE] < nxt:
                return
        for t in range(n):
            if cst[t, K_RX_FREE_AT] <= glob[nk.G_CYCLE]:
                nk.noc_rx_free(tile, t)
                cst[t, K_RX_FREE_AT] = NEVER


@njit(cache=True)
def _noc_next(noc, cst):
    """First cycle at which the NoC can change by itself (BIG if it is idle with nothing pending)."""
    cfg = noc.cfg
    best = nk.noc_next_activity(cfg, noc.glob, noc.tile, noc.queue)
    for t in range(cfg[nk.C_NTILES]):
        if cst[t, K_RX_FREE_AT] < best:
            best = cst[t, K_RX_FREE_AT]
    return best


@njit(cache=True)
def _take_deliveries(st, book, noc):
    """Move NoC delivery events to the receiving cores (interrupt line) or to io_out."""
    cst, gst, io_out = book.cst, book.gst, book.io_out
    glob, ev = noc.glob, noc.ev
    io = gst[G_IO_TILE]
    for r in range(glob[nk.G_NEV]):
        d = ev[r, nk.EV_TILE]
        rise = ev[r, nk.EV_CYCLE] + 1
        if d == io:
            line = gst[G_IO_COUNT]
            io_out[line, 0] = ev[r, nk.EV_CYCLE]
            io_out[line, 1] = ev[r, nk.EV_LEN]
            io_out[line, 2] = ev[r, nk.EV_FIRST]
            for k in range(nk.MEM_FLITS):
                io_out[line, 3 + k] = ev[r, nk.EV_FLITS + k]
            gst[G_IO_COUNT] = line + 1
            continue
        cst[d, K_RX_READY] = rise
        cst[d, K_RX_LEN] = ev[r, nk.EV_LEN]
        record(book.rec, gst, R_DELIVER, d, rise, ev[r, nk.EV_FIRST], ev[r, nk.EV_LEN], ev[r, nk.EV_FLITS + 2],
               ev[r, nk.EV_FLITS + 3], ev[r, nk.EV_FLITS + 5])  # fmt: skip
        div = cst[d, K_DIV]
        line = core_until(rise, div)  # the core's first cycle that sees the line up
        if (st[d, S_IRQ_MASK] & CAUSE_PACKET) != 0:
            # (a core that runs ahead of the rise in a long quantum with the bit set does not hear
            # packets, hears_packets: its controller is done, disabled or already holds its request, so
            # scanning from the rise finds no new request before the store that enables it again, which
            # a long quantum stops)
            irq_external_rise(row(st, d), line)
        else:
            # the line feeds the controller only through IRQ_MASK bit 1: with it clear only IRQ_CAUSE
            # reads see it (and those wait for S_EXT_FINAL), so a core that ran ahead of the rise in a
            # long quantum is told without rewinding its controller into its past
            st[d, S_EXT_RISE] = line
        if cst[d, K_STATE] == K_SLEEP:
            cst[d, K_WAKE] = chip_cycle(wake_time(row(st, d), cst[d, K_SLEEP_FROM]), div)
    glob[nk.G_NEV] = 0


@njit(cache=True, inline="always")
def _run_awake(core, tiles, until, jit_tables, jit_on, jit_params, one, rest, gst, prof, cst):
    """Run ``tiles`` to chip cycle ``until``: each translating tile alone in the dispatch loop, each
    tile on a divided clock alone to its own cycle (:func:`core_until`), the other interpreted ones
    together (through ``run_cores``, the interpreter the dispatch loop calls too: numba compiles
    one, and one variant of the chip loop whatever the engine).  With ``prof`` the host
    ticks of each go to gst (G_TK_JIT, G_TK_INTERP)."""
    k = 0
    st = core.st
    for i in range(tiles.shape[0]):
        t = tiles[i]
        d = cst[t, K_DIV]
        mine = core_until(until, d)
        if jit_on[t] != 0 and (st[t, S_RUN] == RUN_ENTRY or mine - st[t, S_CYCLE] >= JIT_MIN_SLICE):
            one[0] = t
            k0 = ticks() if prof else 0
            jt = item(jit_tables, t)
            run_translated(core, one, mine, jt, jit_params[J_THRESHOLD], jit_params[J_STRETCH])
            if prof:
                gst[G_TK_JIT] += ticks() - k0
                gst[G_N_JIT] += 1
        elif d != 1:
            one[0] = t
            k0 = ticks() if prof else 0
            run_cores(core, one, mine)
            if prof:
                gst[G_TK_INTERP] += ticks() - k0
                gst[G_N_INTERP] += 1
        else:
            rest[k] = t
            k += 1
    if k > 0:
        k0 = ticks() if prof else 0
        run_cores(core, rest[:k], until)
        if prof:
            gst[G_TK_INTERP] += ticks() - k0
            gst[G_N_INTERP] += 1


@njit(cache=True, inline="always")
def _check_translated(core, t, jit_tables, jit_on) -> None:
    """Forget tile ``t``'s translations if a word they were made from changed (a DMA into code)."""
    if jit_on[t] != 0:
        forget_if_changed(item(jit_tables, t), row(core.m32, t), row(core.dec, t))


@njit(cache=True, nogil=True)
def run_chip(core: CoreArrays, noc: nk.NocState, book: ChipBook, until: int, jit_on, jit_tables, jit_params) -> int:
    """Advance the whole chip to cycle ``until`` or an event that needs the host (CHIP_* in gst).

    Tiles with ``jit_on[t]`` run translated code from ``jit_tables[t]``
    (:class:`robosoc.kernels.jit_dispatch.JitArrays`); when one turns hot at a word without a
    translation the chip stops with CHIP_TRANSLATE, the host translates a region there and calls
    again, and the quantum goes on exactly where it stopped (as after a breakpoint).
    """
    # every array borrowed: the host holds them for the call, and the references numba would count
    # at each call, unpacking and view below cost as much as a sleeping chip's instructions
    core = CoreArrays(borrow(core.st), borrow(core.ctr), borrow(core.opc), borrow(core.regs), borrow(core.m8),
                      borrow(core.m16), borrow(core.m32), borrow(core.dec), borrow(core.out))  # fmt: skip
    noc = nk.NocState(borrow(noc.cfg), borrow(noc.glob), borrow(noc.buf), borrow(noc.port), borrow(noc.tile),
                      borrow(noc.mem), borrow(noc.ev), borrow(noc.queue))  # fmt: skip
    book = ChipBook(borrow(book.cst), borrow(book.acc), borrow(book.snap), borrow(book.gst), borrow(book.xout),
                    borrow(book.io_out), borrow(book.rec), borrow(book.work))  # fmt: skip
    jit_on = borrow(jit_on)
    jit_params = borrow(jit_params)
    st, out = core.st, core.out
    glob = noc.glob
    cst, gst, xout, io_out = book.cst, book.gst, book.xout, book.io_out
    prof = gst[G_PROF] != 0
    entered = ticks() if prof else 0
    n = cst.shape[0]
    look_idle = gst[G_LOOK_IDLE]
    look_active = gst[G_LOOK_ACTIVE]
    run = row(book.work, 0)  # the awake cores, in tile order (the order of equal-cycle stops)
    runx = row(book.work, 1)  # those of them that run (not those waiting to report an error)
    queue = row(book.work, 2)  # the stopped ones in handling order (kernels/stop_queue.py: heap, run, state)
    queue_run = row(book.work, 6)
    queue_state = row(book.work, 7)[: stop_queue.Q_STATE]
    qcyc = row(book.work, 3)
    one = row(book.work, 4)[:1]  # a translating tile (run alone)
    rest = row(book.work, 5)  # the interpreted tiles of a run
    look_single = gst[G_LOOK_SINGLE]
    xcap = xout.shape[1]
    T = gst[G_TIME]
    status = CHIP_UNTIL
    quiet = False  # known to have nothing in flight or pending (recomputed on every call)
    while True:
        if gst[G_SUSPEND_H] > 0:
            # continue the quantum a breakpoint suspended: every core is where it stopped
            H = gst[G_SUSPEND_H]
            active = (gst[G_SUSPEND_FLAGS] & 1) != 0
            quiet = (gst[G_SUSPEND_FLAGS] & 2) != 0
            long_q = (gst[G_SUSPEND_FLAGS] & 4) != 0
            gst[G_SUSPEND_H] = 0
            k = 0
            for t in range(n):
                if cst[t, K_STATE] == K_RUN:
                    run[k] = t
                    k += 1
            lo = hi = 0  # run[lo:hi] run next: nobody, every core is where it stopped
            bulk = False
        else:
            if io_out.shape[0] - gst[G_IO_COUNT] < n:
                status = CHIP_IO_FULL
                break
            nrun = 0
            nsleep = 0
            wake = NEVER  # the earliest wake-up of a sleeping core
            wake_later = NEVER  # the earliest one after T
            # a long quantum needs every core that runs in it deaf to the packet line (IRQ_MASK bit 1 clear)
            long_ok = look_single > look_idle and gst[G_NO_LONG] == 0 and gst[G_LONG_OFF] == 0
            for t in range(n):
                state = cst[t, K_STATE]
                if state == K_RUN:
                    nrun += 1
                    if hears_packets(row(st, t)):
                        long_ok = False
                elif state == K_SLEEP:
                    nsleep += 1
                    w = cst[t, K_WAKE]
                    wake = min(wake, w)
                    if w > T:
                        wake_later = min(wake_later, w)
                    elif hears_packets(row(st, t)):
                        long_ok = False
            # the NoC's next activity; a quiet NoC stays quiet until a core sends or receives
            nxt = NEVER if quiet else _noc_next(noc, cst)
            quiet = nxt >= NEVER
            if nrun == 0 and nsleep == 0:
                status = CHIP_DONE
                break
            if nrun == 0 and wake >= NEVER and nxt >= NEVER:
                status = CHIP_STUCK
                break
            if T >= until:  # noqa: SIM300
                status = CHIP_UNTIL
                break
            # --- the quantum -------------------------------------------------------------------
            active = nxt <= T
            long_q = False
            if active:
                H = T + look_active
            elif nrun >= 2:
                if long_ok:
                    H = min(nxt, T + look_single)
                    long_q = True
                else:
                    H = T + look_idle
                    if nxt < H:
                        H = nxt
            elif nrun == 1:
                H = min(nxt, T + look_single)
            else:
                H = nxt  # nobody runs: jump to the next NoC activity or wake-up
            if wake < H:
                if wake > T:
                    H = wake  # the sleeper starts with the next quantum
                else:
                    waking = 0
                    for t in range(n):
                        if cst[t, K_STATE] == K_SLEEP and cst[t, K_WAKE] <= T:
                            waking += 1
                    if nrun + waking >= 2:
                        if long_ok:
                            H = min(H, T + look_single)
                            long_q = True
                        else:
                            H = min(H, T + look_idle)
            if wake_later < H:
                # a core due to wake later starts with a later quantum: woken inside this one it could
                # run ahead of a packet another core sends it before its wake-up
                H = wake_later
            if until < H:
                H = until
            gst[G_QUANTA] += 1
            gst[G_NO_LONG] = 0
            if active:
                k0 = ticks() if prof else 0
                _noc_advance(noc, cst, H)
                if glob[nk.G_STATUS] != nk.STATUS_OK:
                    status = CHIP_ERROR
                    gst[G_ERR_TILE] = -1
                    break
                _take_deliveries(st, book, noc)
                if prof:
                    gst[G_TK_NOC] += ticks() - k0
            # wake sleeping cores due in this quantum
            k0 = ticks() if prof else 0
            for t in range(n):
                if cst[t, K_STATE] == K_SLEEP and cst[t, K_WAKE] < H:
                    _wake_if_due(t, st, cst, H)
                    if prof and cst[t, K_STATE] == K_RUN:
                        gst[G_N_WAKE] += 1
            if prof:
                gst[G_TK_WAKE] += ticks() - k0
            # the awake cores run to H (below); NI accesses are performed here, then the core goes on.
            # How far each may read the packet line: in a long quantum no packet can arrive before
            # T + look_idle (the network is idle at T and every send cuts H to s + look_idle), in a
            # short one none before H that is not already delivered.
            final = T + look_idle if long_q else H
            k = 0
            kx = 0
            for t in range(n):
                if cst[t, K_STATE] == K_RUN:
                    run[k] = t
                    k += 1
                    st[t, S_EXT_FINAL] = core_until(final, cst[t, K_DIV])
                    st[t, S_MASK_LOCK] = 1 if long_q else 0
                    if st[t, S_RUN] != RUN_ERROR:  # a core that failed ahead of H waits to report it
                        runx[kx] = t
                        kx += 1
            lo, hi = np.int64(0), kx  # (not the literal 0: numba would compile push for it too)
            bulk = True  # runx[lo:hi] first
        # Stopped cores are handled in global cycle order, so that an NI access sees the network
        # exactly as it is in its cycle: in an idle quantum the NoC is brought up to the access
        # first, with every packet sent before it by any core (a send cannot reach another tile
        # within the quantum, but it can hold up the sender's own injection, which NI_STATUS shows).
        failed = -1
        suspended = False
        # the stopped cores waiting in the queue (kernels/stop_queue.py), as indices into run
        stop_queue.clear(queue_state)
        fill = True  # the queue starts with every awake core, once they have run to their first stop
        while True:
            if hi > lo:
                # the awake cores to H, then each stopped one on
                _run_awake(core, runx[lo:hi] if bulk else run[lo:hi], H, jit_tables, jit_on, jit_params, one, rest,
                           gst, prof, cst)  # fmt: skip
                if not fill:  # the one core handled last, at its next stop
                    stop_queue.push(queue, queue_run, qcyc, queue_state, lo,
                                    chip_cycle(st[run[lo], S_CYCLE], cst[run[lo], K_DIV]))  # fmt: skip
                hi = lo
                bulk = False
            if fill:
                for r in range(k):
                    stop_queue.push(queue, queue_run, qcyc, queue_state, r,
                                    chip_cycle(st[run[r], S_CYCLE], cst[run[r], K_DIV]))  # fmt: skip
                fill = False
            t = np.int64(-1)  # not the literal -1: numba would compile ni_access and its callees for it too
            rt = 0  # t is run[rt]
            while stop_queue.size(queue_state) > 0:
                r = stop_queue.pop(queue, queue_run, qcyc, queue_state)
                u = run[r]
                # a stop at or after H waits for a later quantum (a long quantum cut short leaves cores
                # ahead of H; H only shrinks, so it stays out); only an exit is taken at once (the core
                # must not run again)
                ahead = chip_cycle(st[u, S_CYCLE], cst[u, K_DIV]) >= H
                if cst[u, K_STATE] != K_RUN or (ahead and st[u, S_RUN] != RUN_EXIT):
                    continue
                t = u
                rt = r
                break
            if t < 0:
                break
            why = st[t, S_RUN]
            if why == RUN_NI:
                s0 = chip_cycle(st[t, S_CYCLE], cst[t, K_DIV])
                sent = cst[t, K_SENT]
                received = cst[t, K_RECEIVED]
                if not active and not quiet:
                    k0 = ticks() if prof else 0
                    _noc_advance(noc, cst, s0)
                    if glob[nk.G_STATUS] != nk.STATUS_OK:
                        break
                    if glob[nk.G_NEV] != 0:
                        _take_deliveries(st, book, noc)
                    if prof:
                        gst[G_TK_NOC] += ticks() - k0
                a = _stop_address(t, core)
                if (
                    a == IRQ_MASK
                    or a == IRQ_STATUS
                    or (long_q and a == SLEEP_ADDRESS and (st[t, S_IRQ_MASK] & CAUSE_PACKET) != 0)
                ):
                    # the store would let packets that cores already past s0 may still send change
                    # t: setting IRQ_MASK bit 1, or IRQ_STATUS bit 0 with it set (a handler's return),
                    # or a sleep with it set (it wakes on an enabled cause whatever IRQ_STATUS says).
                    # End the quantum before the store; the next one is not long
                    H = s0
                    gst[G_NO_LONG] = 1
                    continue
                if a < ni.NI_BASE or a >= ni.NI_END:
                    # an IRQ_CAUSE read (long quanta, see S_EXT_FINAL): every stop before s0 is done,
                    # so no packet reaches t before s0 + look_idle (and t does not run past H)
                    st[t, S_EXT_FINAL] = core_until(s0 + look_idle, cst[t, K_DIV])
                    lo, hi = rt, rt + 1
                    continue
                k0 = ticks() if prof else 0
                if not ni_access(t, core, book, noc):
                    failed = t
                    break
                if prof:
                    gst[G_TK_NI] += ticks() - k0
                    gst[G_N_NI] += 1
                    if cst[t, K_STATE] == K_SLEEP:
                        gst[G_N_SLEEP] += 1
                if cst[t, K_RECEIVED] != received and cst[t, K_RECV_ADDR] - st[t, S_MEM_BASE] < st[t, S_CODE_SIZE]:
                    _check_translated(core, t, jit_tables, jit_on)  # the packet was copied into code
                if cst[t, K_SENT] != sent or cst[t, K_RECEIVED] != received:
                    if quiet:
                        glob[nk.G_CYCLE] = s0  # the network was idle up to here
                    quiet = False
                if cst[t, K_SENT] != sent and s0 + look_idle < H:
                    # a packet left: nobody may run past the first cycle it could be answered
                    # (only shrinks a quantum with a single awake core)
                    H = s0 + look_idle
                if cst[t, K_STATE] == K_SLEEP and cst[t, K_WAKE] < H:
                    # asleep and due again within this quantum: wake it right away
                    k0 = ticks() if prof else 0
                    _wake_if_due(t, st, cst, H)
                    if prof:
                        gst[G_TK_WAKE] += ticks() - k0
                        gst[G_N_WAKE] += 1 if cst[t, K_STATE] == K_RUN else 0
                if cst[t, K_STATE] != K_RUN:
                    continue
            elif why == RUN_OUTPUT:
                _keep_output(t, st, cst, out, xout)
            elif why == RUN_EXIT:
                cst[t, K_STATE] = K_EXITED
                continue
            elif why == RUN_ERROR:
                cst[t, K_STATE] = K_FAULT
                failed = t
                break
            elif why == RUN_BREAK or why == RUN_TRANSLATE:
                # a debugger's breakpoint, or a hot word to translate: hand the chip to the host in
                # the middle of the quantum; the next call continues it exactly (the host clears
                # the stop to go on)
                gst[G_SUSPEND_H] = H
                gst[G_SUSPEND_FLAGS] = (1 if active else 0) | (2 if quiet else 0) | (4 if long_q else 0)
                gst[G_BREAK_TILE] = t
                suspended = True
                break
            lo, hi = rt, rt + 1  # run t on
        for r in range(k):
            if st[run[r], S_OUT_LEN] > 0:
                _keep_output(run[r], st, cst, out, xout)
        if suspended:
            status = CHIP_TRANSLATE if st[gst[G_BREAK_TILE], S_RUN] == RUN_TRANSLATE else CHIP_BREAK
            break
        if glob[nk.G_STATUS] != nk.STATUS_OK:
            status = CHIP_ERROR
            gst[G_ERR_TILE] = -1
            break
        if failed >= 0:
            gst[G_ERR_TILE] = failed
            status = CHIP_ERROR
            break
        alive = False
        last = T
        for t in range(n):
            state = cst[t, K_STATE]
            if state == K_RUN or state == K_SLEEP:
                alive = True
            elif state == K_EXITED and chip_cycle(st[t, S_CYCLE], cst[t, K_DIV]) > last:
                last = chip_cycle(st[t, S_CYCLE], cst[t, K_DIV])
        if not alive:
            H = last  # the run ends when the last core has completed its exit store
        if quiet:
            glob[nk.G_CYCLE] = H  # nothing in or entering the network: time just passes
        elif not active:
            k0 = ticks() if prof else 0
            _noc_advance(noc, cst, H)
            if glob[nk.G_STATUS] != nk.STATUS_OK:
                status = CHIP_ERROR
                gst[G_ERR_TILE] = -1
                break
            if glob[nk.G_NEV] != 0:
                _take_deliveries(st, book, noc)
            if prof:
                gst[G_TK_NOC] += ticks() - k0
        T = H
        full = False
        for t in range(n):
            if cst[t, K_OUT_LEN] > xcap // 2:
                full = True
        if full:
            status = CHIP_OUTPUT
            break
    gst[G_TIME] = T
    gst[G_STATUS] = status
    if prof:
        gst[G_TK_CALL] += ticks() - entered
    return status


__all__ = [
    "ChipBook",
    "account",
    "account_all",
    "bad_pcs",
    "chip_cycle",
    "core_until",
    "ni_access",
    "record",
    "run_chip",
    "wake_time",
]
