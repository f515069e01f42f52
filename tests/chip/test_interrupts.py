"""Timers, interrupt entry/return and SYSTEM traps against the rules of platform.md §2-§3.

Expected cycles are derived by hand from the rules: a request that becomes pending in cycle t is
acknowledged at the earliest in cycle t + 3, only while a single-cycle instruction executes; the
vector's first instruction then executes in t + 6 and t + 7, the second in t + 8.
"""

import pytest

import rv32_asm as A
from core_harness import exit_with, make_soc
from robosoc.chip.single import CycleBudgetExceeded

SRAM = 0x40000000
T0, T3, T4 = 5, 28, 29  # TIMER0 base, IRQ controller base, timer-cause block base
A1, A2, A3, A4, A5 = 11, 12, 13, 14, 15
TIMER0 = 0xE1024000
IRQ = 0xF0000000
TCAUSE = 0xE1020800  # -0x400 TIMERCAUSE, +0 INV, +0x400 MASK


def sw_const(base_reg: int, offset: int, value: int, tmp: int = 6) -> list[int]:
    return [*A.li(tmp, value), A.store("sw", tmp, base_reg, offset)]


def program(sled: list[int], handler: list[int], ocr: int, vector_offset: int = 0x800) -> list[int]:
    """Arm 'TIMER1 >= OCR' (TIMER1 = cycle - 2 with the reset prescaler), run ``sled``, exit.

    ``handler`` is placed at SRAM + vector_offset.  a5 gets the TIMER0 value read just before
    the sled, so the sled starts in cycle a5 + 4.
    """
    setup = [*A.li(T0, TIMER0), *A.li(T3, IRQ), *A.li(T4, TCAUSE)]
    setup += sw_const(T3, 0x00, SRAM + vector_offset)  # IRQ_VECTOR
    setup += sw_const(T0, 0x430, ocr)  # TIMER1_OCR
    setup += sw_const(T4, 0x000, 0x08)  # TIMERCAUSE_INV: line = not (TIMER1 < OCR)
    setup += sw_const(T4, 0x400, 0x08)  # TIMERMASK
    setup += sw_const(T3, 0x20, 0x01)  # IRQ_MASK: the SoC peripheral line
    setup += sw_const(T3, 0x30, 0x01)  # IRQ_STATUS: enable
    words = [*setup, A.load("lw", A5, T0, 0), *sled, *exit_with(0)]
    assert len(words) * 4 <= vector_offset
    words += [A.NOP] * (vector_offset // 4 - len(words))
    return words + handler


def sled_address(words_before_sled: int) -> int:
    return SRAM + 4 * words_before_sled


HANDLER_RECORD = [
    A.i("addi", A1, A1, 1),  # first vector instruction: executes twice
    A.load("lw", A2, T0, 0),  # TIMER0 when the second vector instruction starts, minus 1
    A.load("lw", A3, T3, 0x40),  # IRQ_EPC
    *exit_with(0),
]


def run_program(words: list[int], mul: bool = True):
    soc = make_soc(words, mul=mul)
    result = soc.run(max_cycles=200_000)
    regs = [int(v) & 0xFFFFFFFF for v in soc.regs]
    return soc, result, regs


def test_timer_interrupt_entry_cycles_and_epc():
    ocr = 300
    sled = [A.NOP] * 400
    words = program(sled, HANDLER_RECORD, ocr)
    _, result, regs = run_program(words)
    assert result.counters["interrupts"] == 1
    t = ocr + 2  # TIMER1 counts from its first pulse in cycle 2: 'TIMER1 >= OCR' rises in 302
    assert regs[A1] == 2, "the first vector instruction executes twice"
    assert regs[A2] == t + 8 - 1, "the second vector instruction starts in t + 8"
    sled_start_cycle = regs[A5] + 4
    sled_start = SRAM + 4 * words.index(A.load("lw", A5, T0, 0)) + 4
    acked_nop = sled_start + 4 * (t + 3 - sled_start_cycle)  # executing in the ack cycle t + 3
    assert regs[A3] == acked_nop + 4 + 4, "EPC = address of the squashed instruction + 4"


def test_acknowledge_waits_for_a_single_cycle_instruction():
    ocr = 300
    # loads from SRAM cover cycles up to well past t + 3; then nops
    sled = [A.load("lw", 7, 2, 0)] * 120 + [A.NOP] * 100
    words = program([*A.li(2, SRAM + 0x100), *sled], HANDLER_RECORD, ocr)
    _, _, regs = run_program(words)
    sled_start_cycle = regs[A5] + 4  # li (2 cycles), then 120 loads of 3 cycles, then nops
    first_nop_cycle = sled_start_cycle + 2 + 3 * 120
    assert first_nop_cycle > ocr + 2 + 3
    assert regs[A2] == first_nop_cycle + 5 - 1  # ack at the first nop: vector at +3, +4, second at +5


def test_no_acknowledge_during_a_multiply():
    ocr = 300
    # multiplies of 37 cycles (rs2 = 0xffffffff) straddle t + 3; then nops
    sled = [*A.li(7, 0xFFFFFFFF), *[A.r("mul", 8, 7, 7)] * 12, *[A.NOP] * 100]
    words = program(sled, HANDLER_RECORD, ocr)
    _, _, regs = run_program(words, mul=True)
    first_nop_cycle = regs[A5] + 4 + 2 + 37 * 12
    assert first_nop_cycle > ocr + 2 + 3
    assert regs[A2] == first_nop_cycle + 5 - 1


def test_interrupt_return_resumes_exactly_once():
    ocr = 250
    n = 300
    sled = [A.i("addi", A4, A4, 1)] * n
    handler = [
        A.NOP,  # executes twice
        A.i("addi", A1, A1, 1),
        *sw_const(T4, 0x400, 0x00),  # TIMERMASK = 0: the line drops
        A.load("lw", 27, T3, 0x40),  # s11 = IRQ_EPC
        A.i("addi", 27, 27, -4),
        A.i("addi", 6, 0, 1),
        A.store("sw", 6, T3, 0x30),  # IRQ_STATUS = 1
        A.jalr(0, 27, 0),
    ]
    _, result, regs = run_program(program(sled, handler, ocr))
    assert result.counters["interrupts"] == 1
    assert regs[A1] == 1
    assert regs[A4] == n, "every sled instruction executed exactly once across the interrupt"


def test_interrupts_stay_off_until_status_is_set_again():
    ocr = 250
    sled = [A.i("addi", A4, A4, 1)] * 300
    handler = [
        A.NOP,
        A.i("addi", A1, A1, 1),
        A.load("lw", 27, T3, 0x40),
        A.i("addi", 27, 27, -4),
        A.jalr(0, 27, 0),  # returns without re-enabling: the line stays high
    ]
    _, result, regs = run_program(program(sled, handler, ocr))
    assert result.counters["interrupts"] == 1 and regs[A1] == 1 and regs[A4] == 300


def test_system_instructions_trap_with_shadow():
    # ecall at E: EPC = E + 8; the instruction at E + 8 runs once before the handler,
    # the handler returns to E + 4.
    body = [
        *A.li(T3, IRQ),
        *sw_const(T3, 0x00, SRAM + 0x400),
        A.ECALL,  # E
        A.i("addi", A4, A4, 1),  # E + 4
        A.i("addi", A5, A5, 1),  # E + 8: runs before the handler and again after the return
        *exit_with(0),
    ]
    e = SRAM + 4 * body.index(A.ECALL)
    handler = [
        A.NOP,
        A.load("lw", A3, T3, 0x40),
        A.i("addi", A1, A5, 0),  # a5 as seen by the handler
        A.i("addi", 27, A3, -4),
        A.jalr(0, 27, 0),
    ]
    words = body + [A.NOP] * (0x100 - len(body)) + handler
    _, result, regs = run_program(words)
    assert result.counters["traps"] == 1
    assert regs[A3] == e + 8
    assert regs[A1] == 1, "the shadow instruction executed before the handler"
    assert regs[A4] == 1 and regs[A5] == 2


def test_trap_entry_timing():
    # ecall in cycle s (1), shadow in s + 1 (1), two vector-fetch bubbles, vector instruction in
    # s + 4 and s + 5, the second vector instruction (a TIMER0 load) in s + 6: reads s + 5.
    body = [*A.li(T0, TIMER0), *A.li(T3, IRQ), *sw_const(T3, 0x00, SRAM + 0x400)]
    body += [A.load("lw", A5, T0, 0), A.ECALL, A.NOP, A.NOP, *exit_with(0)]
    handler = [A.NOP, A.load("lw", A2, T0, 0), *exit_with(0)]
    words = body + [A.NOP] * (0x100 - len(body)) + handler
    _, _, regs = run_program(words)
    s = regs[A5] + 1 + 3  # the ecall starts right after the TIMER0 load
    assert regs[A2] == s + 6 - 1


def _idle_loop_program(first: int) -> list[int]:
    """Arm the TIMER1 >= 2000 interrupt, then spin in `first; j .-4`; the handler exits."""
    handler = [A.NOP, A.load("lw", A2, T0, 0), *exit_with(A2)]
    return program([first, A.jal(0, -4)], handler, ocr=2000)


def test_idle_loop_fast_forward_changes_nothing():
    # `nop; j .-4` is skipped over in whole iterations; `addi x0, x0, 1; j .-4` has the same
    # timing but is not recognised as idle, so it runs instruction by instruction
    fast = run_program(_idle_loop_program(A.NOP))
    slow = run_program(_idle_loop_program(A.i("addi", 0, 0, 1)))
    assert fast[1].exit_code == slow[1].exit_code == fast[2][A2]
    assert fast[1].counters == slow[1].counters
    assert fast[1].counters["interrupts"] == 1


def test_jump_to_self_spins_until_the_budget():
    soc = make_soc([A.NOP, A.jal(0, 0)])
    with pytest.raises(CycleBudgetExceeded):
        soc.run(max_cycles=30_000_000)
    c = soc.counters()
    assert c["jump"] == (soc.cycle - 4) // 3
    assert 30_000_000 <= soc.cycle < 30_000_003
