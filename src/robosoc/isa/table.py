"""Every instruction robosoc knows, as data: one row per instruction.

A row gives the mnemonic, the match/mask pair of its encoding, the operand format (for
decoding and disassembly) and the energy/statistics class.  The operation numbers used by the
numba core are the row positions plus one (0 means "not decoded yet"), so this table is the single
source of truth for decode, dispatch and disassembly.  ``tests/isa`` checks that no two rows overlap.

Classes follow ORCA's energy characterisation of HF-RISCV (platform.md §5) plus two of our own:
multiply (the optional iterative multiplier) and system (SYSTEM-opcode traps).
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import IntEnum


class Cls(IntEnum):
    """Instruction class for counters and energy."""

    JUMP = 0  # LUI, AUIPC, JAL, JALR
    BRANCH = 1  # conditional branches
    MEMORY = 2  # loads and stores
    ADD = 3  # add, sub and their immediates
    LOGIC = 4  # and, or, xor and their immediates
    OTHER = 5  # shifts, comparisons, fence ("shifts and the rest")
    MUL = 6  # MUL, MULH, MULHSU, MULHU
    SYSTEM = 7  # ECALL, EBREAK, CSR*, MRET, WFI: trap on HF-RISCV


class Fmt(IntEnum):
    """Operand format: which fields the decoder extracts and how the disassembler prints them."""

    R = 0
    I = 1
    SHIFT = 2
    LOAD = 3
    S = 4
    B = 5
    U = 6
    J = 7
    JALR = 8
    NONE = 9


@dataclass(frozen=True)
class Instr:
    name: str
    match: int
    mask: int
    fmt: Fmt
    cls: Cls
    # Set for encodings that decode but that HF-RISCV cannot execute: the reason is the error text.
    unsupported: str = ""


_OPCODE = 0x7F
_F3 = 0x7000 | _OPCODE
_F7 = 0xFE000000 | _F3
_ALL = 0xFFFFFFFF


def _r(name: str, f7: int, f3: int, cls: Cls, unsupported: str = "") -> Instr:
    return Instr(name, (f7 << 25) | (f3 << 12) | 0x33, _F7, Fmt.R, cls, unsupported)


def _i(name: str, f3: int, opcode: int, fmt: Fmt, cls: Cls) -> Instr:
    return Instr(name, (f3 << 12) | opcode, _F3, fmt, cls)


_NO_DIV = "no HF-RISCV variant has a divider (compile for generic_rv32[+zmmul]: division goes through compiler-rt)"

INSTRUCTIONS: tuple[Instr, ...] = (
    Instr("lui", 0x37, _OPCODE, Fmt.U, Cls.JUMP),
    Instr("auipc", 0x17, _OPCODE, Fmt.U, Cls.JUMP),
    Instr("jal", 0x6F, _OPCODE, Fmt.J, Cls.JUMP),
    _i("jalr", 0, 0x67, Fmt.JALR, Cls.JUMP),
    _i("beq", 0, 0x63, Fmt.B, Cls.BRANCH),
    _i("bne", 1, 0x63, Fmt.B, Cls.BRANCH),
    _i("blt", 4, 0x63, Fmt.B, Cls.BRANCH),
    _i("bge", 5, 0x63, Fmt.B, Cls.BRANCH),
    _i("bltu", 6, 0x63, Fmt.B, Cls.BRANCH),
    _i("bgeu", 7, 0x63, Fmt.B, Cls.BRANCH),
    _i("lb", 0, 0x03, Fmt.LOAD, Cls.MEMORY),
    _i("lh", 1, 0x03, Fmt.LOAD, Cls.MEMORY),
    _i("lw", 2, 0x03, Fmt.LOAD, Cls.MEMORY),
    _i("lbu", 4, 0x03, Fmt.LOAD, Cls.MEMORY),
    _i("lhu", 5, 0x03, Fmt.LOAD, Cls.MEMORY),
    _i("sb", 0, 0x23, Fmt.S, Cls.MEMORY),
    _i("sh", 1, 0x23, Fmt.S, Cls.MEMORY),
    _i("sw", 2, 0x23, Fmt.S, Cls.MEMORY),
    _i("addi", 0, 0x13, Fmt.I, Cls.ADD),
    _i("slti", 2, 0x13, Fmt.I, Cls.OTHER),
    _i("sltiu", 3, 0x13, Fmt.I, Cls.OTHER),
    _i("xori", 4, 0x13, Fmt.I, Cls.LOGIC),
    _i("ori", 6, 0x13, Fmt.I, Cls.LOGIC),
    _i("andi", 7, 0x13, Fmt.I, Cls.LOGIC),
    Instr("slli", (1 << 12) | 0x13, _F7, Fmt.SHIFT, Cls.OTHER),
    Instr("srli", (5 << 12) | 0x13, _F7, Fmt.SHIFT, Cls.OTHER),
    Instr("srai", (0x20 << 25) | (5 << 12) | 0x13, _F7, Fmt.SHIFT, Cls.OTHER),
    _r("add", 0, 0, Cls.ADD),
    _r("sub", 0x20, 0, Cls.ADD),
    _r("sll", 0, 1, Cls.OTHER),
    _r("slt", 0, 2, Cls.OTHER),
    _r("sltu", 0, 3, Cls.OTHER),
    _r("xor", 0, 4, Cls.LOGIC),
    _r("srl", 0, 5, Cls.OTHER),
    _r("sra", 0x20, 5, Cls.OTHER),
    _r("or", 0, 6, Cls.LOGIC),
    _r("and", 0, 7, Cls.LOGIC),
    _r("mul", 1, 0, Cls.MUL),
    _r("mulh", 1, 1, Cls.MUL),
    _r("mulhsu", 1, 2, Cls.MUL),
    _r("mulhu", 1, 3, Cls.MUL),
    _r("div", 1, 4, Cls.MUL, _NO_DIV),
    _r("divu", 1, 5, Cls.MUL, _NO_DIV),
    _r("rem", 1, 6, Cls.MUL, _NO_DIV),
    _r("remu", 1, 7, Cls.MUL, _NO_DIV),
    Instr("fence", 0x0F, _F3, Fmt.NONE, Cls.OTHER),
    Instr("ecall", 0x00000073, _ALL, Fmt.NONE, Cls.SYSTEM),
    Instr("ebreak", 0x00100073, _ALL, Fmt.NONE, Cls.SYSTEM),
    Instr("mret", 0x30200073, _ALL, Fmt.NONE, Cls.SYSTEM),
    Instr("wfi", 0x10500073, _ALL, Fmt.NONE, Cls.SYSTEM),
    # CSR instructions (funct3 1-3, 5-7) and any other SYSTEM encoding: a trap like the rest.
    Instr("system", 0x73, _OPCODE, Fmt.NONE, Cls.SYSTEM),
)

# Operation numbers: position + 1.  0 = not decoded, ILLEGAL = no row matched.
OP: dict[str, int] = {ins.name: i + 1 for i, ins in enumerate(INSTRUCTIONS)}
OP_UNDECODED = 0
OP_ILLEGAL = len(INSTRUCTIONS) + 1
OP_FETCH_FAULT = len(INSTRUCTIONS) + 2  # sentinel row after the last word of memory


def lookup(word: int) -> Instr | None:
    """The row that decodes ``word`` (first match wins: specific SYSTEM rows precede the catch-all)."""
    for ins in INSTRUCTIONS:
        if word & ins.mask == ins.match:
            return ins
    return None
