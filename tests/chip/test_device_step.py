"""The dispatch loop's own device accesses (``kernels.core.device_step``) are the interpreter's.

A translated core's loads and stores of device registers used to be one interpreter call each;
the dispatch loop now makes them itself.  Checked here instruction by instruction against
``run_cores`` running the same single instruction (every array of the core compared), and on a
sleeping chip (``firmware/bench/sleepy_tick.c``) whose every tick makes such accesses, against
the interpreted chip: cycles, exit codes, counters per tile and per task (of which the energies are made).
"""

from __future__ import annotations

import numpy as np
import pytest

import rv32_asm as A
from core_harness import exit_with, make_soc
from robosoc.chip.mpsoc import MPSoC
from robosoc.config.chip import ChipConfig
from robosoc.firmware import FIRMWARE_DIR
from robosoc.kernels.core import CoreArrays, device_step, run_cores
from robosoc.kernels.core_layout import (
    RUN_CHUNK,
    RUN_ERROR,
    RUN_EXIT,
    S_CYCLE,
    S_ERR,
    S_ERR_ADDR,
    S_IRQ_CHECK,
    S_MEM_BASE,
    S_MEM_SIZE,
    S_PC,
    S_RUN,
)
from robosoc.kernels.dev_irq import irq_event
from robosoc.kernels.jit_dispatch import CTX_DEVICE, CTX_NOPS
from robosoc.program.elf import load_elf
from robosoc.toolchain import build_elf

T0, T1, T2, T3, A0, A1, A2 = 5, 6, 7, 28, 10, 11, 12
SRAM = 0x40000000
TICKS = 3


def _copy(core: CoreArrays) -> CoreArrays:
    return CoreArrays(*(a.copy() for a in core))


def _same(a: CoreArrays, b: CoreArrays) -> None:
    for name, x, y in zip(CoreArrays._fields, a, b, strict=True):
        np.testing.assert_array_equal(x, y, err_msg=name)


def _walk(words: list[int]) -> tuple[int, int]:
    """Run ``words`` one instruction at a time; at each, compare ``device_step`` (and the dispatch
    loop's next turn: the interrupt event, if due) with ``run_cores`` running that instruction
    alone.  Returns (device accesses made by device_step, instructions it declined)."""
    soc = make_soc(words)
    core = soc.state.arrays()
    tiles = np.zeros(1, dtype=np.int64)
    made = declined = 0
    for _ in range(200):
        st = core.st
        pc, cyc = int(st[0, S_PC]), int(st[0, S_CYCLE])
        assert cyc < st[0, S_IRQ_CHECK]  # device_step's condition (the dispatch loop checks it)
        mine = _copy(core)
        before = _copy(core)
        word = int(core.m32[0, (pc - SRAM) >> 2])
        done, status, err, err_addr, npc, ncyc = device_step(
            mine.st[0], mine.ctr[0], mine.out[0], mine.opc[0], mine.regs[0], word, (pc - SRAM) >> 2, pc, cyc,
            int(st[0, S_MEM_BASE]), int(st[0, S_MEM_SIZE]),
        )  # fmt: skip
        run_cores(core, tiles, cyc + 1)  # the reference: the interpreter runs this one instruction
        if not done:
            declined += 1
            _same(mine, before)  # nothing changed: the interpreter made (or refused) the access
        else:
            made += 1
            if err != 0:
                assert status == RUN_ERROR and core.st[0, S_RUN] == RUN_ERROR
                assert (err, err_addr) == (core.st[0, S_ERR], core.st[0, S_ERR_ADDR])
                assert (npc, ncyc) == (core.st[0, S_PC], core.st[0, S_CYCLE])
                return made, declined
            # the dispatch loop's next turn: an interrupt event due after the access
            if ncyc >= mine.st[0, S_IRQ_CHECK]:
                npc, ncyc = irq_event(mine.st[0], mine.ctr[0], npc, ncyc)
            mine.st[0, S_PC] = npc
            mine.st[0, S_CYCLE] = ncyc
            mine.st[0, S_RUN] = core.st[0, S_RUN]  # (the interpreter's return status, checked below)
            assert core.st[0, S_RUN] == (RUN_EXIT if status == RUN_EXIT else RUN_CHUNK)
            mine.dec[0, :] = core.dec[0, :]  # the interpreter predecoded the word; device_step needs not
            _same(mine, core)
            if status == RUN_EXIT:
                return made, declined
        if core.st[0, S_RUN] != RUN_CHUNK:
            return made, declined
    raise AssertionError("the program did not end")


def test_device_accesses_are_the_interpreters_one_instruction_at_a_time() -> None:
    words = [
        *A.li(T0, 0xE1024410),  # TIMER1_PRE
        A.i("addi", T1, 0, 2),
        A.store("sw", T1, T0, 0),  # a timer store (moves the timer's line)
        A.load("lw", T2, T0, -0x10),  # TIMER1
        *A.li(T3, 0xE1024000),
        A.load("lw", A1, T3, 0),  # TIMER0
        *A.li(A0, 0xF0000000),
        A.load("lw", A1, A0, 0x10),  # IRQ_CAUSE
        A.store("sw", T1, A0, 0x20),  # IRQ_MASK
        A.store("sw", 0, A0, 0x30),  # IRQ_STATUS from x0
        A.load("lw", 0, A0, 0x30),  # into x0 (the sink)
        *A.li(A2, 0xE1020800),  # TIMERCAUSE_INV
        A.load("lw", A1, A2, 0),
        A.i("xori", A1, A1, 4),
        A.store("sw", A1, A2, 0),
        A.i("addi", A1, 0, 0x41),
        A.store("sw", A1, A0, 0xD0),  # the debug port (output)
        *exit_with(0),
    ]
    made, declined = _walk(words)
    assert made == 11  # every device load and store above, and the exit store
    assert declined == len(words) - made


def test_a_misaligned_device_access_is_left_to_the_interpreter() -> None:
    words = [*A.li(T0, 0xE1024000), A.load("lw", T1, T0, 2), *exit_with(0)]
    made, declined = _walk(words)
    assert (made, declined) == (0, len(A.li(T0, 0xE1024000)) + 1)  # the walk ends at the interpreter's error


@pytest.mark.parametrize(
    "access",
    [A.load("lw", A1, T0, 0), A.store("sw", A1, T0, 0)],
    ids=["load", "store"],
)
def test_an_unmapped_device_address_is_the_interpreters_error(access: int) -> None:
    words = [*A.li(T0, 0xE9000000), access, *exit_with(0)]
    made, _ = _walk(words)
    assert made == 1


def test_sram_accesses_are_left_to_the_interpreter() -> None:
    words = [*A.li(T0, SRAM + 0x800), A.store("sw", T0, T0, 0), A.load("lw", T1, T0, 0), *exit_with(0)]
    made, declined = _walk(words)
    assert made == 1  # the exit store only
    assert declined == len(words) - 1


def _sleeping(engine: str) -> tuple[tuple, MPSoC]:
    program = load_elf(build_elf([FIRMWARE_DIR / "bench" / "sleepy_tick.c"], mul=True, defines={"TICKS": TICKS}))
    chip = MPSoC(ChipConfig(width=2, height=2), engine=engine)
    chip.load_all(program)
    result = chip.run(max_cycles=(TICKS + 2) * 250_000)
    tiles = chip.core_tiles()
    seen = (
        result.cycles,
        result.exit_codes,
        {xy: chip.counters(xy) for xy in tiles},
        {xy: chip.task_counters(xy) for xy in tiles},  # (the energies are made from these)
    )
    return seen, chip


def test_a_sleeping_chip_on_translated_code_is_the_interpreted_one() -> None:
    reference, _ = _sleeping("interp")
    got, chip = _sleeping("jit")
    assert got == reference
    for t, translator in enumerate(chip._jit.translators):
        if translator is not None:
            # the ticks' timer acknowledgements (a load and a store each) made by the dispatch loop
            assert translator.tables().ctx[CTX_DEVICE] >= 2 * TICKS, t


def test_the_vectors_replayed_nop_run_by_the_dispatch_loop_is_the_interpreters() -> None:
    """Every interrupt entry has the controller look again one cycle later, inside the vector's
    first instruction (a `nop` the RTL replays): the region there stops before it and the dispatch
    loop executes the `nop` itself.  The whole state of every core (registers with the sink, the
    per-operation counters in both banks, cycles and the core state row) is the interpreter's."""
    _, reference = _sleeping("interp")
    _, chip = _sleeping("jit")
    for name in ("st", "ctr", "opc", "regs", "m8"):
        assert np.array_equal(getattr(chip.cores, name), getattr(reference.cores, name)), name
    nops = [translator.tables().ctx[CTX_NOPS] for translator in chip._jit.translators if translator is not None]
    assert nops and all(n >= TICKS for n in nops), nops  # one per tick's entry, at least
