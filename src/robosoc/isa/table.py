"""Every instruction robosoc knows, as data: one row per instruction.

A row gives the mnemonic, the match/mask pair of its encoding, the operand format (for
decoding and disassembly), the energy/statistics class and the timing class (platform.md §1).
Everything else that depends on the instruction set is derived from these rows: the operation
numbers and cycle costs of the numba core, the counter and energy class names, the stall kinds,
and which encodings write ``rd`` (the post-link s11 check).  The operation numbers used by the
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


class Timing(IntEnum):
    """How long an instruction occupies the core (platform.md §1)."""

    SINGLE = 0  # 1 cycle: ALU register/immediate, LUI, AUIPC, FENCE
    MEMORY = 1  # 3 cycles: loads and stores (any width, any device)
    BRANCH = 2  # 1 cycle not taken, 3 taken (even to pc + 4)
    JUMP = 3  # 3 cycles: JAL, JALR
    MULTIPLY = 4  # MUL_BASE_CYCLES + steps of the iterative multiplier over rs2
    TRAP = 5  # SYSTEM opcode: 1 cycle, then the trap sequence of platform.md §3


#: Cycle costs of the timing classes (platform.md §1).
SINGLE_CYCLES = 1
MEMORY_CYCLES = 3
BRANCH_NOT_TAKEN_CYCLES = 1
BRANCH_TAKEN_CYCLES = 3
JUMP_CYCLES = 3
MUL_BASE_CYCLES = 5
TRAP_CYCLES = 1

#: Fixed cycles beyond the first of each timing class (the data-dependent parts, taken branches and
#: multiplier steps, are counted by the core as they happen).
FIXED_EXTRA_CYCLES: dict[Timing, int] = {
    Timing.SINGLE: SINGLE_CYCLES - 1,
    Timing.MEMORY: MEMORY_CYCLES - 1,
    Timing.BRANCH: BRANCH_NOT_TAKEN_CYCLES - 1,
    Timing.JUMP: JUMP_CYCLES - 1,
    Timing.MULTIPLY: 0,
    Timing.TRAP: TRAP_CYCLES - 1,
}

#: The stall counter each timing class charges its extra cycles to (energy ``stall.<kind>``).
STALL_KIND: dict[Timing, str] = {
    Timing.BRANCH: "branch_cycle",
    Timing.JUMP: "branch_cycle",
    Timing.MEMORY: "memory_cycle",
    Timing.MULTIPLY: "mul_cycle",
}
#: Stall kinds the core itself produces: the classes' kinds plus interrupt/trap entry bubbles.
CORE_STALL_KINDS: tuple[str, ...] = (*dict.fromkeys(STALL_KIND.values()), "entry_cycle")


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
    timing: Timing
    # Set for encodings that decode but that HF-RISCV cannot execute: the reason is the error text.
    unsupported: str = ""


_OPCODE = 0x7F
_F3 = 0x7000 | _OPCODE
_F7 = 0xFE000000 | _F3
_ALL = 0xFFFFFFFF


def _r(name: str, f7: int, f3: int, cls: Cls, unsupported: str = "") -> Instr:
    timing = Timing.MULTIPLY if cls is Cls.MUL else Timing.SINGLE
    return Instr(name, (f7 << 25) | (f3 << 12) | 0x33, _F7, Fmt.R, cls, timing, unsupported)


def _i(name: str, f3: int, opcode: int, fmt: Fmt, cls: Cls, timing: Timing = Timing.SINGLE) -> Instr:
    return Instr(name, (f3 << 12) | opcode, _F3, fmt, cls, timing)


_NO_DIV = "no HF-RISCV variant has a divider (compile for generic_rv32[+zmmul]: division goes through compiler-rt)"

INSTRUCTIONS: tuple[Instr, ...] = (
    Instr("lui", 0x37, _OPCODE, Fmt.U, Cls.JUMP, Timing.SINGLE),
    Instr("auipc", 0x17, _OPCODE, Fmt.U, Cls.JUMP, Timing.SINGLE),
    Instr("jal", 0x6F, _OPCODE, Fmt.J, Cls.JUMP, Timing.JUMP),
    _i("jalr", 0, 0x67, Fmt.JALR, Cls.JUMP, Timing.JUMP),
    _i("beq", 0, 0x63, Fmt.B, Cls.BRANCH, Timing.BRANCH),
    _i("bne", 1, 0x63, Fmt.B, Cls.BRANCH, Timing.BRANCH),
    _i("blt", 4, 0x63, Fmt.B, Cls.BRANCH, Timing.BRANCH),
    _i("bge", 5, 0x63, Fmt.B, Cls.BRANCH, Timing.BRANCH),
    _i("bltu", 6, 0x63, Fmt.B, Cls.BRANCH, Timing.BRANCH),
    _i("bgeu", 7, 0x63, Fmt.B, Cls.BRANCH, Timing.BRANCH),
    _i("lb", 0, 0x03, Fmt.LOAD, Cls.MEMORY, Timing.MEMORY),
    _i("lh", 1, 0x03, Fmt.LOAD, Cls.MEMORY, Timing.MEMORY),
    _i("lw", 2, 0x03, Fmt.LOAD, Cls.MEMORY, Timing.MEMORY),
    _i("lbu", 4, 0x03, Fmt.LOAD, Cls.MEMORY, Timing.MEMORY),
    _i("lhu", 5, 0x03, Fmt.LOAD, Cls.MEMORY, Timing.MEMORY),
    _i("sb", 0, 0x23, Fmt.S, Cls.MEMORY, Timing.MEMORY),
    _i("sh", 1, 0x23, Fmt.S, Cls.MEMORY, Timing.MEMORY),
    _i("sw", 2, 0x23, Fmt.S, Cls.MEMORY, Timing.MEMORY),
    _i("addi", 0, 0x13, Fmt.I, Cls.ADD),
    _i("slti", 2, 0x13, Fmt.I, Cls.OTHER),
    _i("sltiu", 3, 0x13, Fmt.I, Cls.OTHER),
    _i("xori", 4, 0x13, Fmt.I, Cls.LOGIC),
    _i("ori", 6, 0x13, Fmt.I, Cls.LOGIC),
    _i("andi", 7, 0x13, Fmt.I, Cls.LOGIC),
    Instr("slli", (1 << 12) | 0x13, _F7, Fmt.SHIFT, Cls.OTHER, Timing.SINGLE),
    Instr("srli", (5 << 12) | 0x13, _F7, Fmt.SHIFT, Cls.OTHER, Timing.SINGLE),
    Instr("srai", (0x20 << 25) | (5 << 12) | 0x13, _F7, Fmt.SHIFT, Cls.OTHER, Timing.SINGLE),
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
    Instr("fence", 0x0F, _F3, Fmt.NONE, Cls.OTHER, Timing.SINGLE),
    Instr("ecall", 0x00000073, _ALL, Fmt.NONE, Cls.SYSTEM, Timing.TRAP),
    Instr("ebreak", 0x00100073, _ALL, Fmt.NONE, Cls.SYSTEM, Timing.TRAP),
    Instr("mret", 0x30200073, _ALL, Fmt.NONE, Cls.SYSTEM, Timing.TRAP),
    Instr("wfi", 0x10500073, _ALL, Fmt.NONE, Cls.SYSTEM, Timing.TRAP),
    # CSR instructions (funct3 1-3, 5-7) and any other SYSTEM encoding: a trap like the rest.
    Instr("system", 0x73, _OPCODE, Fmt.NONE, Cls.SYSTEM, Timing.TRAP),
)

# Operation numbers: position + 1.  0 = not decoded, ILLEGAL = no row matched.
OP: dict[str, int] = {ins.name: i + 1 for i, ins in enumerate(INSTRUCTIONS)}
OP_UNDECODED = 0
OP_ILLEGAL = len(INSTRUCTIONS) + 1
OP_FETCH_FAULT = len(INSTRUCTIONS) + 2  # sentinel row after the last word of memory
OP_BREAK = len(INSTRUCTIONS) + 3  # a debugger's breakpoint: the core stops before the instruction
OP_ENTRY = len(INSTRUCTIONS) + 4  # a translated block starts here: the interpreter stops before it (RUN_ENTRY)


#: Operand formats whose instructions write ``rd``: every format but stores and branches.  FENCE
#: (NONE) writes nothing; the SYSTEM catch-all stands for the CSR instructions, which write rd.
_FORMATS_WRITING_RD = frozenset({Fmt.R, Fmt.I, Fmt.SHIFT, Fmt.LOAD, Fmt.U, Fmt.J, Fmt.JALR})

#: Counter/energy name of each class: its enum name in lower case ("jump", "branch", ...).
CLASS_NAMES: dict[Cls, str] = {c: c.name.lower() for c in Cls}


def writes_rd(ins: Instr) -> bool:
    """True when executing ``ins`` writes its rd field."""
    return ins.fmt in _FORMATS_WRITING_RD or ins.name == "system"


#: The rows by major opcode (the low 7 bits, which every row's mask holds), in table order: a
#: lookup scans the few rows of its opcode (the translator decodes each word of a region).
_ROWS_BY_OPCODE: dict[int, tuple[Instr, ...]] = {}
for _ins in INSTRUCTIONS:
    assert _ins.mask & 0x7F == 0x7F, f"{_ins.name}: its mask does not hold the major opcode"
    _ROWS_BY_OPCODE[_ins.match & 0x7F] = (*_ROWS_BY_OPCODE.get(_ins.match & 0x7F, ()), _ins)


def lookup(word: int) -> Instr | None:
    """The row that decodes ``word`` (first match wins: specific SYSTEM rows precede the catch-all)."""
    for ins in _ROWS_BY_OPCODE.get(word & 0x7F, ()):
        if word & ins.mask == ins.match:
            return ins
    return None
