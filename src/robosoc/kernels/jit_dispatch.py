"""The compiled dispatch loop of the block translator: translated regions and the interpreter, alternating.

The loop keeps the interpreter's instruction-boundary rules (:func:`robosoc.kernels.core.run_cores`):
at every boundary at or after the next event it consults the interrupt controller, the end of the
slice and the output buffer in the same order.  Between events it calls the translated region that
has an entry at the pc (through a function pointer, :func:`call_region`), which runs blocks only
while the block's worst-case cycles end before the next event (docs/translation.md).  Whatever a
region does not do -- device accesses, misaligned or unmapped accesses, traps, illegal words, the
idle loops the interpreter skips -- the interpreter does, one instruction at a time, by calling
``run_cores`` with the slice ending at the next cycle; from a block that could reach the next event
it runs up to the event (on the chip: to the end of the quantum).  Every translated block start
holds OP_ENTRY in its predecode row, so the interpreter, wherever it runs, stops before translated
code (RUN_ENTRY) and the loop calls it; to run such a word itself the loop takes the mark off until
the core has left the word (CTX_UNMARKED).

A region returns one of the X_* codes with the pc and cycle in ``ctx``.  A region adds the
instructions it executes to the core's counters itself (``opc``, passed to it, and the taken
branches' ``ctr[C_TAKEN]``; :mod:`robosoc.jit.emit_ir`), so the counters equal the interpreter's
whenever a region returns: the chip's accounting at a TASK_ID store (the interpreter's, in the
chip loop) charges the running task with what its translated blocks executed, as with the
interpreter.  Stores into the
loaded code are always the interpreter's, which counts them (``S_CODE_STORES``); when the count
moved, the loop compares the translated words with memory and forgets every translation if one
changed (a pass over those words, so not after every interpreted stretch).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, NamedTuple

import numpy as np
from llvmlite import ir
from numba import njit, types
from numba.extending import intrinsic
from numba.typed import List

from robosoc.isa.table import OP_BREAK, OP_ENTRY, SINGLE_CYCLES
from robosoc.kernels.borrowed import UNCOUNTED, row
from robosoc.kernels.core import ADDI, SINK, CoreArrays, decode_word, device_step, fetch_error, run_cores
from robosoc.kernels.core_layout import (
    ERR_FETCH_DATA,
    OUT_CAPACITY,
    RUN_CHUNK,
    RUN_ENTRY,
    RUN_ERROR,
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
    S_IRQ_CHECK,
    S_MAX_CYCLES,
    S_MEM_BASE,
    S_MEM_SIZE,
    S_OUT_LEN,
    S_PC,
    S_PROF_STRIDE,
    S_RUN,
)
from robosoc.kernels.dev_irq import irq_event

# region exit codes
X_JUMP = 0  # control left the region for a pc without a translation: continue at ctx[CTX_PC]
X_LIMIT = 1  # the block at ctx[CTX_PC] could reach the next event: the interpreter runs it
X_SIDE = 2  # the instruction at ctx[CTX_PC] is the interpreter's (device, code store, misaligned ...)

# ctx slots
CTX_PC = 0
CTX_CYC = 1
CTX_FLUSHES = 4  # how many times the loop forgot every translation (self-modifying code)
CTX_CALLS = 5  # region calls (statistics)
CTX_STEPS = 6  # instructions handed to the interpreter (statistics)
CTX_LIMITS = 7  # region exits because a block could reach the next event (statistics)
# addresses of the tables a region reads to jump straight into the next region (JitArrays), and
# of the core's state and counter rows
CTX_ENTRY_FN = 8
CTX_ST = 9
CTX_CTR = 10
CTX_WORDS = 11  # entries of tpcs/twords that hold translated words (0 after forgetting them)
CTX_ENTRY_BLK = 12
CTX_MIDBLOCK = 13  # interpreter steps at translated words that start no block (statistics)
#: 1 + the word whose OP_ENTRY row the loop took off for the interpreter to run it, while the core
#: is still there (0: none); it goes back when the core has left the word (a core stopped there for
#: the chip loop, RUN_NI, must hold its decoded row)
CTX_UNMARKED = 14
CTX_DEVICE = 15  # device-register loads and stores the loop made itself, of the CTX_STEPS (statistics)
CTX_NOPS = 16  # `nop`s the loop executed itself after a region's limit exit, of the CTX_STEPS (statistics)
CTX_SIZE = 17

# dispatcher results beyond the interpreter's RUN_* codes
RUN_TRANSLATE = 100  # the pc in st[S_PC] turned hot: translate a region there and call again

NEVER_TRANSLATE = -(1 << 30)
#: arrivals inside a translated block (threshold times this) before a region starts there too
MIDBLOCK_FACTOR = 8  # hot counter of a word no region can start at

_JAL_X0_OPCODE = 0x6F  # jal with rd = x0 (low 12 bits)
_LOAD_STORE_OPCODE = 0x03  # the major opcode of loads (0x03) and stores (0x23) without bit 5
_NOP = 0x13  # addi x0, x0, 0
M32 = 0xFFFFFFFF


class JitArrays(NamedTuple):
    """The translator's tables, one entry per word of the loaded code plus one (the word after it).

    ``entry_fn`` native address of the region function with a block starting at the word (0: none),
    ``entry_blk`` the block's index in it, ``hot`` arrivals at a word without an entry
    (NEVER_TRANSLATE: none can start there), ``tmap`` for words some region translated the
    instructions from there to the end of the block (1..255; 0: not translated),
    ``tpcs``/``twords`` those words' indices and contents when translated, ``ctx`` the region
    call's in/out slots.
    """

    entry_fn: np.ndarray
    entry_blk: np.ndarray
    hot: np.ndarray
    tmap: np.ndarray
    tpcs: np.ndarray
    twords: np.ndarray
    ctx: np.ndarray


def empty_tables(words: int = 1) -> JitArrays:
    """Tables of ``words`` words with nothing translated (a tile that interprets holds such tables)."""
    hot = np.zeros(words, dtype=np.int32)
    hot[-1] = NEVER_TRANSLATE
    return JitArrays(
        entry_fn=np.zeros(words, dtype=np.int64),
        entry_blk=np.zeros(words, dtype=np.int64),
        hot=hot,
        tmap=np.zeros(words, dtype=np.uint8),
        tpcs=np.zeros(0, dtype=np.int64),
        twords=np.zeros(0, dtype=np.int32),
        ctx=np.zeros(CTX_SIZE, dtype=np.int64),
    )


if TYPE_CHECKING:
    # what the dispatch loop sees (numba's stubs type the call of an @intrinsic as taking the typing
    # context too and as never returning)
    def call_region(
        fn: int | np.integer,
        ctx: int | np.integer,
        regs: int | np.integer,
        mem: int | np.integer,
        opc: int | np.integer,
        cyc: int | np.integer,
        limit: int | np.integer,
        blk: int | np.integer,
    ) -> int: ...

else:

    @intrinsic
    def call_region(typingctx, fn, ctx, regs, mem, opc, cyc, limit, blk):
        """Call the region function at native address ``fn`` (array addresses, cycle, limit, block); its X_* code."""
        sig = types.int32(types.int64, *([types.int64] * 7))

        def codegen(context, builder, signature, args):
            i64 = ir.IntType(64)
            ptrs = [i64.as_pointer(), ir.IntType(32).as_pointer(), ir.IntType(8).as_pointer(), i64.as_pointer()]
            fnty = ir.FunctionType(ir.IntType(32), [*ptrs, i64, i64, i64])
            f = builder.inttoptr(args[0], fnty.as_pointer())
            call_args = [builder.inttoptr(a, t) for a, t in zip(args[1:5], ptrs, strict=True)]
            return builder.call(f, [*call_args, *args[5:8]])

        return sig, codegen


@njit(cache=True)
def tables_list(jt: JitArrays, n: int):
    """A numba typed list holding ``jt`` ``n`` times (made here, compiled and cached: the typed
    list's own constructor compiles its methods in every process, about a second of every start)."""
    tables = List()
    for _ in range(n):
        tables.append(jt)
    return tables


@njit(cache=True)
def set_tables(tables, t: int, jt: JitArrays) -> None:
    """``tables[t] = jt`` for a numba typed list of tables (compiled and cached here: the typed
    list's own ``__setitem__`` compiles in every process and costs a dispatch per call)."""
    tables[t] = jt


@njit(cache=True)
def set_table_copies(tables, tiles: np.ndarray, rows: JitArrays) -> None:
    """``tables[tiles[k]]`` = the ``k``-th copy of ``rows`` for every k: the arrays a core writes in
    place are its row ``k`` of ``rows``' (two-dimensional) ones, the others are shared
    (:meth:`robosoc.jit.tables.CoreTables.clones`; a call of :func:`set_tables` per tile cost a
    16x16 chip 1.5 ms at each run's start)."""
    for k in range(tiles.shape[0]):
        tables[tiles[k]] = JitArrays(
            rows.entry_fn[k],
            rows.entry_blk[k],
            rows.hot[k],
            rows.tmap[k],
            rows.tpcs,
            rows.twords,
            rows.ctx[k],
        )


@njit(cache=True)
def forget_translations(jt: JitArrays, dec_t: np.ndarray) -> None:
    """Drop every translation of the core whose predecode rows are ``dec_t`` (and the interpreter's
    stops before their blocks)."""
    for i in range(jt.entry_fn.shape[0]):
        if jt.entry_fn[i] != 0 and dec_t[2 * i] == OP_ENTRY:
            dec_t[2 * i] = 0  # decoded again when executed
    jt.entry_fn[:] = 0
    jt.entry_blk[:] = 0
    jt.hot[:] = 0
    jt.tmap[:] = 0
    jt.ctx[CTX_WORDS] = 0
    jt.ctx[CTX_FLUSHES] += 1


@njit(cache=True)
def forget_if_changed(jt: JitArrays, m32_t: np.ndarray, dec_t: np.ndarray) -> None:
    """Forget every translation if a word one was made from no longer holds its instruction
    (written by the interpreter's stores or a DMA)."""
    for k in range(jt.ctx[CTX_WORDS]):
        if m32_t[jt.tpcs[k]] != jt.twords[k]:
            forget_translations(jt, dec_t)
            return


@njit(nogil=True, **UNCOUNTED)
def run_translated(
    core: CoreArrays, tiles: np.ndarray, until: int, jt: JitArrays, threshold: int, stretch: int
) -> None:
    """Run core ``tiles[0]`` until cycle ``until`` like ``run_cores``, with translated regions.

    Leaves the RUN_* status in st[t, S_RUN], or RUN_TRANSLATE with the pc of a word that turned
    hot (``threshold`` arrivals without an entry) for the caller to translate.  At a word without a
    translation the interpreter runs one instruction (``stretch`` 0), or ``stretch`` cycles at its
    own speed.
    """
    st, ctr, opc, regs, m8, _m16, m32, dec, out = core
    t = tiles[0]
    st_t = row(st, t)
    dec_t = row(dec, t)
    regs_t = row(regs, t)
    opc_t = row(opc, t)
    ctr_t = row(ctr, t)
    base = st_t[S_MEM_BASE]
    size = st_t[S_MEM_SIZE]
    code = st_t[S_CODE_SIZE]
    pc = st_t[S_PC]
    cyc = st_t[S_CYCLE]
    budget = st_t[S_MAX_CYCLES]
    stop = until if budget < 0 else min(until, budget)
    out_limit = OUT_CAPACITY - 8
    ctx = jt.ctx
    p_ctx = np.int64(ctx.ctypes.data)
    p_regs = np.int64(regs_t.ctypes.data)
    p_mem = np.int64(row(m8, t).ctypes.data)
    p_opc = np.int64(opc_t.ctypes.data)
    p_st = np.int64(st_t.ctypes.data)
    p_ctr = np.int64(ctr_t.ctypes.data)
    ctx[CTX_ENTRY_FN] = np.int64(jt.entry_fn.ctypes.data)
    ctx[CTX_ENTRY_BLK] = np.int64(jt.entry_blk.ctypes.data)
    ctx[CTX_ST] = p_st
    ctx[CTX_CTR] = p_ctr
    status = RUN_CHUNK
    err = 0
    err_addr = 0
    while True:
        u = ctx[CTX_UNMARKED] - 1
        if u >= 0 and pc != base + 4 * u:
            if jt.entry_fn[u] != 0:
                dec_t[2 * u] = OP_ENTRY
            ctx[CTX_UNMARKED] = 0
        # the interpreter's boundary: interrupt controller, end of the slice, output buffer
        next_event = min(st_t[S_IRQ_CHECK], stop)
        if cyc >= next_event:
            if cyc >= st_t[S_IRQ_CHECK]:
                pc, cyc = irq_event(st_t, ctr_t, pc, cyc)
                err = fetch_error(pc, base, code, size)
                if err != 0:
                    err_addr = pc
                    break
            if cyc >= stop:
                status = RUN_MAX_CYCLES if (budget >= 0 and cyc >= budget) else RUN_CHUNK
                break
            next_event = min(st_t[S_IRQ_CHECK], stop)
        if st_t[S_OUT_LEN] >= out_limit:
            status = RUN_OUTPUT
            break
        i = (pc - base) >> 2
        fn = jt.entry_fn[i]
        step_to = -1  # where the interpreter runs to next (-1: one instruction, below)
        limited = False  # a region stopped short of the next event: the interpreter runs up to it
        if fn != 0:
            x = call_region(fn, p_ctx, p_regs, p_mem, p_opc, cyc, next_event, jt.entry_blk[i])
            ctx[CTX_CALLS] += 1
            pc = ctx[CTX_PC]
            cyc = ctx[CTX_CYC]
            if x == X_JUMP:
                continue
            if x == X_LIMIT:
                # the next block could pass the event: the interpreter runs up to it (on the chip,
                # the end of every quantum)
                ctx[CTX_LIMITS] += 1
                step_to = next_event
                limited = True
        else:
            left = jt.tmap[i]
            h = jt.hot[i]
            if left != 0:
                # inside a translated block (after an event): the interpreter runs at most the rest
                # of it (each instruction takes a cycle or more), unless control returns here often
                # (an interrupted polling loop)
                ctx[CTX_MIDBLOCK] += 1
                if h > NEVER_TRANSLATE:
                    h += 1
                    jt.hot[i] = h
                    if h >= threshold * MIDBLOCK_FACTOR:
                        status = RUN_TRANSLATE
                        break
                step_to = min(next_event, cyc + left)
            else:
                if h > NEVER_TRANSLATE:
                    h += 1
                    jt.hot[i] = h
                    if h >= threshold:
                        status = RUN_TRANSLATE
                        break
                if stretch > 0:  # auto: stretch cycles at the interpreter's speed
                    step_to = min(stop, cyc + stretch)
        ahead = -1  # the word after a load or store the interpreter runs on from (see below)
        i = (pc - base) >> 2
        word = np.int64(m32[t, i]) & M32 if 0 <= pc - base < code else 0
        if (
            limited
            and word == _NOP
            and 0 <= pc - base < code
            and cyc < st_t[S_IRQ_CHECK]
            and st_t[S_PROF_STRIDE] == 0
            and dec_t[2 * i] != OP_BREAK
        ):
            # a `nop` before the next event, executed as the interpreter executes it (counted as an
            # ADDI in its word's bank, the sink register written, one cycle) without an interpreter
            # call: an interrupt entry has the controller look again one cycle later, inside the
            # vector's first instruction (a `nop`, which the RTL replays), so every entry leaves
            # the vector's region before it (a sleeping chip's tick makes one)
            opc_t[(np.uint64(ADDI) << np.uint64(1)) | (np.uint64(i) & np.uint64(1))] += 1
            regs_t[SINK] = regs_t[0]
            pc += 4
            cyc += SINGLE_CYCLES
            ctx[CTX_STEPS] += 1
            ctx[CTX_NOPS] += 1
            continue
        if (step_to < 0 or limited) and (
            0 <= pc - base < code and cyc < st_t[S_IRQ_CHECK] and st_t[S_PROF_STRIDE] == 0 and dec_t[2 * i] != OP_BREAK
        ):
            # a device register's load or store, the first instruction the interpreter would run:
            # made here as the interpreter makes it (no event is due before it; the events after
            # it are this loop's next turn), without an interpreter call (a sleeping chip's tick
            # makes about eight)
            done, dstatus, derr, daddr, npc, ncyc = device_step(
                st_t, ctr_t, row(out, t), opc_t, regs_t, word, i, pc, cyc, base, size
            )
            if done:
                ctx[CTX_STEPS] += 1
                ctx[CTX_DEVICE] += 1
                pc = npc
                cyc = ncyc
                if derr != 0:
                    err = derr
                    err_addr = daddr
                    break
                if dstatus != RUN_CHUNK:
                    status = dstatus  # an exit store
                    break
                continue
            if dstatus == RUN_NI:
                # the chip loop performs it: stop before it as the interpreter does, with the word's
                # predecoded row for the chip loop to read (the mark goes back when the core has left)
                ctx[CTX_STEPS] += 1
                ctx[CTX_DEVICE] += 1
                if dec_t[2 * i] == OP_ENTRY:
                    dec_t[2 * i] = 0
                    ctx[CTX_UNMARKED] = i + 1
                if dec_t[2 * i] == 0:
                    iu = np.uint64(i)
                    decode_word(m32[t, iu], dec_t, iu)  # (as run_cores calls it: one compiled decode_word)
                status = RUN_NI
                break
        if step_to < 0:
            # one instruction by the interpreter (two for a trap: its shadow runs before the vector)
            step_to = cyc + 1
            if (word & 0xFFF) == _JAL_X0_OPCODE and (
                (word >> 12) == 0 or (word == 0xFFDFF06F and i > 0 and (np.int64(m32[t, i - 1]) & M32) == _NOP)
            ):
                step_to = next_event  # an idle loop: the interpreter skips its iterations up to the event
            elif (word & 0x5F) == _LOAD_STORE_OPCODE and (pc - base) + 4 < code:
                # a load or store (a device access, mostly) goes on at the next word: when that word
                # lies inside a translated block without starting one, the interpreter also runs
                # the rest of that block in the same call, as the loop would do next (one call and
                # one turn of the loop less per access; the arrival there is counted below), unless
                # this arrival would make it hot
                left = jt.tmap[i + 1]
                if left != 0 and jt.entry_fn[i + 1] == 0 and jt.hot[i + 1] + 1 < threshold * MIDBLOCK_FACTOR:
                    ahead = i + 1
                    step_to = min(next_event, cyc + 1 + left)  # each instruction takes a cycle or more
            ctx[CTX_STEPS] += 1
        st_t[S_PC] = pc
        st_t[S_CYCLE] = cyc
        stores = st_t[S_CODE_STORES]
        i = (pc - base) >> 2
        if 0 <= pc - base < code and dec_t[2 * i] == OP_ENTRY:
            dec_t[2 * i] = 0  # the interpreter starts with this block's first instruction
            ctx[CTX_UNMARKED] = i + 1
        was = pc
        run_cores(core, tiles, step_to)
        pc = st_t[S_PC]
        cyc = st_t[S_CYCLE]
        status = st_t[S_RUN]
        if ahead >= 0 and pc != was:  # the access executed (no stop before it): the next word was reached
            ctx[CTX_MIDBLOCK] += 1
            if jt.hot[ahead] > NEVER_TRANSLATE:
                jt.hot[ahead] += 1
        if st_t[S_CODE_STORES] != stores:
            forget_if_changed(jt, row(m32, t), dec_t)  # the interpreter stored into the loaded code
        if status == RUN_ENTRY:
            status = RUN_CHUNK  # at a translated block: the loop calls it
        if status != RUN_CHUNK:
            return
    if err != 0:
        status = RUN_ERROR
        st_t[S_ERR] = err
        st_t[S_ERR_PC] = pc
        st_t[S_ERR_ADDR] = err_addr
        wi = (pc - base) >> 2
        st_t[S_ERR_INSN] = m32[t, wi] & M32 if 0 <= wi < size >> 2 else 0
    st_t[S_PC] = pc & M32
    st_t[S_CYCLE] = cyc
    st_t[S_RUN] = status


__all__ = [
    "CTX_CYC",
    "CTX_DEVICE",
    "CTX_FLUSHES",
    "CTX_NOPS",
    "CTX_PC",
    "CTX_SIZE",
    "ERR_FETCH_DATA",
    "NEVER_TRANSLATE",
    "RUN_TRANSLATE",
    "X_JUMP",
    "X_LIMIT",
    "X_SIDE",
    "JitArrays",
    "empty_tables",
    "forget_if_changed",
    "forget_translations",
    "run_translated",
    "set_table_copies",
    "set_tables",
]
