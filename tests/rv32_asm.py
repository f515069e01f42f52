"""A tiny RV32 assembler for tests: encodes instructions from the RISC-V specification's formats.

It is written from the specification independently of robosoc's decoder, so tests that assemble
with it and run on the core check the decoder as well.
"""

from __future__ import annotations

R_OPS = {  # name: (funct7, funct3)
    "add": (0, 0), "sub": (0x20, 0), "sll": (0, 1), "slt": (0, 2), "sltu": (0, 3), "xor": (0, 4),
    "srl": (0, 5), "sra": (0x20, 5), "or": (0, 6), "and": (0, 7),
    "mul": (1, 0), "mulh": (1, 1), "mulhsu": (1, 2), "mulhu": (1, 3),
    "div": (1, 4), "divu": (1, 5), "rem": (1, 6), "remu": (1, 7),
}  # fmt: skip
I_OPS = {"addi": 0, "slti": 2, "sltiu": 3, "xori": 4, "ori": 6, "andi": 7}
SHIFT_OPS = {"slli": (0, 1), "srli": (0, 5), "srai": (0x20, 5)}
LOAD_OPS = {"lb": 0, "lh": 1, "lw": 2, "lbu": 4, "lhu": 5}
STORE_OPS = {"sb": 0, "sh": 1, "sw": 2}
BRANCH_OPS = {"beq": 0, "bne": 1, "blt": 4, "bge": 5, "bltu": 6, "bgeu": 7}


def r(name: str, rd: int, rs1: int, rs2: int) -> int:
    f7, f3 = R_OPS[name]
    return (f7 << 25) | (rs2 << 20) | (rs1 << 15) | (f3 << 12) | (rd << 7) | 0x33


def i(name: str, rd: int, rs1: int, imm: int) -> int:
    assert -2048 <= imm < 2048, imm
    return ((imm & 0xFFF) << 20) | (rs1 << 15) | (I_OPS[name] << 12) | (rd << 7) | 0x13


def shift(name: str, rd: int, rs1: int, shamt: int) -> int:
    f7, f3 = SHIFT_OPS[name]
    return (f7 << 25) | ((shamt & 31) << 20) | (rs1 << 15) | (f3 << 12) | (rd << 7) | 0x13


def load(name: str, rd: int, rs1: int, imm: int) -> int:
    return ((imm & 0xFFF) << 20) | (rs1 << 15) | (LOAD_OPS[name] << 12) | (rd << 7) | 0x03


def store(name: str, rs2: int, rs1: int, imm: int) -> int:
    imm &= 0xFFF
    return ((imm >> 5) << 25) | (rs2 << 20) | (rs1 << 15) | (STORE_OPS[name] << 12) | ((imm & 31) << 7) | 0x23


def branch(name: str, rs1: int, rs2: int, offset: int) -> int:
    assert offset % 2 == 0 and -4096 <= offset < 4096
    o = offset & 0x1FFF
    return (
        ((o >> 12) << 31) | (((o >> 5) & 0x3F) << 25) | (rs2 << 20) | (rs1 << 15) | (BRANCH_OPS[name] << 12)
        | (((o >> 1) & 0xF) << 8) | (((o >> 11) & 1) << 7) | 0x63
    )  # fmt: skip


def lui(rd: int, imm20: int) -> int:
    return ((imm20 & 0xFFFFF) << 12) | (rd << 7) | 0x37


def auipc(rd: int, imm20: int) -> int:
    return ((imm20 & 0xFFFFF) << 12) | (rd << 7) | 0x17


def jal(rd: int, offset: int) -> int:
    o = offset & 0x1FFFFF
    return (
        ((o >> 20) << 31) | (((o >> 1) & 0x3FF) << 21) | (((o >> 11) & 1) << 20) | (((o >> 12) & 0xFF) << 12)
        | (rd << 7) | 0x6F
    )  # fmt: skip


def jalr(rd: int, rs1: int, imm: int) -> int:
    return ((imm & 0xFFF) << 20) | (rs1 << 15) | (rd << 7) | 0x67


NOP = i("addi", 0, 0, 0)
ECALL = 0x00000073
EBREAK = 0x00100073
FENCE = 0x0FF0000F


def li(rd: int, value: int) -> list[int]:
    """Load a 32-bit constant: LUI + ADDI (always two instructions, so timing is predictable)."""
    value &= 0xFFFFFFFF
    lo = value & 0xFFF
    if lo >= 0x800:
        lo -= 0x1000
    hi = ((value - lo) >> 12) & 0xFFFFF
    return [lui(rd, hi), i("addi", rd, rd, lo)]


def words_to_bytes(words: list[int]) -> bytes:
    return b"".join((w & 0xFFFFFFFF).to_bytes(4, "little") for w in words)
