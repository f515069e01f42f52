"""Region discovery: the basic blocks reachable from a start pc, callees included, up to a size cap.

A region starts as one guest function: blocks joined by conditional branches and ``jal x0``
jumps, plus the return sites after the calls it makes; the callees of direct calls join it too
(until the cap), so that a call and its return stay inside the native code (the emitter turns a
``jalr`` into a switch over the region's return sites and callees).  Targets already translated
elsewhere and beyond the cap leave the region; an instruction the translator does not handle
ends its block with a *side exit*, after which the interpreter executes it (docs/translation.md).

Instructions are decoded here from the memory words with :mod:`robosoc.isa.table` (the same rows
the interpreter decodes), never from the interpreter's predecode table.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from enum import Enum

from robosoc.isa import fields
from robosoc.isa.table import INSTRUCTIONS, OP, Cls, Fmt, Instr, Timing, lookup

NOP_WORD = 0x00000013  # addi x0, x0, 0

#: Most instructions a region may hold (bounds compile time); targets beyond leave the region.
MAX_REGION_INSTRUCTIONS = 400
#: Longest block: a longer run is cut with a fall-through, so the pre-block event check stays tight.
MAX_BLOCK_INSTRUCTIONS = 64


@dataclass(frozen=True)
class Insn:
    """One decoded guest instruction at ``pc``."""

    pc: int
    word: int
    ins: Instr
    rd: int
    rs1: int
    rs2: int
    imm: int

    @property
    def name(self) -> str:
        return self.ins.name

    @property
    def op(self) -> int:
        """The interpreter's operation number (row position + 1)."""
        return OP[self.ins.name]


class End(Enum):
    """How a block ends."""

    FALL = "fall"  # runs into the next block (or leaves the region to it)
    BRANCH = "branch"  # conditional branch, last instruction
    JUMP = "jump"  # jal x0 (last instruction)
    CALL = "call"  # jal with a link register: leaves the region to the callee
    JALR = "jalr"  # leaves the region to a computed target
    SIDE = "side"  # the instruction at ``next_pc`` is left to the interpreter


@dataclass
class Block:
    start: int
    insns: list[Insn] = field(default_factory=list)
    end: End = End.FALL
    next_pc: int = 0  # FALL: the next block's pc; SIDE: the untranslated instruction's pc


@dataclass
class Region:
    start: int
    blocks: dict[int, Block]  # by start pc, in address order

    @property
    def instructions(self) -> int:
        return sum(len(b.insns) for b in self.blocks.values())

    def words(self) -> set[int]:
        """The pcs of every translated instruction."""
        return {i.pc for b in self.blocks.values() for i in b.insns}


def decode(word: int, pc: int) -> Insn | None:
    """The instruction at ``pc``, or None for a word no row decodes."""
    ins = lookup(word)
    if ins is None:
        return None
    rd, rs1, rs2 = fields.rd(word), fields.rs1(word), fields.rs2(word)
    imm = 0
    match ins.fmt:
        case Fmt.I | Fmt.LOAD | Fmt.JALR:
            imm = fields.imm_i(word)
        case Fmt.SHIFT:
            imm = rs2
        case Fmt.S:
            imm = fields.imm_s(word)
        case Fmt.B:
            imm = fields.imm_b(word)
        case Fmt.U:
            imm = fields.imm_u(word)
        case Fmt.J:
            imm = fields.imm_j(word)
    return Insn(pc, word, ins, rd, rs1, rs2, imm)


@dataclass(frozen=True)
class CodeView:
    """What the translator may know about the core: its code words and build options."""

    word: Callable[[int], int]  # memory word at an address of the loaded code
    base: int
    code_size: int
    mem_size: int
    has_mul: bool

    def in_code(self, pc: int) -> bool:
        return pc % 4 == 0 and 0 <= pc - self.base < self.code_size

    def fetchable(self, target: int) -> bool:
        """Whether a jump or branch to ``target`` continues (else the interpreter reports the error)."""
        return self.in_code(target & 0xFFFFFFFF)


def is_idle_jump(insn: Insn, view: CodeView) -> bool:
    """``j .`` or ``nop; j .-4``: the interpreter skips whole iterations of these, so they stay there."""
    if insn.name != "jal" or insn.rd != 0:
        return False
    if insn.imm == 0:
        return True
    return insn.imm == -4 and view.in_code(insn.pc - 4) and view.word(insn.pc - 4) == NOP_WORD


def translatable(insn: Insn | None, view: CodeView) -> bool:
    """Whether the translator emits code for ``insn`` (else a side exit leaves it to the interpreter)."""
    if insn is None or insn.ins.unsupported:
        return False
    if insn.ins.timing is Timing.TRAP:
        return False
    if insn.ins.cls is Cls.MUL and not view.has_mul:
        return False
    if insn.ins.fmt in (Fmt.B, Fmt.J) and not view.fetchable(insn.pc + insn.imm):
        return False
    return not is_idle_jump(insn, view)


def _fetch(view: CodeView, pc: int) -> Insn | None:
    insn = decode(view.word(pc), pc)
    return insn if translatable(insn, view) else None


def discover(
    view: CodeView,
    start: int,
    max_instructions: int = MAX_REGION_INSTRUCTIONS,
    translated: Callable[[int], bool] = lambda pc: False,
) -> Region:
    """The region reachable from ``start`` (which must be a word of the loaded code).

    Targets for which ``translated`` is true (blocks of earlier regions) are left to those
    regions rather than translated again.
    """
    leaders: list[int] = [start]
    queued = {start}
    visited: dict[int, Insn] = {}  # the instructions taken, by pc (decoded once)
    count = 0

    def add(pc: int) -> None:
        if view.in_code(pc) and pc not in queued and not translated(pc):
            queued.add(pc)
            leaders.append(pc)

    k = 0
    while k < len(leaders) and count < max_instructions:
        pc = leaders[k]
        k += 1
        while view.in_code(pc) and pc not in visited and count < max_instructions:
            if pc != start and translated(pc):
                break
            insn = _fetch(view, pc)
            if insn is None:
                break
            visited[pc] = insn
            count += 1
            fmt = insn.ins.fmt
            if fmt is Fmt.B:
                add(pc + insn.imm)
                add(pc + 4)
                break
            if fmt is Fmt.J:  # a call's callee joins the region too, its returns come back in it
                add(pc + insn.imm)
                if insn.rd != 0:
                    add(pc + 4)
                break
            if fmt is Fmt.JALR:
                if insn.rd != 0:
                    add(pc + 4)
                break
            pc += 4
        else:
            if pc in visited and pc not in queued:  # two paths merge here: a block starts
                queued.add(pc)
    starts = sorted(p for p in queued if p in visited)
    start_set = set(starts)
    blocks: dict[int, Block] = {}
    k = 0
    while k < len(starts):
        s = starts[k]
        k += 1
        block = Block(s)
        pc = s
        while True:
            if pc not in visited:  # untranslatable (side exit), beyond the cap or outside the code
                side = view.in_code(pc) and _fetch(view, pc) is None
                block.end, block.next_pc = (End.SIDE if side else End.FALL), pc
                break
            insn = visited[pc]
            block.insns.append(insn)
            fmt = insn.ins.fmt
            if fmt is Fmt.B:
                block.end, block.next_pc = End.BRANCH, pc + 4
                break
            if fmt is Fmt.J:
                block.end, block.next_pc = (End.JUMP if insn.rd == 0 else End.CALL), pc + 4
                break
            if fmt is Fmt.JALR:
                block.end, block.next_pc = End.JALR, pc + 4
                break
            pc += 4
            if pc in start_set:
                block.end, block.next_pc = End.FALL, pc
                break
            if len(block.insns) >= MAX_BLOCK_INSTRUCTIONS and pc in visited:
                block.end, block.next_pc = End.FALL, pc
                start_set.add(pc)
                starts.append(pc)
                break
        blocks[s] = block
    blocks = dict(sorted(blocks.items()))
    return Region(start, blocks)


#: Instructions per timing class, for docs and tests: every row the translator can emit.
TRANSLATED_OPS = tuple(i.name for i in INSTRUCTIONS if not i.unsupported and i.timing is not Timing.TRAP)
