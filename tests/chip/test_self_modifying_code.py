"""Self-modifying code: a store of any width into an instruction that already ran (so it sits in the
predecode table) must make the core execute the new word (platform.md, "Code and data").

Each program runs a target instruction, rewrites part of it with one SW, SH or SB, jumps back and
runs it again.  What the second pass must do is read off the new word with a decoder written here
(only ``addi rd, x0, imm`` is ever produced), independently of robosoc's decoder.
"""

from __future__ import annotations

import pytest

import rv32_asm as A
from core_harness import exit_with, run_words
from robosoc.chip.core_state import SRAM_BASE

ORIGINAL = A.i("addi", 10, 0, 11)  # target: x10 = 11


def _addi_from_x0(word: int) -> tuple[int, int]:
    """(rd, value) of ``addi rd, x0, imm`` by the RISC-V I-format (opcode 0x13, funct3 0, rs1 0)."""
    assert word & 0x7F == 0x13 and (word >> 12) & 7 == 0 and (word >> 15) & 31 == 0, hex(word)
    imm = word >> 20
    return (word >> 7) & 31, imm - 4096 if imm & 0x800 else imm


def _program(width: str, offset: int, value: int) -> tuple[list[int], int]:
    """The program and the word the target holds after the store of ``value`` at target + offset."""
    head = 8  # words before the target: li x5 (2), li x6 (2), x8 = 0, x10 = 0, x11 = 0, x12 = 0
    target = SRAM_BASE + 4 * head
    words = [*A.li(5, target + offset), *A.li(6, value)]
    words += [A.i("addi", 8, 0, 0), A.i("addi", 10, 0, 0), A.i("addi", 11, 0, 0), A.i("addi", 12, 0, 0)]
    assert len(words) == head
    words += [
        ORIGINAL,  # target
        A.shift("slli", 12, 12, 8),  # x12 = x12 << 8 | x10 (records x10 after each pass)
        A.r("or", 12, 12, 10),
        A.branch("bne", 8, 0, 20),  # second pass: to done
        A.i("addi", 8, 0, 1),
        A.store(width, 6, 5, 0),  # rewrite the target
        A.i("addi", 10, 0, 0),  # forget the first pass
        A.jal(0, -4 * 7),  # back to the target
        # done: exit with x11 << 16 | x12
        A.shift("slli", 11, 11, 16),
        A.r("or", 12, 12, 11),
        *exit_with(12),
    ]
    size = {"sb": 1, "sh": 2, "sw": 4}[width]
    mask = ((1 << (8 * size)) - 1) << (8 * offset)
    new = (ORIGINAL & ~mask) | ((value << (8 * offset)) & mask)
    return words, new & 0xFFFFFFFF


CASES = [
    ("sw", 0, A.i("addi", 10, 0, 77)),  # a whole new instruction
    ("sw", 0, A.i("addi", 11, 0, -5)),  # another destination register
    ("sh", 2, A.i("addi", 10, 0, 0x123) >> 16),  # upper half: imm[11:0] and rs1[4:1]
    ("sh", 0, (A.i("addi", 11, 0, 11) & 0xFFFF)),  # lower half: opcode, rd, funct3, rs1[0]
    ("sb", 3, A.i("addi", 10, 0, 0x5B) >> 24),  # imm[11:4]
    ("sb", 2, (A.i("addi", 10, 0, 0x7F5) >> 16) & 0xFF),  # imm[3:0] and rs1[4:1]
    ("sb", 1, (A.i("addi", 8, 0, 11) >> 8) & 0xFF),  # rd[4:1], funct3, rs1[0]: x10 becomes x8
    ("sb", 0, A.i("addi", 11, 0, 11) & 0xFF),  # opcode and rd[0]: x10 becomes x11
]


@pytest.mark.parametrize(("width", "offset", "value"), CASES)
def test_store_into_executed_code_is_executed(width: str, offset: int, value: int) -> None:
    words, new = _program(width, offset, value)
    rd, result = _addi_from_x0(new)
    assert new != ORIGINAL and rd in (8, 10, 11)  # the store changes the instruction (x8 stays non-zero)
    x10 = result if rd == 10 else 0
    x11 = result if rd == 11 else 0
    want = ((x11 << 16) | (11 << 8) | x10) & 0xFFFFFFFF  # first pass x10 = 11, second the new instruction
    soc, run = run_words(words)
    assert run.exit_code & 0xFFFFFFFF == want, (width, offset, hex(new))
    assert int.from_bytes(soc.state.read(SRAM_BASE + 32, 4), "little") == new  # the memory holds it too


@pytest.mark.parametrize("width", ["sw", "sh", "sb"])
def test_store_of_the_same_bytes_changes_nothing(width: str) -> None:
    # rewriting the target with its own bytes: the second pass repeats the first
    size = {"sb": 1, "sh": 2, "sw": 4}[width]
    words, new = _program(width, 0, ORIGINAL & ((1 << (8 * size)) - 1))
    assert new == ORIGINAL
    _, run = run_words(words)
    assert run.exit_code == (11 << 8) | 11
