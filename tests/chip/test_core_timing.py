"""Cycle counts against the rules of platform.md §1, derived by hand.

A load of TIMER0 that starts in cycle c reads c - 1, so reading TIMER0 before and after a
sequence of instructions costing K cycles gives a difference of K + 3 (the first load's own 3).
"""

import pytest

import rv32_asm as A
from core_harness import exit_with, run_words

T0 = 5  # t0 holds the TIMER0 address
TIMER0 = 0xE1024000


def measure(seq: list[int], setup: list[int] | None = None, mul: bool = True) -> int:
    """Cycles taken by ``seq``, measured with two TIMER0 reads around it."""
    words = [*A.li(T0, TIMER0), *(setup or []), A.load("lw", 10, T0, 0), *seq, A.load("lw", 11, T0, 0)]
    words += [A.r("sub", 10, 11, 10), *exit_with(10)]
    _, result = run_words(words, mul=mul)
    return result.exit_code - 3


def test_pipeline_fill_first_instruction_executes_in_cycle_3():
    # lui t0 executes in cycle 3, the load starts in cycle 4 and reads 3
    _, result = run_words([A.lui(T0, TIMER0 >> 12), A.load("lw", 10, T0, 0), *exit_with(10)])
    assert result.exit_code == 3
    # lui(3) lw(4..6) lui(7) addi(8) sw(9..11): the run ends after cycle 11
    assert result.cycles == 12


@pytest.mark.parametrize(
    "seq,cycles",
    [
        ([A.i("addi", 6, 6, 1)], 1),
        ([A.r("add", 6, 6, 7), A.r("sub", 6, 6, 7), A.r("xor", 6, 6, 7), A.shift("srai", 6, 6, 3)], 4),
        ([A.i("slti", 6, 6, 1), A.r("sltu", 6, 6, 7), A.i("andi", 6, 6, 3), A.r("or", 6, 6, 7)], 4),
        ([A.lui(6, 0x12345), A.auipc(7, 1), A.FENCE], 3),
        ([A.load("lw", 6, 2, -4)], 3),
        ([A.load("lbu", 6, 2, -1), A.load("lh", 6, 2, -2)], 6),
        ([A.store("sw", 6, 2, -8), A.store("sb", 6, 2, -9), A.store("sh", 6, 2, -12)], 9),
        ([A.load("lw", 6, 2, -4), A.i("addi", 7, 6, 1)], 4),  # a dependent use costs nothing extra
        ([A.branch("bne", 0, 0, 8), A.NOP], 2),  # not taken: 1, then the nop
        ([A.branch("beq", 0, 0, 8), A.NOP], 3),  # taken over the nop: 3
        ([A.branch("beq", 0, 0, 4)], 3),  # taken to pc + 4 is still taken
        ([A.jal(0, 4)], 3),
        ([A.jal(1, 8), A.NOP], 3),
    ],
)
def test_instruction_costs(seq, cycles):
    setup = [*A.li(2, 0x40008000)]  # sp for the memory cases
    assert measure(seq, setup) == cycles


def test_jalr_costs_three():
    # auipc t1, 0 (1) ; jalr x0, 12(t1) -> skips one nop (3)
    assert measure([A.auipc(6, 0), A.jalr(0, 6, 12), A.NOP]) == 4


# platform.md §1: measured multiplier latencies on the RTL
MUL_LATENCY = {
    0: 16, 1: 16, 2: 16, 3: 16, 0x10: 16, 0x100: 16, 0x10000: 16, 0x80000000: 16,
    0xF: 19, 0x11: 19, 0xFF: 22, 0xFFFF: 28,
    0x55555555: 37, 0x7FFFFFFF: 37, 0xFFFFFFFF: 37, 0x12345678: 37,
}  # fmt: skip


@pytest.mark.parametrize("rs2", list(MUL_LATENCY))
@pytest.mark.parametrize("op", ["mul", "mulh", "mulhu"])
def test_multiplier_latency_table(op, rs2):
    setup = [*A.li(6, 0x7FFFFFFF), *A.li(7, rs2)]
    assert measure([A.r(op, 8, 6, 7)], setup) == MUL_LATENCY[rs2]


def test_multiplier_latency_ignores_rs1_and_back_to_back_adds_nothing():
    setup = [*A.li(6, 0xFFFFFFFF), *A.li(7, 0xFF)]
    assert measure([A.r("mul", 8, 7, 6)], setup) == 37  # rs2 = 0xffffffff
    assert measure([A.r("mul", 8, 6, 7)], setup) == 22  # rs2 = 0xff, rs1 dense
    assert measure([A.r("mul", 8, 6, 7), A.r("mul", 9, 6, 7)], setup) == 44


def test_cycle_total_is_fill_plus_instructions_plus_stalls():
    words = [*A.li(2, 0x40008000), *A.li(6, 0x1234), *A.li(7, 10)]
    loop = len(words)
    words += [A.store("sw", 6, 2, 0), A.load("lw", 8, 2, 0), A.r("mul", 8, 8, 6), A.i("addi", 7, 7, -1)]
    words += [A.branch("bne", 7, 0, (loop - len(words)) * 4), *exit_with(8)]
    _, result = run_words(words)
    c = result.counters
    assert c["taken_branches"] == 9 and c["branch"] == 10
    assert c["memory"] == 21  # 10 sw + 10 lw + the exit store
    assert c["mul"] == 10 and c["mul_cycle"] == 10 * (25 - 1)  # rs2 = 0x1234: 25 cycles, derived below
    stalls = c["branch_cycle"] + c["memory_cycle"] + c["mul_cycle"] + c["entry_cycle"]
    assert c["cycles"] == 3 + c["instructions"] + stalls


def test_mul_latency_of_0x1234_by_hand():
    # 0x1234 has bits 2, 4, 5, 9 and 12 set.  One step is taken at every counter position it
    # visits: 0..13 one by one (each window c..c+3 for c <= 12 holds a set bit), then windows of
    # four zeros send it 13 -> 17 -> 21 -> 25 -> 29, then 30, 31 (the last step).
    # Visits: 14 + 3 (17, 21, 25) + 3 (29, 30, 31) = 20 steps: latency 5 + 20 = 25 cycles.
    setup = [*A.li(6, 3), *A.li(7, 0x1234)]
    assert measure([A.r("mul", 8, 6, 7)], setup) == 25


# Every conditional branch kind, taken and not taken, on signed/unsigned edge operands.  Whether it
# is taken comes from the RISC-V definitions on Python integers (no code shared with the core); the
# cost from platform.md §1: 1 cycle not taken, 3 taken (also when the target is pc + 4).
def _signed(v: int) -> int:
    v &= 0xFFFFFFFF
    return v - (1 << 32) if v & 0x80000000 else v


BRANCH_RULES = {
    "beq": lambda a, b: a == b,
    "bne": lambda a, b: a != b,
    "blt": lambda a, b: _signed(a) < _signed(b),
    "bge": lambda a, b: _signed(a) >= _signed(b),
    "bltu": lambda a, b: a < b,
    "bgeu": lambda a, b: a >= b,
}
BRANCH_OPERANDS = [
    (0, 0), (1, 2), (2, 1), (5, 5),
    (0xFFFFFFFF, 0), (0, 0xFFFFFFFF),  # -1 against 0: signed and unsigned orders disagree
    (0x7FFFFFFF, 0x80000000), (0x80000000, 0x7FFFFFFF),  # INT_MAX against INT_MIN
    (0x80000000, 0x80000000), (0xFFFFFFFF, 0xFFFFFFFE), (0xFFFFFFFE, 0xFFFFFFFF),
]  # fmt: skip


def test_branch_operands_cover_both_outcomes_of_every_kind():
    for name, rule in BRANCH_RULES.items():
        assert {rule(a, b) for a, b in BRANCH_OPERANDS} == {True, False}, name


@pytest.mark.parametrize("name", list(BRANCH_RULES))
def test_every_branch_kind_taken_and_not_taken_costs_and_outcome(name):
    for a, b in BRANCH_OPERANDS:
        taken = BRANCH_RULES[name](a, b)
        setup = [*A.li(6, a), *A.li(7, b), A.i("addi", 9, 0, 0)]
        # over one instruction: taken skips `addi x9, x0, 1` (3), not taken runs it (1 + 1)
        words = [*A.li(T0, TIMER0), *setup, A.load("lw", 10, T0, 0), A.branch(name, 6, 7, 8), A.i("addi", 9, 0, 1)]
        words += [A.load("lw", 11, T0, 0), A.r("sub", 10, 11, 10), *exit_with(10)]
        soc, result = run_words(words)
        cycles = result.exit_code - 3
        assert (cycles, int(soc.state.regs[0, 9])) == ((3, 0) if taken else (2, 1)), (name, hex(a), hex(b))
        c = result.counters
        assert c["branch"] == 1 and c["taken_branches"] == int(taken), (name, hex(a), hex(b))
        assert c["branch_cycle"] == (2 if taken else 0), (name, hex(a), hex(b))
        # to pc + 4: the same instruction follows either way, but a taken branch still costs 3
        assert measure([A.branch(name, 6, 7, 4)], setup) == (3 if taken else 1), (name, hex(a), hex(b))


@pytest.mark.parametrize("name", list(BRANCH_RULES))
def test_backward_branch_loop_costs_three_per_taken_iteration(name):
    # `loop: addi x6, x6, 1; b<cond> back to loop` with x6 counting up from 0 against x7 = 4: the
    # iterations come from the rule; each costs 1 (addi) + 3 (taken) except the last (1 + 1).
    rule = BRANCH_RULES[name]
    rs1, rs2 = (7, 6) if name in ("bge", "bgeu") else (6, 7)  # keep looping while x6 < 4 or x6 <= 4
    x6, iterations = 0, 0
    while True:
        x6, iterations = x6 + 1, iterations + 1
        regs = {6: x6, 7: 4}
        if not rule(regs[rs1], regs[rs2]):
            break
    want = iterations * 1 + (iterations - 1) * 3 + 1
    assert measure([A.i("addi", 6, 6, 1), A.branch(name, rs1, rs2, -4)], [*A.li(6, 0), *A.li(7, 4)]) == want
