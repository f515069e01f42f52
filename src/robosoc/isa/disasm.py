"""Disassembly of single instruction words, for error messages and traces."""

from __future__ import annotations

from robosoc.isa import fields
from robosoc.isa.table import Fmt, lookup

ABI_NAMES = (
    "zero", "ra", "sp", "gp", "tp", "t0", "t1", "t2", "s0", "s1", "a0", "a1", "a2", "a3", "a4", "a5",
    "a6", "a7", "s2", "s3", "s4", "s5", "s6", "s7", "s8", "s9", "s10", "s11", "t3", "t4", "t5", "t6",
)  # fmt: skip


def reg(n: int) -> str:
    return ABI_NAMES[n]


def disassemble(word: int, pc: int | None = None) -> str:
    """Text of one instruction, e.g. ``addi sp, sp, -16``; ``.word 0x...`` for an unknown encoding.

    Branch and jump targets are shown as absolute addresses when ``pc`` is given.
    """
    word &= 0xFFFFFFFF
    ins = lookup(word)
    if ins is None:
        return f".word 0x{word:08x}"
    d, s1, s2 = reg(fields.rd(word)), reg(fields.rs1(word)), reg(fields.rs2(word))
    n = ins.name

    def target(offset: int) -> str:
        return f"0x{(pc + offset) & 0xFFFFFFFF:08x}" if pc is not None else f"{offset:+d}"

    match ins.fmt:
        case Fmt.R:
            return f"{n} {d}, {s1}, {s2}"
        case Fmt.I:
            return f"{n} {d}, {s1}, {fields.imm_i(word)}"
        case Fmt.SHIFT:
            return f"{n} {d}, {s1}, {fields.rs2(word)}"
        case Fmt.LOAD:
            return f"{n} {d}, {fields.imm_i(word)}({s1})"
        case Fmt.S:
            return f"{n} {s2}, {fields.imm_s(word)}({s1})"
        case Fmt.B:
            return f"{n} {s1}, {s2}, {target(fields.imm_b(word))}"
        case Fmt.U:
            return f"{n} {d}, 0x{(fields.imm_u(word) >> 12) & 0xFFFFF:x}"
        case Fmt.J:
            return f"{n} {d}, {target(fields.imm_j(word))}"
        case Fmt.JALR:
            return f"{n} {d}, {fields.imm_i(word)}({s1})"
        case _:
            if n == "system":
                return f"system 0x{word:08x}"
            return n
