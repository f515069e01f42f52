"""Every computational instruction on edge values against a reference written from the RISC-V spec.

The reference below works on Python integers (no shared code with the numba core); each case
runs one instruction between two registers loaded with edge values and compares the result.
"""

import itertools

import pytest

import rv32_asm as A
from core_harness import exit_with, run_words

M = 0xFFFFFFFF
EDGE = [0, 1, 2, 0x7FFFFFFF, 0x80000000, 0xFFFFFFFF, 0xFFFFFFFE, 31, 32, 0x12345678, 0x8000_0001, 0x0000FFFF]


def signed(v: int) -> int:
    v &= M
    return v - (1 << 32) if v & 0x80000000 else v


REFERENCE = {
    "add": lambda a, b: a + b,
    "sub": lambda a, b: a - b,
    "sll": lambda a, b: a << (b & 31),
    "slt": lambda a, b: int(signed(a) < signed(b)),
    "sltu": lambda a, b: int(a < b),
    "xor": lambda a, b: a ^ b,
    "srl": lambda a, b: a >> (b & 31),
    "sra": lambda a, b: signed(a) >> (b & 31),
    "or": lambda a, b: a | b,
    "and": lambda a, b: a & b,
    "mul": lambda a, b: a * b,
    "mulh": lambda a, b: (signed(a) * signed(b)) >> 32,
    "mulhu": lambda a, b: (a * b) >> 32,
    "mulhsu": lambda a, b: (signed(a) * b) >> 32,
}
IMM_REFERENCE = {
    "addi": lambda a, i: a + i,
    "slti": lambda a, i: int(signed(a) < i),
    "sltiu": lambda a, i: int(a < (i & M)),
    "xori": lambda a, i: a ^ i,
    "ori": lambda a, i: a | i,
    "andi": lambda a, i: a & i,
}
IMMS = [0, 1, -1, 2047, -2048, 0x7FF, -2]


def run_one(insn: int, a: int, b: int) -> int:
    words = [*A.li(11, a), *A.li(12, b), insn, *exit_with(10)]
    _, result = run_words(words)
    return result.exit_code & M


@pytest.mark.filterwarnings("ignore::robosoc.chip.single.MulhsuErratum")
@pytest.mark.parametrize("name", list(REFERENCE))
def test_register_register_ops(name):
    for a, b in itertools.product(EDGE, EDGE):
        want = REFERENCE[name](a, b) & M
        assert run_one(A.r(name, 10, 11, 12), a, b) == want, (name, hex(a), hex(b))


@pytest.mark.parametrize("name", list(IMM_REFERENCE))
def test_register_immediate_ops(name):
    for a, i in itertools.product(EDGE, IMMS):
        want = IMM_REFERENCE[name](a, i) & M
        assert run_one(A.i(name, 10, 11, i), a, 0) == want, (name, hex(a), i)


@pytest.mark.parametrize("name,ref", [("slli", lambda a, s: a << s), ("srli", lambda a, s: a >> s),
                                      ("srai", lambda a, s: signed(a) >> s)])  # fmt: skip
def test_shift_immediates(name, ref):
    for a, s in itertools.product(EDGE, [0, 1, 15, 16, 31]):
        assert run_one(A.shift(name, 10, 11, s), a, 0) == ref(a, s) & M, (name, hex(a), s)


def test_writes_to_x0_are_discarded():
    words = [*A.li(11, 5), A.r("add", 0, 11, 11), A.i("addi", 0, 0, 7), A.r("add", 10, 0, 0), *exit_with(10)]
    _, result = run_words(words)
    assert result.exit_code == 0


def test_lui_auipc_jal_jalr_link_values():
    base = 0x40000000
    words = [
        A.lui(10, 0xFFFFF),  # 0: a0 = 0xfffff000
        A.auipc(11, 1),  # 4: a1 = 4 + 0x1000 + base
        A.jal(12, 8),  # 8: a2 = 12, skips the next word
        A.i("addi", 10, 0, 0),  # 12: skipped
        A.auipc(13, 0),  # 16
        A.jalr(14, 13, 9),  # 20: target (16 + 9) & ~1 = 24; a4 = 24
        *exit_with(0),
    ]
    soc, _ = run_words(words)
    regs = [int(v) & M for v in soc.regs]
    assert regs[10] == 0xFFFFF000
    assert regs[11] == base + 4 + 0x1000
    assert regs[12] == base + 12
    assert regs[14] == base + 24


def test_loads_sign_and_zero_extend_and_stores_write_only_their_bytes():
    data = 0x40008000
    words = [
        *A.li(5, data),
        *A.li(6, 0x8081F2F3),
        A.store("sw", 6, 5, 0),
        A.load("lb", 10, 5, 0),  # 0xf3 -> -13
        A.load("lbu", 11, 5, 1),  # 0xf2
        A.load("lh", 12, 5, 2),  # 0x8081 -> negative
        A.load("lhu", 13, 5, 2),
        *A.li(7, 0x11223344),
        A.store("sb", 7, 5, 1),  # byte 1 <- 0x44
        A.store("sh", 7, 5, 2),  # bytes 2,3 <- 0x3344
        A.load("lw", 14, 5, 0),
        *exit_with(0),
    ]
    soc, _ = run_words(words)
    regs = [int(v) & M for v in soc.regs]
    assert regs[10] == (-13) & M and regs[11] == 0xF2
    assert regs[12] == 0xFFFF8081 and regs[13] == 0x8081
    assert regs[14] == 0x334444F3
