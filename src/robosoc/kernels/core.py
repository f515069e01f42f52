"""The HF-RISCV core: predecoded RV32I(+M multiply) interpreter with exact cycle timing.

Instruction words are decoded lazily into ``dec`` (one row per memory word: op, rd, rs1, rs2,
imm) the first time they execute; a store into memory clears the row of the word it touches, so
self-modifying code stays correct.  The row after the last word holds OP_FETCH_FAULT so that
running off the end of memory is caught without a bounds check per instruction.

Registers live in ``regs`` (int32, 33 entries): x0..x31 and a sink at index 32 that the decoder
substitutes for rd = x0, so x0 is never written and no per-instruction reset is needed.

Timing (platform.md §1) comes from the timing class of each row of :mod:`robosoc.isa.table`: 1
cycle for ALU, LUI, AUIPC, FENCE and not-taken branches; 3 for loads, stores, taken branches, JAL
and JALR; 5 + steps(rs2) for multiplies.  Devices are reached through :mod:`robosoc.kernels.soc_bus`;
the loop consults the interrupt controller (:mod:`robosoc.kernels.dev_irq`) only at instruction
boundaries at or after the earliest cycle an entry could happen, so an instruction costs one
comparison for it.

Only the loaded code has predecode rows (``S_CODE_SIZE`` bytes from the SRAM base, plus the
sentinel row), so the table grows with the program rather than with the SRAM.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from robosoc.isa.table import (
    BRANCH_NOT_TAKEN_CYCLES,
    BRANCH_TAKEN_CYCLES,
    INSTRUCTIONS,
    JUMP_CYCLES,
    MEMORY_CYCLES,
    MUL_BASE_CYCLES,
    OP,
    OP_BREAK,
    OP_ENTRY,
    OP_FETCH_FAULT,
    OP_ILLEGAL,
    SINGLE_CYCLES,
    TRAP_CYCLES,
    Fmt,
)
from robosoc.kernels.borrowed import UNCOUNTED, row
from robosoc.kernels.core_layout import (
    C_MMIO,
    C_MUL_STALL,
    C_TAKEN,
    DEV_EXIT,
    DEV_NI,
    DEV_READONLY,
    ERR_FETCH,
    ERR_FETCH_DATA,
    ERR_FETCH_MISALIGNED,
    ERR_ILLEGAL,
    ERR_LOAD_MISALIGNED,
    ERR_LOAD_UNMAPPED,
    ERR_NO_MUL,
    ERR_STORE_MISALIGNED,
    ERR_STORE_READONLY,
    ERR_STORE_UNMAPPED,
    ERR_UNSUPPORTED,
    ERRATA_RTL,
    OPC_SIZE,
    OUT_CAPACITY,
    RUN_BREAK,
    RUN_CHUNK,
    RUN_ENTRY,
    RUN_ERROR,
    RUN_EXIT,
    RUN_MAX_CYCLES,
    RUN_NI,
    RUN_OUTPUT,
    S_CODE_SIZE,
    S_CODE_STORES,
    S_CYCLE,
    S_ERR,
    S_ERR_ADDR,
    S_ERR_INSN,
    S_ERR_PC,
    S_ERRATA,
    S_IRQ_CHECK,
    S_MAX_CYCLES,
    S_MEM_BASE,
    S_MEM_SIZE,
    S_MUL,
    S_MUL_END,
    S_MULHSU_COUNT,
    S_MULHSU_PC,
    S_OUT_LEN,
    S_PC,
    S_PROF_BASE,
    S_PROF_STRIDE,
    S_RUN,
)
from robosoc.kernels.dev_irq import irq_event, trap
from robosoc.kernels.soc_bus import LD_NI, LD_OK, mmio_load, mmio_store

# The encoding table as arrays for the decoder.
_MATCH = np.array([i.match for i in INSTRUCTIONS], dtype=np.int64)
_MASK = np.array([i.mask for i in INSTRUCTIONS], dtype=np.int64)
_FMT = np.array([int(i.fmt) for i in INSTRUCTIONS], dtype=np.int64)
_UNSUPPORTED = np.array([1 if i.unsupported else 0 for i in INSTRUCTIONS], dtype=np.int64)

# Operation numbers are compile-time constants for the dispatch below.
LUI, AUIPC, JAL, JALR = OP["lui"], OP["auipc"], OP["jal"], OP["jalr"]
BEQ, BNE, BLT, BGE, BLTU, BGEU = OP["beq"], OP["bne"], OP["blt"], OP["bge"], OP["bltu"], OP["bgeu"]
LB, LH, LW, LBU, LHU, SB, SH, SW = OP["lb"], OP["lh"], OP["lw"], OP["lbu"], OP["lhu"], OP["sb"], OP["sh"], OP["sw"]
ADDI, SLTI, SLTIU, XORI, ORI, ANDI = OP["addi"], OP["slti"], OP["sltiu"], OP["xori"], OP["ori"], OP["andi"]
SLLI, SRLI, SRAI = OP["slli"], OP["srli"], OP["srai"]
ADD, SUB, SLL, SLT, SLTU, XOR, SRL, SRA, OR, AND = (
    OP["add"], OP["sub"], OP["sll"], OP["slt"], OP["sltu"], OP["xor"], OP["srl"], OP["sra"], OP["or"], OP["and"],
)  # fmt: skip
MUL, MULH, MULHSU, MULHU = OP["mul"], OP["mulh"], OP["mulhsu"], OP["mulhu"]
FENCE = OP["fence"]
FIRST_SYSTEM = OP["ecall"]
FETCH_FAULT = OP_FETCH_FAULT
BREAK = OP_BREAK
ENTRY = OP_ENTRY
ILLEGAL = OP_ILLEGAL

F_I, F_SHIFT, F_LOAD, F_S = int(Fmt.I), int(Fmt.SHIFT), int(Fmt.LOAD), int(Fmt.S)
F_B, F_U, F_J, F_JALR = int(Fmt.B), int(Fmt.U), int(Fmt.J), int(Fmt.JALR)

SINK = 32  # register index that stands in for rd = x0
NOP_ROW = ADDI | (SINK << 8)  # predecoded `addi x0, x0, 0` (its immediate row is 0)
UNSUPPORTED_BIT = 0x80
U1 = np.uint64(1)
U2 = np.uint64(2)
U8 = np.uint64(8)
U16 = np.uint64(16)
U24 = np.uint64(24)
U255 = np.uint64(255)
M32 = 0xFFFFFFFF


@njit(cache=True, inline="always")
def _sext(v: int, bits: int) -> int:
    sign = np.int64(1) << (bits - 1)
    v &= (np.int64(1) << bits) - 1
    return (v ^ sign) - sign


@njit(cache=True)
def decode_word(w: int | np.integer, dec: np.ndarray, i: int | np.integer) -> None:
    """Fill row ``i`` of ``dec`` for instruction word ``w``.

    A row is two int32: ``op | rd << 8 | rs1 << 16 | rs2 << 24`` and the immediate.  Encodings
    the hardware lacks (DIV/REM) get ``op | UNSUPPORTED_BIT``; words matching no row get ILLEGAL.
    """
    w &= M32
    op = ILLEGAL
    fmt = -1
    for k in range(_MATCH.shape[0]):
        if (w & _MASK[k]) == _MATCH[k]:
            op = k + 1
            fmt = _FMT[k]
            break
    rd = (w >> 7) & 31
    if rd == 0:
        rd = SINK
    imm = 0
    if fmt == F_I or fmt == F_LOAD or fmt == F_JALR:
        imm = _sext(w >> 20, 12)
    elif fmt == F_SHIFT:
        imm = (w >> 20) & 31
    elif fmt == F_S:
        imm = _sext(((w >> 25) << 5) | ((w >> 7) & 31), 12)
    elif fmt == F_B:
        imm = _sext(
            ((w >> 31) << 12) | (((w >> 7) & 1) << 11) | (((w >> 25) & 0x3F) << 5) | (((w >> 8) & 0xF) << 1), 13
        )
    elif fmt == F_U:
        imm = _sext(w & 0xFFFFF000, 32)
    elif fmt == F_J:
        imm = _sext(
            ((w >> 31) << 20) | (((w >> 12) & 0xFF) << 12) | (((w >> 20) & 1) << 11) | (((w >> 21) & 0x3FF) << 1), 21
        )
    if op != ILLEGAL and _UNSUPPORTED[op - 1] != 0:
        op |= UNSUPPORTED_BIT
    dec[2 * i] = op | (rd << 8) | (((w >> 15) & 31) << 16) | (((w >> 20) & 31) << 24)
    dec[2 * i + 1] = imm


def _multiplier_chunk_table() -> np.ndarray:
    """Steps of the multiplier's counter across one byte of rs2, for table-driven latency.

    Inside the loop the counter c moves by 1 when bits c..c+3 of rs2 are not all zero, else by 4
    (platform.md §1).  Entry ``[off, w]`` gives, for a counter entering a byte at offset ``off``
    (0..3) and the 11 bits ``w`` from the byte's first bit, ``steps * 16 + exit_offset`` where
    the counter leaves the byte at ``8 + exit_offset``.
    """
    table = np.zeros((4, 2048), dtype=np.int64)
    for off in range(4):
        for w in range(2048):
            c, steps = off, 0
            while c < 8:
                c += 1 if (w >> c) & 15 else 4
                steps += 1
            table[off, w] = steps * 16 + (c - 8)
    return table


_MUL_CHUNK = _multiplier_chunk_table()


@njit(cache=True, inline="always")
def mul_latency(b: int) -> int:
    """Cycles of a multiply: 5 + steps of the iterative multiplier over rs2 (platform.md §1)."""
    steps = 0
    c = 0
    for k in range(3):  # bits 0..23 by table, while the counter is below 24
        e = _MUL_CHUNK[c - 8 * k, (b >> (8 * k)) & 2047]
        steps += e >> 4
        c = 8 * (k + 1) + (e & 15)
    while c < 28:
        c += 1 if (b >> c) & 15 else 4
        steps += 1
    # from c to 31 one step per bit, then the last step at c == 31
    return MUL_BASE_CYCLES + steps + (31 - c) + 1


@njit(cache=True, inline="always")
def fields(dec_t: np.ndarray, i: np.uint64) -> tuple[np.uint64, np.uint64, np.uint64, np.uint64, np.int64]:
    """(op, rd, rs1, rs2, imm) of predecode row ``i``."""
    w0 = np.uint64(np.uint32(dec_t[i << U1]))
    return w0 & U255, (w0 >> U8) & U255, (w0 >> U16) & U255, w0 >> U24, np.int64(dec_t[(i << U1) + U1])


@njit(cache=True, inline="always")
def fetch_error(target: int, base: int, code: int, size: int) -> int:
    """0 if the core may continue at ``target``, else the ERR_* code of the jump or branch."""
    if target & 3:
        return ERR_FETCH_MISALIGNED
    off = (target - base) & M32
    if off >= code:
        return ERR_FETCH_DATA if off < size else ERR_FETCH
    return 0


@njit(cache=True, inline="always")
def flow(st: np.ndarray, t: int, opc_t: np.ndarray, word: np.uint64, n: int) -> None:
    """Add ``n`` to the profile's flow count of ``word`` (see ``run_cores``; nothing when not profiling).

    The profile's state is read from ``st`` where it is needed rather than held in the loop: the
    interpreter's hot path keeps its registers.
    """
    if st[t, S_PROF_STRIDE] != 0:
        opc_t[np.uint64(st[t, S_PROF_BASE]) + word] += n


@njit(cache=True, inline="always")
def flow_jump(st: np.ndarray, t: int, opc_t: np.ndarray, pc: int, target: int, base: int) -> None:
    """The profile's flow counts of a transfer from the instruction at ``pc`` to ``target``."""
    if st[t, S_PROF_STRIDE] != 0:
        pb = np.uint64(st[t, S_PROF_BASE])
        opc_t[pb + (np.uint64(target - base) >> U2)] += 1
        opc_t[pb + (np.uint64(pc - base) >> U2) + U1] -= 1


@njit(cache=True, inline="always")
def flow_extra(st: np.ndarray, t: int, opc_t: np.ndarray, word: np.uint64, cycles: int) -> None:
    """Dynamic extra cycles of ``word`` (taken branch, multiply) in the profile's second half."""
    if st[t, S_PROF_STRIDE] != 0:
        half = np.uint64((opc_t.shape[0] - OPC_SIZE) >> 1)
        opc_t[np.uint64(st[t, S_PROF_BASE]) + half + word] += cycles


@njit(cache=True, inline="always")
def branch(
    taken: bool, pc: int, imm: int, cyc: int, n_taken: int, base: int, code: int, size: int,
    st: np.ndarray, t: int, opc_t: np.ndarray,
) -> tuple[int, int, int, int, int]:  # fmt: skip
    """A conditional branch: (pc, cyc, taken count, err, err_addr) after it (a taken one books its
    jump and extra cycles in the profile of core ``t``, if it is profiled: see ``run_cores``)."""
    if not taken:
        return pc + 4, cyc + BRANCH_NOT_TAKEN_CYCLES, n_taken, 0, 0
    target = (pc + imm) & M32
    err = fetch_error(target, base, code, size)
    if err != 0:
        return pc, cyc, n_taken, err, target
    flow_jump(st, t, opc_t, pc, target, base)
    flow_extra(st, t, opc_t, np.uint64(pc - base) >> U2, BRANCH_TAKEN_CYCLES - BRANCH_NOT_TAKEN_CYCLES)
    return target, cyc + BRANCH_TAKEN_CYCLES, n_taken + 1, 0, 0


@njit(cache=True, inline="always")
def load_device(
    st_t: np.ndarray, ctr_t: np.ndarray, opc_t: np.ndarray, k: np.uint64, addr: int, cyc: int
) -> tuple[int, int, int]:
    """A load outside SRAM: (value, RUN_CHUNK or RUN_NI or RUN_ERROR, err)."""
    v, code = mmio_load(st_t, addr, cyc)
    if code == LD_NI:
        opc_t[k] -= 1  # not executed yet: the chip loop performs it
        return 0, RUN_NI, 0
    if code != LD_OK:
        return 0, RUN_ERROR, ERR_LOAD_UNMAPPED
    ctr_t[C_MMIO] += 1
    return v, RUN_CHUNK, 0


@njit(cache=True, inline="always")
def store_device(
    st_t: np.ndarray, ctr_t: np.ndarray, out_t: np.ndarray, opc_t: np.ndarray, k: np.uint64, addr: int,
    value: int, pc: int, cyc: int,
) -> tuple[int, int, int, int]:  # fmt: skip
    """A store outside SRAM: (status, err, pc, cyc) after it (status RUN_CHUNK: go on)."""
    r = mmio_store(st_t, out_t, addr, value, cyc)
    if r == DEV_NI:
        opc_t[k] -= 1  # not executed yet: the chip loop performs it
        return RUN_NI, 0, pc, cyc
    ctr_t[C_MMIO] += 1
    if r == DEV_EXIT:
        return RUN_EXIT, 0, pc + 4, cyc + MEMORY_CYCLES
    if r < 0:
        return RUN_ERROR, ERR_STORE_READONLY if r == DEV_READONLY else ERR_STORE_UNMAPPED, pc, cyc
    return RUN_CHUNK, 0, pc + 4, cyc + MEMORY_CYCLES


#: the encodings of LW and SW (their rows of the table: the first that match them, as decode_word finds)
LW_MASK, LW_MATCH = int(_MASK[LW - 1]), int(_MATCH[LW - 1])
SW_MASK, SW_MATCH = int(_MASK[SW - 1]), int(_MATCH[SW - 1])


@njit(cache=True, inline="always")
def device_step(
    st_t: np.ndarray, ctr_t: np.ndarray, out_t: np.ndarray, opc_t: np.ndarray, regs_t: np.ndarray, word: int | np.int64,
    i: int, pc: int, cyc: int, base: int, size: int,
) -> tuple[bool, int, int, int, int, int]:  # fmt: skip
    """Instruction ``word`` (word ``i`` of the code, at ``pc``, in cycle ``cyc``) if it is an LW or
    SW of a device register, executed as ``run_cores`` executes it when it is the only instruction
    of a call (the caller has made sure that no interrupt event is due in ``cyc`` and that the
    core is not profiled): (done, status, err, err_addr, pc, cyc) after it.  ``done`` False, with
    nothing changed, for any other word and for an access the interpreter does not perform itself
    (SRAM, misaligned: status RUN_CHUNK; a network-interface register, which the chip loop
    performs: status RUN_NI, ``run_cores`` stops before it).
    The dispatch loop (:mod:`robosoc.kernels.jit_dispatch`) makes a translated core's device
    accesses here, without an interpreter call; the word need not be predecoded.  Inlined: called,
    it cost a sleeping 16x16 chip's translated tick about 0.25 µs more (eleven calls, each
    passing five arrays); its copy costs the cold start no measurable time."""
    w = word & M32
    load = (w & LW_MASK) == LW_MATCH
    if not load and (w & SW_MASK) != SW_MATCH:
        return False, RUN_CHUNK, 0, 0, pc, cyc
    imm = _sext(w >> 20, 12) if load else _sext(((w >> 25) << 5) | ((w >> 7) & 31), 12)
    addr = (regs_t[(w >> 15) & 31] + imm) & M32
    off = addr - base
    if (off & 3) != 0 or (off & M32) < size:
        return False, RUN_CHUNK, 0, 0, pc, cyc
    if load:
        kc = (np.uint64(LW) << U1) | (np.uint64(i) & U1)
        opc_t[kc] += 1
        v, status, err = load_device(st_t, ctr_t, opc_t, kc, addr, cyc)
        if status == RUN_NI:  # (load_device took the count back)
            return False, RUN_NI, 0, 0, pc, cyc
        if status != RUN_CHUNK:
            return True, status, err, addr, pc, cyc
        rd = (w >> 7) & 31
        regs_t[rd if rd != 0 else SINK] = v
        return True, RUN_CHUNK, 0, 0, pc + 4, cyc + MEMORY_CYCLES
    kc = (np.uint64(SW) << U1) | (np.uint64(i) & U1)
    opc_t[kc] += 1
    status, err, pc, cyc = store_device(
        st_t, ctr_t, out_t, opc_t, kc, addr, np.int64(regs_t[(w >> 20) & 31]), pc, cyc
    )  # int64 like run_cores' store: one compiled mmio_store
    if status == RUN_NI:  # (store_device took the count back)
        return False, RUN_NI, 0, 0, pc, cyc
    return True, status, err, addr if err != 0 else 0, pc, cyc


class CoreArrays(NamedTuple):
    """The arrays of a set of cores, one row per core (tile); built by ``CoreState.arrays()``.

    ``st`` state (layout: core_layout.S_*), ``ctr`` event counters (C_*), ``opc`` instructions per
    operation in two banks, ``regs`` x0..x31 and a sink, ``m8``/``m16``/``m32`` three views of the
    SRAM bytes, ``dec`` the predecode rows of the loaded code, ``out`` the output buffer.  Beyond
    its OPC_SIZE per-operation counters an ``opc`` row holds the exact profile (see ``run_cores``).
    """

    st: np.ndarray
    ctr: np.ndarray
    opc: np.ndarray
    regs: np.ndarray
    m8: np.ndarray
    m16: np.ndarray
    m32: np.ndarray
    dec: np.ndarray
    out: np.ndarray


@njit(**UNCOUNTED)
def run_cores(core: CoreArrays, tiles: np.ndarray, until: int) -> None:
    """Run each core in ``tiles`` until cycle ``until`` or until it must stop.

    Every array has one row per core (tile).  A core stops at the first instruction boundary at or
    after ``until``, at its exit, an error, its cycle budget, a full output buffer, before an
    instruction a debugger marked (RUN_BREAK) or where a translated block starts (RUN_ENTRY: only
    the dispatch loop's cores have such words, :mod:`robosoc.kernels.jit_dispatch`), or just before
    an access to its network-interface registers (RUN_NI: the chip simulator performs that access
    in global time order).  The reason is left in ``st[t, S_RUN]``; all state stays in the arrays,
    so calls can be repeated.

    ``opc[t, 2 * op + (word index & 1)]`` counts executed instructions per operation (two banks,
    so that consecutive instructions never wait on the same counter); ``dec`` is the predecode
    table (int32, two per word of loaded code).  The three arrays the loop touches on every
    instruction (registers, predecode, counters) are taken as row views once per tile; the others
    are indexed in two dimensions, because every view costs reference counting on entry and exit,
    which dominates the short time slices of a busy many-core chip.

    The exact profile (``S_PROF_STRIDE`` != 0, :meth:`robosoc.chip.core_state.CoreState.enable_profile`)
    lives in the ``opc`` row after its OPC_SIZE counters, so that it costs no array (no view, no
    reference count) of its own.  It counts the flow of control, not each instruction: column
    ``S_PROF_BASE + i`` (the running task's bank) gains one each time execution arrives at word i
    other than from word i - 1 (entry to this function, a taken branch or jump, an interrupt or trap
    entry) and loses one each time it leaves word i - 1 other than to word i (a taken branch or jump,
    a redirection, a stop before word i), so the executions of word i are the running sum of the
    bank up to i.  The column W further on (W = half the row beyond OPC_SIZE) adds the dynamic extra
    cycles of taken branches and multiplies.  Sequential instructions cost nothing; not profiling, a
    jump costs a load and a well-predicted branch more.

    One compiled function, called (not inlined) by the chip loop, the dispatch loop and the host's
    single-core engines, and compiled without reference counts (``_nrt=False``: see
    :mod:`robosoc.kernels.borrowed`).  numba's ``inline="always"`` would copy its IR into each
    caller: copying this function's 439 blocks was 8 of the 21 s its compilation took, and up to
    39 s nested inside another compilation (2026-11-28).
    """
    st, ctr, opc, regs, m8, m16, m32, dec, out = core
    for k in range(tiles.shape[0]):
        t = tiles[k]
        opc_t = row(opc, t)
        regs_t = row(regs, t)
        dec_t = row(dec, t)
        base = st[t, S_MEM_BASE]
        size = st[t, S_MEM_SIZE]
        code = st[t, S_CODE_SIZE]
        code_words = np.uint64(code >> 2)
        has_mul = st[t, S_MUL] != 0
        rtl = st[t, S_ERRATA] == ERRATA_RTL
        pc = st[t, S_PC]
        cyc = st[t, S_CYCLE]
        budget = st[t, S_MAX_CYCLES]
        stop = until if budget < 0 else min(until, budget)
        out_limit = OUT_CAPACITY - 8
        n_taken = ctr[t, C_TAKEN]
        n_mulstall = ctr[t, C_MUL_STALL]

        status = RUN_CHUNK
        err = 0
        err_addr = 0
        next_event = min(st[t, S_IRQ_CHECK], stop)
        flow(st, t, opc_t, np.uint64(pc - base) >> U2, 1)  # the flow arrives here

        while True:
            if cyc >= next_event:
                if cyc >= st[t, S_IRQ_CHECK]:
                    was = pc
                    pc, cyc = irq_event(row(st, t), row(ctr, t), pc, cyc)
                    err = fetch_error(pc, base, code, size)
                    if err != 0:  # IRQ_VECTOR outside the loaded code
                        err_addr = pc
                        break
                    if pc != was:  # an entry: the flow leaves `was` unexecuted
                        flow(st, t, opc_t, np.uint64(was - base) >> U2, -1)
                        flow(st, t, opc_t, np.uint64(pc - base) >> U2, 1)
                if cyc >= stop:
                    status = RUN_MAX_CYCLES if (budget >= 0 and cyc >= budget) else RUN_CHUNK
                    break
                if st[t, S_OUT_LEN] >= out_limit:
                    status = RUN_OUTPUT
                    break
                next_event = min(st[t, S_IRQ_CHECK], stop)
                if next_event <= cyc:
                    next_event = cyc + 1

            i = np.uint64(pc - base) >> U2
            op, rd, rs1, rs2, imm = fields(dec_t, i)
            kc = (op << U1) | (i & U1)
            opc_t[kc] += 1  # two banks by word parity: no store-to-load chain

            if op == ADDI:
                regs_t[rd] = regs_t[rs1] + imm
                cyc += SINGLE_CYCLES
                pc += 4
            elif op == LW:
                addr = (regs_t[rs1] + imm) & M32
                off = addr - base
                if off & 3:
                    err = ERR_LOAD_MISALIGNED
                    err_addr = addr
                    break
                if (off & M32) < size:
                    regs_t[rd] = m32[t, np.uint64(off) >> U2]
                else:
                    v, status, err = load_device(row(st, t), row(ctr, t), opc_t, kc, addr, cyc)
                    if status != RUN_CHUNK:
                        err_addr = addr
                        break
                    regs_t[rd] = v
                cyc += MEMORY_CYCLES
                pc += 4
            elif op == SW:
                addr = (regs_t[rs1] + imm) & M32
                off = addr - base
                if off & 3:
                    err = ERR_STORE_MISALIGNED
                    err_addr = addr
                    break
                if (off & M32) < size:
                    wi = np.uint64(off) >> U2
                    m32[t, wi] = regs_t[rs2]
                    if wi < code_words:
                        dec_t[wi << U1] = 0  # the word may be code: decode it again
                        st[t, S_CODE_STORES] += 1
                    cyc += MEMORY_CYCLES
                    pc += 4
                else:
                    status, err, pc, cyc = store_device(
                        row(st, t), row(ctr, t), row(out, t), opc_t, kc, addr, np.int64(regs_t[rs2]), pc, cyc
                    )  # int64 like the other store: one compiled mmio_store
                    if status != RUN_CHUNK:
                        err_addr = addr
                        break
                    next_event = cyc
            elif op == ADD:
                regs_t[rd] = regs_t[rs1] + regs_t[rs2]
                cyc += SINGLE_CYCLES
                pc += 4
            elif op == BNE:
                pc, cyc, n_taken, err, err_addr = branch(
                    regs_t[rs1] != regs_t[rs2], pc, imm, cyc, n_taken, base, code, size, st, t, opc_t
                )
                if err != 0:
                    break
            elif op == BEQ:
                pc, cyc, n_taken, err, err_addr = branch(
                    regs_t[rs1] == regs_t[rs2], pc, imm, cyc, n_taken, base, code, size, st, t, opc_t
                )
                if err != 0:
                    break
            elif op == BLT:
                pc, cyc, n_taken, err, err_addr = branch(
                    regs_t[rs1] < regs_t[rs2], pc, imm, cyc, n_taken, base, code, size, st, t, opc_t
                )
                if err != 0:
                    break
            elif op == BGE:
                pc, cyc, n_taken, err, err_addr = branch(
                    regs_t[rs1] >= regs_t[rs2], pc, imm, cyc, n_taken, base, code, size, st, t, opc_t
                )
                if err != 0:
                    break
            elif op == BLTU:
                pc, cyc, n_taken, err, err_addr = branch(
                    (regs_t[rs1] & M32) < (regs_t[rs2] & M32), pc, imm, cyc, n_taken, base, code, size,
                    st, t, opc_t,
                )  # fmt: skip
                if err != 0:
                    break
            elif op == BGEU:
                pc, cyc, n_taken, err, err_addr = branch(
                    (regs_t[rs1] & M32) >= (regs_t[rs2] & M32), pc, imm, cyc, n_taken, base, code, size,
                    st, t, opc_t,
                )  # fmt: skip
                if err != 0:
                    break
            elif op == SLLI:
                regs_t[rd] = regs_t[rs1] << imm
                cyc += SINGLE_CYCLES
                pc += 4
            elif op == SRLI:
                regs_t[rd] = (regs_t[rs1] & M32) >> imm
                cyc += SINGLE_CYCLES
                pc += 4
            elif op == SRAI:
                regs_t[rd] = regs_t[rs1] >> imm
                cyc += SINGLE_CYCLES
                pc += 4
            elif op == ANDI:
                regs_t[rd] = regs_t[rs1] & imm
                cyc += SINGLE_CYCLES
                pc += 4
            elif op == ORI:
                regs_t[rd] = regs_t[rs1] | imm
                cyc += SINGLE_CYCLES
                pc += 4
            elif op == XORI:
                regs_t[rd] = regs_t[rs1] ^ imm
                cyc += SINGLE_CYCLES
                pc += 4
            elif op == SUB:
                regs_t[rd] = regs_t[rs1] - regs_t[rs2]
                cyc += SINGLE_CYCLES
                pc += 4
            elif op == AND:
                regs_t[rd] = regs_t[rs1] & regs_t[rs2]
                cyc += SINGLE_CYCLES
                pc += 4
            elif op == OR:
                regs_t[rd] = regs_t[rs1] | regs_t[rs2]
                cyc += SINGLE_CYCLES
                pc += 4
            elif op == XOR:
                regs_t[rd] = regs_t[rs1] ^ regs_t[rs2]
                cyc += SINGLE_CYCLES
                pc += 4
            elif op == SLL:
                regs_t[rd] = regs_t[rs1] << (regs_t[rs2] & 31)
                cyc += SINGLE_CYCLES
                pc += 4
            elif op == SRL:
                regs_t[rd] = (regs_t[rs1] & M32) >> (regs_t[rs2] & 31)
                cyc += SINGLE_CYCLES
                pc += 4
            elif op == SRA:
                regs_t[rd] = regs_t[rs1] >> (regs_t[rs2] & 31)
                cyc += SINGLE_CYCLES
                pc += 4
            elif op == SLT:
                regs_t[rd] = 1 if regs_t[rs1] < regs_t[rs2] else 0
                cyc += SINGLE_CYCLES
                pc += 4
            elif op == SLTU:
                regs_t[rd] = 1 if (regs_t[rs1] & M32) < (regs_t[rs2] & M32) else 0
                cyc += SINGLE_CYCLES
                pc += 4
            elif op == SLTI:
                regs_t[rd] = 1 if regs_t[rs1] < imm else 0
                cyc += SINGLE_CYCLES
                pc += 4
            elif op == SLTIU:
                regs_t[rd] = 1 if (regs_t[rs1] & M32) < (imm & M32) else 0
                cyc += SINGLE_CYCLES
                pc += 4
            elif op == LUI:
                regs_t[rd] = imm
                cyc += SINGLE_CYCLES
                pc += 4
            elif op == AUIPC:
                regs_t[rd] = pc + imm
                cyc += SINGLE_CYCLES
                pc += 4
            elif op == JAL or op == JALR:
                target = (pc + imm) & M32 if op == JAL else (regs_t[rs1] + imm) & 0xFFFFFFFE
                err = fetch_error(target, base, code, size)
                if err != 0:
                    err_addr = target
                    break
                regs_t[rd] = pc + 4
                if op == JAL and rd == SINK and imm <= 0:
                    # idle loops `j .` and `nop; j .-4`: skip whole iterations while every boundary
                    # they pass lies before the next event (interrupt check, end of the slice)
                    if imm == 0:
                        n = (next_event - cyc - 1) // JUMP_CYCLES
                        if n > 0:
                            cyc += JUMP_CYCLES * n
                            opc_t[kc] += n
                            flow(st, t, opc_t, i, n)  # n more arrivals at the jump, departures after it
                            flow(st, t, opc_t, i + U1, -n)
                    elif imm == -4 and dec_t[(i << U1) - U2] == NOP_ROW and dec_t[(i << U1) - U1] == 0:
                        period = JUMP_CYCLES + SINGLE_CYCLES
                        n = (next_event - (cyc + JUMP_CYCLES)) // period
                        if n > 0:
                            cyc += period * n
                            opc_t[kc] += n
                            opc_t[(np.uint64(ADDI) << U1) | ((i - U1) & U1)] += n
                            flow(st, t, opc_t, i - U1, n)  # n more arrivals at the nop, departures after the jump
                            flow(st, t, opc_t, i + U1, -n)
                flow_jump(st, t, opc_t, pc, target, base)
                pc = target
                cyc += JUMP_CYCLES
            elif op == LBU or op == LB or op == LHU or op == LH:
                addr = (regs_t[rs1] + imm) & M32
                off = addr - base
                if (op == LHU or op == LH) and (off & 1):
                    err = ERR_LOAD_MISALIGNED
                    err_addr = addr
                    break
                if (off & M32) < size:
                    if op == LBU:
                        v = np.int64(m8[t, np.uint64(off)])
                    elif op == LB:
                        v = _sext(np.int64(m8[t, np.uint64(off)]), 8)
                    elif op == LHU:
                        v = np.int64(m16[t, np.uint64(off) >> U1])
                    else:
                        v = _sext(np.int64(m16[t, np.uint64(off) >> U1]), 16)
                else:
                    w, status, err = load_device(row(st, t), row(ctr, t), opc_t, kc, addr, cyc)
                    if status != RUN_CHUNK:
                        err_addr = addr
                        break
                    sh = (addr & 3) * 8
                    if op == LBU:
                        v = (w >> sh) & 0xFF
                    elif op == LB:
                        v = _sext((w >> sh) & 0xFF, 8)
                    elif op == LHU:
                        v = (w >> sh) & 0xFFFF
                    else:
                        v = _sext((w >> sh) & 0xFFFF, 16)
                regs_t[rd] = v
                cyc += MEMORY_CYCLES
                pc += 4
            elif op == SB or op == SH:
                addr = (regs_t[rs1] + imm) & M32
                off = addr - base
                if op == SH and (off & 1):
                    err = ERR_STORE_MISALIGNED
                    err_addr = addr
                    break
                if (off & M32) < size:
                    if op == SB:
                        m8[t, np.uint64(off)] = regs_t[rs2]
                    else:
                        m16[t, np.uint64(off) >> U1] = regs_t[rs2]
                    wi = np.uint64(off) >> U2
                    if wi < code_words:
                        dec_t[wi << U1] = 0  # the word may be code: decode it again
                        st[t, S_CODE_STORES] += 1
                    cyc += MEMORY_CYCLES
                    pc += 4
                else:
                    value = regs_t[rs2] & 0xFF if op == SB else regs_t[rs2] & 0xFFFF
                    status, err, pc, cyc = store_device(
                        row(st, t), row(ctr, t), row(out, t), opc_t, kc, addr, value, pc, cyc
                    )
                    if status != RUN_CHUNK:
                        err_addr = addr
                        break
                    next_event = cyc
            elif op == MUL or op == MULH or op == MULHU or op == MULHSU:
                if not has_mul:
                    err = ERR_NO_MUL
                    break
                a = np.int64(regs_t[rs1])
                b = np.int64(regs_t[rs2])
                p = a * b
                if op == MUL:
                    regs_t[rd] = p
                elif op == MULH:
                    regs_t[rd] = p >> 32
                elif op == MULHU or rtl:  # the RTL's MULHSU returns the MULHU result (erratum)
                    regs_t[rd] = (p >> 32) + (b if a < 0 else 0) + (a if b < 0 else 0)
                else:
                    regs_t[rd] = (p >> 32) + (a if b < 0 else 0)
                if op == MULHSU:
                    st[t, S_MULHSU_COUNT] += 1
                    if st[t, S_MULHSU_PC] < 0:
                        st[t, S_MULHSU_PC] = pc
                lat = mul_latency(b & M32)
                n_mulstall += lat - 1
                flow_extra(st, t, opc_t, i, lat - 1)
                cyc += lat
                pc += 4
                st[t, S_MUL_END] = cyc  # the interrupt controller's erratum window needs it
            elif op == FENCE:
                cyc += SINGLE_CYCLES
                pc += 4
            elif op == 0:
                opc_t[kc] -= 1
                decode_word(m32[t, i], dec_t, i)
            elif op >= FIRST_SYSTEM and op < ILLEGAL:
                # SYSTEM opcode: trap.  EPC = trap + 8; the instruction at trap + 8 executes first.
                cyc += TRAP_CYCLES
                trap(row(st, t), pc, cyc)
                flow_jump(st, t, opc_t, pc, pc + 8, base)
                pc += 8
                next_event = cyc + 1
            elif op == FETCH_FAULT:
                err = ERR_FETCH if code >= size else ERR_FETCH_DATA
                err_addr = pc
                break
            elif op == BREAK:
                opc_t[kc] -= 1  # not executed: a debugger stops the core before it
                status = RUN_BREAK
                break
            elif op == ENTRY:
                opc_t[kc] -= 1  # not executed here: the dispatch loop runs the translated block
                status = RUN_ENTRY
                break
            elif op & UNSUPPORTED_BIT:
                err = ERR_UNSUPPORTED
                break
            else:
                err = ERR_ILLEGAL
                break

        if err != 0:
            status = RUN_ERROR
            st[t, S_ERR] = err
            st[t, S_ERR_PC] = pc
            st[t, S_ERR_ADDR] = err_addr
            wi = (pc - base) >> 2
            st[t, S_ERR_INSN] = m32[t, wi] & M32 if 0 <= wi < size >> 2 else 0

        w = np.uint64(pc - base) >> U2  # the flow stops before pc (if profiled, and pc is in the code)
        if w < np.uint64(st[t, S_PROF_STRIDE]):
            opc_t[np.uint64(st[t, S_PROF_BASE]) + w] -= 1
        st[t, S_PC] = pc & M32
        st[t, S_CYCLE] = cyc
        st[t, S_RUN] = status
        ctr[t, C_TAKEN] = n_taken
        ctr[t, C_MUL_STALL] = n_mulstall
