"""LLVM IR of one region: one function, its blocks as basic blocks.

The region function has the signature (all arrays distinct, hence ``noalias``)::

    i32 @region(i64* ctx, i32* regs, i8* mem, i64* opc, i64 cycle, i64 limit, i64 block)

and starts with a switch over ``block``, the index of the block to enter: the dispatch loop and
other regions may enter at any block start (the entry table holds each word's function and block
index).  Each block checks that its worst-case cycles end before the next event, runs its
instructions and continues with a branch to the next block of the region, or through the entry
table with a tail call to whichever region has a block at the target (an indirect jump;
``musttail``, as every region function has the same signature), or returns an X_* code of
:mod:`robosoc.kernels.jit_dispatch` to the dispatch loop.  Guest registers stay in the register
array (a load at first use in a block, a store per write); the cycle count is an SSA value (a
stack slot SROA promotes); the state and counter arrays are reached through ``ctx``.  The IR is
written as text (faster to produce than llvmlite's builder objects).  Loads outside SRAM, stores
outside its data part (devices, and the loaded code: self-modifying code) and misaligned accesses
leave the region before the instruction, for the interpreter.  Costs come from the timing classes
of :mod:`robosoc.isa.table`.  Each way out of a block adds the instructions it executed to the
tile's counters itself (``opc``, and ``ctr[C_TAKEN]`` for a taken branch): the block's ends its
whole histogram (one add per operation), a side exit the prefix before it; the blocks of a small
loop (:func:`looped_blocks`) count their executions in locals instead, added to the counters at the
function's ways out.  So the counters are the interpreter's whenever a region returns.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass

import numpy as np

from robosoc.isa.table import (
    BRANCH_NOT_TAKEN_CYCLES,
    BRANCH_TAKEN_CYCLES,
    JUMP_CYCLES,
    MEMORY_CYCLES,
    MUL_BASE_CYCLES,
    SINGLE_CYCLES,
    Fmt,
    Timing,
)
from robosoc.jit.regions import Block, End, Insn, Region
from robosoc.jit.target import Target
from robosoc.kernels.core import _MUL_CHUNK
from robosoc.kernels.core_layout import C_MUL_STALL, C_TAKEN, OPC_SIZE, S_MUL_END, S_MULHSU_COUNT, S_MULHSU_PC
from robosoc.kernels.jit_dispatch import (
    CTX_CTR,
    CTX_CYC,
    CTX_ENTRY_BLK,
    CTX_ENTRY_FN,
    CTX_PC,
    CTX_ST,
    X_JUMP,
    X_LIMIT,
    X_SIDE,
)

NAME_PLACEHOLDER = "REGION_NAME"
SINK = 32  # the interpreter's register for rd = x0 (written, never read)
M32 = 0xFFFFFFFF


def multiplier_tail_table() -> np.ndarray:
    """Cycles after bit 24 of the multiplier's scan: ``[entry offset 0..3, rs2 bits 24..31]``.

    Continues :func:`robosoc.kernels.core.mul_latency` from where its byte table leaves the
    counter (24 + offset): steps while c < 28 (c grows by 1 when bits c..c+3 are not all zero,
    else by 4), one step per bit from c to 31, and the last step.
    """
    table = np.zeros((4, 256), dtype=np.int64)
    for off in range(4):
        for top in range(256):
            b = top << 24
            c, steps = 24 + off, 0
            while c < 28:
                c += 1 if (b >> c) & 15 else 4
                steps += 1
            table[off, top] = steps + (31 - c) + 1
    return table


_TAIL = multiplier_tail_table()
#: Most cycles one multiply takes (every step advances the counter by one bit).
MUL_WORST_CYCLES = MUL_BASE_CYCLES + int(_TAIL[0].max()) + 3 * int((_MUL_CHUNK[0] >> 4).max())

#: Most cycles an instruction of each timing class takes: the pre-block event check uses these.
WORST_CYCLES: dict[Timing, int] = {
    Timing.SINGLE: SINGLE_CYCLES,
    Timing.MEMORY: MEMORY_CYCLES,
    Timing.BRANCH: max(BRANCH_TAKEN_CYCLES, BRANCH_NOT_TAKEN_CYCLES),
    Timing.JUMP: JUMP_CYCLES,
    Timing.MULTIPLY: MUL_WORST_CYCLES,
}


def _bytes_const(values: np.ndarray) -> str:
    data = values.astype(np.uint8).tobytes()
    return 'c"' + "".join(f"\\{b:02X}" for b in data) + '"'


def _i32(v: int) -> int:
    """A 32-bit constant as LLVM prints it (signed)."""
    v &= M32
    return v - (1 << 32) if v >> 31 else v


MAX_SWITCH = 8  # most return sites a return compares its target with before the entry table
_ALU_RR = {"add": "add", "sub": "sub", "xor": "xor", "or": "or", "and": "and"}
_ALU_RI = {"addi": "add", "xori": "xor", "ori": "or", "andi": "and"}
_SHIFT_I = {"slli": "shl", "srli": "lshr", "srai": "ashr"}
_SHIFT_R = {"sll": "shl", "srl": "lshr", "sra": "ashr"}
_SET = {"slt": "slt", "slti": "slt", "sltu": "ult", "sltiu": "ult"}
_BRANCH = {"beq": "eq", "bne": "ne", "blt": "slt", "bge": "sge", "bltu": "ult", "bgeu": "uge"}
_LOADS = {"lb": (8, "sext", 0), "lbu": (8, "zext", 0), "lh": (16, "sext", 1), "lhu": (16, "zext", 1), "lw": (32, "", 3)}
_STORES = {"sb": (8, 0), "sh": (16, 1), "sw": (32, 3)}


@dataclass
class EmittedRegion:
    ir: str
    function: str  # the region function's name (with the region's name placeholder)
    blocks: dict[int, int]  # block start pc -> block index (the function's ``block`` argument)


@dataclass(frozen=True)
class MemoryCheck:
    """The check before the first access of a group: the bytes at ``low``..``low + span`` from the
    base register lie in the part of memory from ``start`` on, and the access at ``anchor`` is
    aligned to ``align + 1`` bytes (which aligns the others)."""

    start: int
    low: int
    span: int
    align: int
    anchor: int


def _access(insn: Insn) -> tuple[bool, int] | None:
    """(is a load, size in bytes) of a memory access, else None."""
    if insn.name in _LOADS:
        return True, _LOADS[insn.name][0] // 8
    if insn.name in _STORES:
        return False, _STORES[insn.name][0] // 8
    return None


@dataclass
class _Group:
    """Accesses of one kind through one base register, checked together (see :func:`memory_checks`)."""

    first: int  # index of the first access in the block
    start: int  # where the part they may touch begins
    room: int  # and its size
    accesses: list[tuple[int, int]]  # (offset, size)
    widest: int
    anchor: int  # offset of the first of the widest accesses: its alignment aligns the others
    low: int
    high: int  # one past the last byte

    @staticmethod
    def of(j: int, imm: int, size: int, load: bool, target: Target) -> _Group:
        start = 0 if load else target.code_size
        return _Group(j, start, target.mem_size - start, [(imm, size)], size, imm, imm, imm + size)

    def add(self, imm: int, size: int) -> bool:
        """Take in an access, if one check can still stand for the group (else change nothing)."""
        widest, anchor = (size, imm) if size > self.widest else (self.widest, self.anchor)
        if anchor != self.anchor:
            if any((a - anchor) % n for a, n in self.accesses):
                return False
        elif (imm - anchor) % size:
            return False  # no one alignment test stands for all of them
        low, high = min(self.low, imm), max(self.high, imm + size)
        if high - low > self.room:
            return False
        self.accesses.append((imm, size))
        self.widest, self.anchor, self.low, self.high = widest, anchor, low, high
        return True

    def check(self) -> MemoryCheck:
        return MemoryCheck(self.start, self.low, self.high - self.low, self.widest - 1, self.anchor)


def memory_checks(insns: list[Insn], target: Target) -> dict[int, MemoryCheck]:
    """The memory checks of a block, by the index of the access each is made before.

    Accesses of one kind (loads, or stores) through the same base register, which no instruction
    between them writes, form a group checked once, before its first access: a register save or
    restore sequence is one compare instead of one per access, and one way out.  When the check
    fails, the block leaves before the group's first access and the interpreter runs the accesses
    one by one (with the same results and errors as without the group).  Loads may read all of
    SRAM; stores only its data part, past the loaded code (self-modifying code is the
    interpreter's).
    """
    open_groups: dict[tuple[int, bool], _Group] = {}
    checks: dict[int, MemoryCheck] = {}

    def close(key: tuple[int, bool]) -> None:
        group = open_groups.pop(key)
        checks[group.first] = group.check()

    for j, insn in enumerate(insns):
        access = _access(insn)
        if access is not None:
            load, size = access
            key = (insn.rs1, load)
            if key in open_groups and not open_groups[key].add(insn.imm, size):
                close(key)
            if key not in open_groups:
                open_groups[key] = _Group.of(j, insn.imm, size, load, target)
        if insn.rd and insn.ins.fmt not in (Fmt.S, Fmt.B):
            for key in [k for k in open_groups if k[0] == insn.rd]:
                close(key)
    for key in list(open_groups):
        close(key)
    return checks


_PARAMS = "i64* noalias %ctx, i32* noalias %regs, i8* noalias %mem, i64* noalias %opc, i64 %cyc, i64 %limit, i64 %blk"
_FN_TYPE = "i32 (i64*, i32*, i8*, i64*, i64, i64, i64)"
#: histogram index of the taken-branch counter ``ctr[C_TAKEN]``: past the per-operation counters
TAKEN_INDEX = OPC_SIZE + C_TAKEN


def successors(block: Block, returns: list[int]) -> list[int]:
    """The pcs a block continues at with a branch of the region function, if blocks start there:
    its static targets, and for a return (``jalr x0, 0(ra)``) the region's return sites ``returns``."""
    last = block.insns[-1]
    match block.end:
        case End.FALL:
            return [block.next_pc]
        case End.BRANCH:
            return [(last.pc + last.imm) & M32, last.pc + 4]
        case End.JUMP | End.CALL:
            return [(last.pc + last.imm) & M32]
        case End.JALR:
            return list(returns) if (last.rd, last.rs1, last.imm) == (0, 1, 0) else []
    return []


#: Most blocks of a cycle whose blocks count through locals (:func:`looped_blocks`)
MAX_LOOP_BLOCKS = 4


def looped_blocks(region: Region, returns: list[int]) -> set[int]:
    """Starts of the blocks that lie on a small cycle of the region's own branches: a strongly
    connected set of at most MAX_LOOP_BLOCKS blocks (a loop inside a function).  They count their
    executions through locals, written to the counters at the function's ways out (:class:`_Writer`)."""
    succ = {pc: [t for t in successors(b, returns) if t in region.blocks] for pc, b in region.blocks.items()}
    reach: dict[int, set[int]] = {}
    for pc in region.blocks:
        seen: set[int] = set()
        todo = list(succ[pc])
        while todo:
            t = todo.pop()
            if t not in seen:
                seen.add(t)
                todo.extend(succ[t])
        reach[pc] = seen
    looped = set()
    for pc in region.blocks:
        if pc in reach[pc]:
            cycle = {q for q in reach[pc] if pc in reach[q]}
            if len(cycle) <= MAX_LOOP_BLOCKS:
                looped.add(pc)
    return looped


class _Writer:
    """Writes one region.  Register values and the cycles since the block started are tracked
    along each path, so an instruction is its operation plus one register store.
    """

    def __init__(self, target: Target, region: Region, name: str) -> None:
        self.t = target
        self.region = region
        self.name = name
        self.lines: list[str] = []
        self.n = 0
        self.uses_mul = False
        self.uses_fshr = False
        self.index = {pc: k for k, pc in enumerate(region.blocks)}
        # where a return (jalr x0, 0(ra)) may land inside the region: the return sites of its calls,
        # when there are few (else returns go through the entry table)
        sites = {b.next_pc for b in region.blocks.values() if b.end is End.CALL and b.next_pc in self.index}
        self.returns = sorted(sites) if len(sites) <= MAX_SWITCH else []
        #: blocks on a cycle of the region's own branches (block index -> its histogram): they count
        #: their executions in a local (a register in a loop), added to the counters at the ways out
        self.looped: dict[int, list[int]] = {self.index[pc]: [] for pc in looped_blocks(region, self.returns)}
        self.regs: dict[int, str] = {}  # register -> its current SSA value in this block
        self.dirty: dict[int, str] = {}  # registers written since the last store to the array
        self.pointers: dict[str, str] = {}  # SSA name -> its definition, written in the entry block
        self.cyc = "%cyc"  # SSA value of the cycle count at the last dynamic change
        self.pending = 0  # cycles of the instructions since then
        self.cur = "entry"  # the basic block being written
        self.jumps: list[tuple[str, str, str]] = []  # through the entry table: (from label, pc, cycle)
        self.exits: list[tuple[str, int, str, str]] = []  # to the loop: (from label, code, pc, cycle)
        self.counted_exits = False  # a side exit counted its block's prefix and returns through %side

    def tmp(self) -> str:
        self.n += 1
        return f"%t{self.n}"

    def label(self, stem: str) -> str:
        self.n += 1
        return f"{stem}{self.n}"

    def emit(self, line: str) -> None:
        self.lines.append("  " + line)

    def put_label(self, name: str) -> None:
        self.lines.append(f"{name}:")
        self.cur = name

    # --- state ------------------------------------------------------------------------------
    def pointer(self, name: str, definition: str) -> str:
        """``%name``, defined once in the entry block (addresses that hold for the whole call)."""
        self.pointers.setdefault(f"%{name}", definition)
        return f"%{name}"

    def reg_ptr(self, r: int) -> str:
        p = self.tmp()
        self.emit(f"{p} = getelementptr i32, i32* %regs, i64 {r}")
        return p

    def reg(self, r: int) -> str:
        if r == 0:
            return "0"
        v = self.regs.get(r)
        if v is None:
            v = self.tmp()
            self.emit(f"{v} = load i32, i32* {self.reg_ptr(r)}")
            self.regs[r] = v
        return v

    def set_reg(self, rd: int, value: str) -> None:
        """Write ``rd`` (x0: the interpreter's sink); stored to the array before the next way out."""
        self.dirty[rd if rd != 0 else SINK] = value
        if rd != 0:
            self.regs[rd] = value

    def flush(self) -> None:
        """Store the registers written since the last way out (before control can leave this path)."""
        for r, v in self.dirty.items():
            self.emit(f"store i32 {v}, i32* {self.reg_ptr(r)}")
        self.dirty = {}

    def cycles(self, extra: int | str = 0) -> str:
        """The cycle count after the instructions so far plus ``extra``, as an SSA value."""
        v = self.cyc
        total = self.pending + (extra if isinstance(extra, int) else 0)
        if total:
            w = self.tmp()
            self.emit(f"{w} = add i64 {v}, {total}")
            v = w
        if isinstance(extra, str):
            w = self.tmp()
            self.emit(f"{w} = add i64 {v}, {extra}")
            v = w
        return v

    def add_i64(self, ptr: str, n: int | str) -> None:
        a, b = self.tmp(), self.tmp()
        self.emit(f"{a} = load i64, i64* {ptr}")
        self.emit(f"{b} = add i64 {a}, {n}")
        self.emit(f"store i64 {b}, i64* {ptr}")

    def ctx_ptr(self, slot: int) -> str:
        """The address held in ctx[slot] as an i64* (loaded once, in the entry block)."""
        g = self.pointer(f"ctxg{slot}", f"getelementptr i64, i64* %ctx, i64 {slot}")
        a = self.pointer(f"ctxa{slot}", f"load i64, i64* {g}")
        return self.pointer(f"ctxp{slot}", f"inttoptr i64 {a} to i64*")

    def field(self, base: str, index: int | str) -> str:
        p = self.tmp()
        self.emit(f"{p} = getelementptr i64, i64* {base}, i64 {index}")
        return p

    def counter(self, kc: int) -> str:
        """The address of histogram index ``kc``'s counter: below OPC_SIZE a per-operation counter
        ``opc[kc]``, OPC_SIZE + k ``ctr[k]``."""
        return self.field("%opc", kc) if kc < OPC_SIZE else self.field(self.ctx_ptr(CTX_CTR), kc - OPC_SIZE)

    def count(self, hist: list[int]) -> None:
        """Add the histogram ``hist`` (indices of :meth:`counter`) to the tile's counters, one add
        per counter."""
        for kc, n in sorted(Counter(hist).items()):
            self.add_i64(self.counter(kc), n)

    # --- leaving a block ----------------------------------------------------------------------
    def leave(self, code: int, pc: int | str, cyc: str | None = None) -> None:
        """Return ``code`` to the dispatch loop with pc and cycle in ctx, through the function's one
        way out (:meth:`leave_block`): an exit costs a branch here."""
        cyc = cyc or self.cycles()
        self.flush()
        self.exits.append((self.cur, code, str(pc), cyc))
        self.emit("br label %leave")

    def leave_block(self) -> None:
        """The shared way out to the dispatch loop: pc and cycle into ctx, the exit code.

        One block for every exit keeps the IR (and the code generator's time) small: the side
        exits of memory accesses, limits and jumps are most of a region's ways out.  The side exits
        inside a block, which count the block's prefix on their way (:meth:`prefix_chain`), store pc
        and cycle themselves and return through ``%side``.
        """
        if self.counted_exits:
            self.put_label("side")
            self.write_locals()
            self.emit(f"ret i32 {X_SIDE}")
        if not self.exits:
            return
        self.put_label("leave")
        incoming = [(f"%{lb}", *rest) for lb, *rest in self.exits]
        self.emit(f"%xcode = phi i32 {', '.join(f'[ {code}, {lb} ]' for lb, code, _, _ in incoming)}")
        self.emit(f"%xpc = phi i64 {', '.join(f'[ {pc}, {lb} ]' for lb, _, pc, _ in incoming)}")
        self.emit(f"%xcyc = phi i64 {', '.join(f'[ {cyc}, {lb} ]' for lb, _, _, cyc in incoming)}")
        self.emit(f"store i64 %xpc, i64* {self.field('%ctx', CTX_PC)}")
        self.emit(f"store i64 %xcyc, i64* {self.field('%ctx', CTX_CYC)}")
        self.write_locals()
        self.emit("ret i32 %xcode")

    def branch(self, pc: int, cyc: str) -> None:
        """Continue at this region's block at ``pc`` (a branch within the function)."""
        self.flush()
        self.emit(f"store i64 {cyc}, i64* %cycp")
        self.emit(f"br label %blk{self.index[pc]}")

    def jump(self, pc: str, cyc: str) -> None:
        """Continue at the dynamic ``pc`` (i64): the region with a block there, else the dispatch loop."""
        self.jumps.append((self.cur, pc, cyc))
        self.flush()
        self.emit("br label %jump")

    def jump_block(self) -> None:
        """The function's shared way out through the entry table (``jump``), when a block uses it."""
        if self.jumps:
            self.put_label("jump")
            self.emit(f"%jpc = phi i64 {', '.join(f'[ {pc}, %{lb} ]' for lb, pc, _ in self.jumps)}")
            self.emit(f"%jcyc = phi i64 {', '.join(f'[ {cyc}, %{lb} ]' for lb, _, cyc in self.jumps)}")
            off, i = self.tmp(), self.tmp()
            self.emit(f"{off} = sub i64 %jpc, {self.t.base}")
            self.emit(f"{i} = lshr i64 {off}, 2")
            fe, fa = self.tmp(), self.tmp()
            self.emit(f"{fe} = getelementptr i64, i64* {self.ctx_ptr(CTX_ENTRY_FN)}, i64 {i}")
            self.emit(f"{fa} = load i64, i64* {fe}")
            none = self.tmp()
            self.emit(f"{none} = icmp eq i64 {fa}, 0")
            self.emit(f"br i1 {none}, label %jx, label %jgo")
            self.put_label("jx")
            self.leave(X_JUMP, "%jpc", "%jcyc")
            self.put_label("jgo")
            be, bl, f, r = (self.tmp() for _ in range(4))
            self.emit(f"{be} = getelementptr i64, i64* {self.ctx_ptr(CTX_ENTRY_BLK)}, i64 {i}")
            self.emit(f"{bl} = load i64, i64* {be}")
            self.emit(f"{f} = inttoptr i64 {fa} to {_FN_TYPE}*")
            args = f"i64* %ctx, i32* %regs, i8* %mem, i64* %opc, i64 %jcyc, i64 %limit, i64 {bl}"
            self.write_locals()
            self.emit(f"{r} = musttail call i32 {f}({args})")
            self.emit(f"ret i32 {r}")

    def goto(self, pc: int, cyc: str) -> None:
        """Continue at the static ``pc``: this region's block there, or through the entry table."""
        pc &= M32
        if pc in self.index:
            self.branch(pc, cyc)
        else:
            self.jump(str(pc), cyc)

    def side_exit(self, cond: str, j: int, pc: int, stem: str) -> None:
        """Leave before instruction ``j`` (at ``pc``) to the dispatch loop (X_SIDE) when ``cond``,
        counting the instructions before it; else go on in a new label."""
        x, ok = self.label(f"{stem}.x"), self.label(stem)
        self.flush()
        self.emit(f"br i1 {cond}, label %{x}, label %{ok}")
        self.put_label(x)
        self.emit(f"store i64 {pc}, i64* {self.field('%ctx', CTX_PC)}")
        self.emit(f"store i64 {self.cycles()}, i64* {self.field('%ctx', CTX_CYC)}")
        self.emit(f"br label %{self.prefix[j]}")
        self.counted_exits = True
        self.put_label(ok)

    # --- counting -----------------------------------------------------------------------------
    def count_end(self) -> None:
        """Count the block's instructions at its end, where no side exit can come (before a
        branch's two ways: the taken one also counts ``ctr[C_TAKEN]``, :meth:`count_taken`); a
        block on a cycle counts one execution in its local instead."""
        k = self.index[self.block_start]
        if k in self.looped:
            self.looped[k] = self.kcs
            self.add_local(f"%bc{k}")
        else:
            self.count(self.kcs)

    def count_taken(self) -> None:
        if self.index[self.block_start] in self.looped:
            self.add_local("%taken")
        else:
            self.count([TAKEN_INDEX])

    def add_local(self, local: str) -> None:
        a, b = self.tmp(), self.tmp()
        self.emit(f"{a} = load i64, i64* {local}")
        self.emit(f"{b} = add i64 {a}, 1")
        self.emit(f"store i64 {b}, i64* {local}")

    def write_locals(self) -> None:
        """Add the executions the blocks on cycles counted in their locals, times their histograms,
        to the counters (at each of the function's ways out: the shared returns and the tail call)."""
        if not self.looped:
            return
        terms: dict[int, list[tuple[str, int]]] = {}
        for k, hist in sorted(self.looped.items()):
            v = self.tmp()
            self.emit(f"{v} = load i64, i64* %bc{k}")
            for kc, n in Counter(hist).items():
                terms.setdefault(kc, []).append((v, n))
        taken = self.tmp()
        self.emit(f"{taken} = load i64, i64* %taken")
        terms.setdefault(TAKEN_INDEX, []).append((taken, 1))
        for kc, parts in sorted(terms.items()):
            total = ""
            for v, n in parts:
                term = v
                if n != 1:
                    term = self.tmp()
                    self.emit(f"{term} = mul i64 {v}, {n}")
                if total:
                    w = self.tmp()
                    self.emit(f"{w} = add i64 {total}, {term}")
                    term = w
                total = term
            self.add_i64(self.counter(kc), total)

    def prefix_chain(self, points: list[int]) -> None:
        """The side exits' counts of the block: the exit before instruction ``points[k]`` enters a
        chain of labels at its segment (the instructions from the point before it), which counts
        that segment and goes on to the one before, down to ``%side`` (one count per instruction
        of the block however many exits it has)."""
        down, last = "side", 0
        for j in points:
            if j > last:
                label = self.label("pfx")
                self.put_label(label)
                self.count(self.kcs[last:j])
                self.emit(f"br label %{down}")
                down, last = label, j
            self.prefix[j] = down

    def kc(self, insn: Insn) -> int:
        return 2 * insn.op + (((insn.pc - self.t.base) >> 2) & 1)

    def block(self, block: Block) -> None:
        insns = block.insns
        worst = sum(WORST_CYCLES[i.ins.timing] for i in insns[:-1])
        self.put_label(f"blk{self.index[block.start]}")
        self.block_start = block.start
        self.regs, self.cyc, self.pending = {}, self.tmp(), 0
        self.emit(f"{self.cyc} = load i64, i64* %cycp")
        e, ok, go, lim = self.tmp(), self.tmp(), self.label("go"), self.label("lim")
        self.emit(f"{e} = add i64 {self.cyc}, {worst}")
        self.emit(f"{ok} = icmp slt i64 {e}, %limit")
        self.emit(f"br i1 {ok}, label %{go}, label %{lim}")
        self.put_label(lim)
        self.leave(X_LIMIT, block.start)
        self.put_label(go)
        # Each way out adds the instructions executed to the counters: the block's ends the whole
        # block (and the taken branch), a side exit before instruction j the prefix before j
        # (through the block's chain of prefix segments, written after it: prefix_chain).
        self.kcs = [self.kc(i) for i in insns]
        self.checks = memory_checks(insns, self.t)
        points = [j for j, i in enumerate(insns) if j in self.checks or i.name == "jalr"]
        self.prefix: dict[int, str] = {}
        body, here = self.lines, self.cur
        self.lines = []
        self.prefix_chain(points)
        chain, self.lines, self.cur = self.lines, body, here
        for j, insn in enumerate(insns):
            self.insn(j, insn)
        match block.end:
            case End.FALL:
                self.count_end()
                self.goto(block.next_pc, self.cycles())
            case End.SIDE:
                self.count_end()
                self.leave(X_SIDE, block.next_pc)
            case End.BRANCH | End.JUMP | End.CALL | End.JALR:
                self.control(len(insns) - 1, insns[-1])
        self.lines += chain

    def function(self) -> None:
        """The region function: the entry switch over the block index, then every block."""
        for block in self.region.blocks.values():
            self.block(block)
        self.jump_block()
        self.leave_block()  # after the jump block, which leaves through it too
        body, self.lines = self.lines, [f"define i32 @{self.name}({_PARAMS}) nounwind {{", "entry:"]
        self.emit("%cycp = alloca i64")
        for k in sorted(self.looped):
            self.emit(f"%bc{k} = alloca i64")
            self.emit(f"store i64 0, i64* %bc{k}")
        if self.looped:
            self.emit("%taken = alloca i64")
            self.emit("store i64 0, i64* %taken")
        self.emit("store i64 %cyc, i64* %cycp")
        for name, definition in self.pointers.items():
            self.emit(f"{name} = {definition}")
        cases = " ".join(f"i64 {k}, label %blk{k}" for k in range(1, len(self.index)))
        self.emit(f"switch i64 %blk, label %blk0 [ {cases} ]")
        self.lines += [*body, "}"]

    # --- instructions -------------------------------------------------------------------------
    def control(self, j: int, insn: Insn) -> None:
        pc = insn.pc
        name = insn.name
        if name in _BRANCH:
            a, b, cond = self.reg(insn.rs1), self.reg(insn.rs2), self.tmp()
            self.emit(f"{cond} = icmp {_BRANCH[name]} i32 {a}, {b}")
            self.flush()
            self.count_end()
            taken, fall = self.label("taken"), self.label("fall")
            self.emit(f"br i1 {cond}, label %{taken}, label %{fall}")
            self.put_label(taken)
            self.count_taken()
            self.goto(pc + insn.imm, self.cycles(BRANCH_TAKEN_CYCLES))
            self.put_label(fall)
            self.goto(pc + 4, self.cycles(BRANCH_NOT_TAKEN_CYCLES))
        elif name == "jal":
            self.set_reg(insn.rd, str(_i32(pc + 4)))
            self.count_end()
            self.goto(pc + insn.imm, self.cycles(JUMP_CYCLES))
        else:  # jalr: the target is checked as the interpreter's fetch_error does
            a, s, tgt = self.reg(insn.rs1), self.tmp(), self.tmp()
            self.emit(f"{s} = add i32 {a}, {insn.imm}")
            self.emit(f"{tgt} = and i32 {s}, -2")
            m, off, bad1, bad2, bad = self.tmp(), self.tmp(), self.tmp(), self.tmp(), self.tmp()
            self.emit(f"{m} = and i32 {tgt}, 3")
            self.emit(f"{bad1} = icmp ne i32 {m}, 0")
            self.emit(f"{off} = sub i32 {tgt}, {_i32(self.t.base)}")
            self.emit(f"{bad2} = icmp uge i32 {off}, {_i32(self.t.code_size)}")
            self.emit(f"{bad} = or i1 {bad1}, {bad2}")
            self.side_exit(bad, j, pc, "jr")
            self.set_reg(insn.rd, str(_i32(pc + 4)))
            self.count_end()
            cyc = self.cycles(JUMP_CYCLES)
            targets = self.returns if (insn.rd, insn.rs1, insn.imm) == (0, 1, 0) else []
            labels = [self.label("ret") for _ in targets]
            other = self.label("other")
            cases = " ".join(f"i32 {_i32(t)}, label %{lb}" for t, lb in zip(targets, labels, strict=True))
            self.flush()
            self.emit(f"switch i32 {tgt}, label %{other} [ {cases} ]")
            for t, lb in zip(targets, labels, strict=True):
                self.put_label(lb)
                self.branch(t, cyc)
            self.put_label(other)
            z = self.tmp()
            self.emit(f"{z} = zext i32 {tgt} to i64")
            self.jump(z, cyc)

    def insn(self, j: int, insn: Insn) -> None:
        name = insn.name
        if insn.ins.timing in (Timing.BRANCH, Timing.JUMP):
            return  # the block's end
        if name in _LOADS or name in _STORES:
            self.memory(j, insn)
            return
        if insn.ins.timing is Timing.MULTIPLY:
            self.multiply(insn)
            return
        v = self.tmp()
        if name in _ALU_RR:
            a, b = self.reg(insn.rs1), self.reg(insn.rs2)
            self.emit(f"{v} = {_ALU_RR[name]} i32 {a}, {b}")
        elif name in _ALU_RI:
            a = self.reg(insn.rs1)
            self.emit(f"{v} = {_ALU_RI[name]} i32 {a}, {_i32(insn.imm)}")
        elif name in _SHIFT_I:
            a = self.reg(insn.rs1)
            self.emit(f"{v} = {_SHIFT_I[name]} i32 {a}, {insn.imm}")
        elif name in _SHIFT_R:
            a, b, s = self.reg(insn.rs1), self.reg(insn.rs2), self.tmp()
            self.emit(f"{s} = and i32 {b}, 31")
            self.emit(f"{v} = {_SHIFT_R[name]} i32 {a}, {s}")
        elif name in _SET:
            a = self.reg(insn.rs1)
            b = self.reg(insn.rs2) if insn.ins.fmt is Fmt.R else str(_i32(insn.imm))
            cond = self.tmp()
            self.emit(f"{cond} = icmp {_SET[name]} i32 {a}, {b}")
            self.emit(f"{v} = zext i1 {cond} to i32")
        elif name == "lui":
            v = str(_i32(insn.imm))
        elif name == "auipc":
            v = str(_i32(insn.pc + insn.imm))
        elif name == "fence":
            v = ""
        else:
            raise AssertionError(f"no IR for {name}")
        if v:
            self.set_reg(insn.rd, v)
        self.pending += SINGLE_CYCLES

    def memory(self, j: int, insn: Insn) -> None:
        name = insn.name
        load = name in _LOADS
        bits, ext = _LOADS[name][:2] if load else (_STORES[name][0], "")
        a, addr, off = self.reg(insn.rs1), self.tmp(), self.tmp()
        self.emit(f"{addr} = add i32 {a}, {insn.imm}")
        self.emit(f"{off} = sub i32 {addr}, {_i32(self.t.base)}")
        check = self.checks.get(j)
        if check is not None:
            self.check_memory(j, insn, check, off)
        z, p = self.tmp(), self.tmp()
        self.emit(f"{z} = zext i32 {off} to i64")
        self.emit(f"{p} = getelementptr i8, i8* %mem, i64 {z}")
        ty = f"i{bits}"
        q = p
        if bits != 8:
            q = self.tmp()
            self.emit(f"{q} = bitcast i8* {p} to {ty}*")
        self.pending += MEMORY_CYCLES
        if load:
            v = self.tmp()
            self.emit(f"{v} = load {ty}, {ty}* {q}, align {bits // 8}")
            if bits != 32:
                w = self.tmp()
                self.emit(f"{w} = {ext} {ty} {v} to i32")
                v = w
            self.set_reg(insn.rd, v)
            return
        v = self.reg(insn.rs2)
        if bits != 32:
            w = self.tmp()
            self.emit(f"{w} = trunc i32 {v} to {ty}")
            v = w
        self.emit(f"store {ty} {v}, {ty}* {q}, align {bits // 8}")

    def check_memory(self, j: int, insn: Insn, check: MemoryCheck, off: str) -> None:
        """Leave before instruction ``j`` unless every access of its group is in its part and aligned.

        ``off`` is instruction ``j``'s offset from SRAM's base.  A group of one is one compare: the
        offset into the part rotated right by log2(size) is an aligned access's index, and a
        misaligned one has its low bits on top, beyond any index (the part's start and size are
        whole words).  A larger group compares the lowest offset of its span with the last one the
        span fits at, and tests the alignment of its widest access.
        """
        part = off
        shift = check.align.bit_length()
        if check.start or check.low != insn.imm:
            part = self.tmp()
            self.emit(f"{part} = sub i32 {off}, {_i32(check.start + insn.imm - check.low)}")
        room = self.t.mem_size - check.start
        bad = self.tmp()
        if check.span == check.align + 1 and check.low == check.anchor:  # one access (or one word)
            index = part
            if shift:
                index = self.tmp()
                self.emit(f"{index} = call i32 @llvm.fshr.i32(i32 {part}, i32 {part}, i32 {shift})")
                self.uses_fshr = True
            self.emit(f"{bad} = icmp uge i32 {index}, {_i32(room >> shift)}")
        elif not shift:
            self.emit(f"{bad} = icmp ugt i32 {part}, {_i32(room - check.span)}")
        else:
            out, low, mis = self.tmp(), self.tmp(), self.tmp()
            self.emit(f"{out} = icmp ugt i32 {part}, {_i32(room - check.span)}")
            self.emit(f"{low} = and i32 {off}, {check.align}")
            skew = (check.anchor - insn.imm) & check.align
            self.emit(f"{mis} = icmp ne i32 {low}, {(-skew) & check.align}")
            self.emit(f"{bad} = or i1 {out}, {mis}")
        self.side_exit(bad, j, insn.pc, "m")

    def multiply(self, insn: Insn) -> None:
        self.uses_mul = True
        name = insn.name
        a, b = self.reg(insn.rs1), self.reg(insn.rs2)
        p, h, v, x, y = self.tmp(), self.tmp(), self.tmp(), self.tmp(), self.tmp()
        if name == "mul":
            self.emit(f"{v} = mul i32 {a}, {b}")
        else:
            signed_a = name in ("mulh", "mulhsu") and not (name == "mulhsu" and self.t.rtl_errata)
            signed_b = name == "mulh"
            # the RTL's MULHSU returns the MULHU result (erratum): both unsigned in rtl mode
            self.emit(f"{x} = {'sext' if signed_a else 'zext'} i32 {a} to i64")
            self.emit(f"{y} = {'sext' if signed_b else 'zext'} i32 {b} to i64")
            self.emit(f"{p} = mul i64 {x}, {y}")
            self.emit(f"{h} = lshr i64 {p}, 32")
            self.emit(f"{v} = trunc i64 {h} to i32")
        self.set_reg(insn.rd, v)
        st = self.ctx_ptr(CTX_ST)
        if name == "mulhsu":
            self.add_i64(self.field(st, S_MULHSU_COUNT), 1)
            pp = self.field(st, S_MULHSU_PC)
            old, neg, new = self.tmp(), self.tmp(), self.tmp()
            self.emit(f"{old} = load i64, i64* {pp}")
            self.emit(f"{neg} = icmp slt i64 {old}, 0")
            self.emit(f"{new} = select i1 {neg}, i64 {insn.pc}, i64 {old}")
            self.emit(f"store i64 {new}, i64* {pp}")
        lat, stall = self.tmp(), self.tmp()
        self.emit(f"{lat} = call i64 @mul_latency(i32 {b})")
        self.emit(f"{stall} = add i64 {lat}, -1")
        self.add_i64(self.field(self.ctx_ptr(CTX_CTR), C_MUL_STALL), stall)
        self.cyc = self.cycles(lat)
        self.pending = 0
        self.emit(f"store i64 {self.cyc}, i64* {self.field(st, S_MUL_END)}")  # the controller's erratum window


def _mul_latency_ir() -> str:
    """mul_latency(i32 rs2) -> i64: three byte-table lookups as kernels.core.mul_latency does, then the tail."""
    lines = [
        f"@mulchunk = internal unnamed_addr constant [8192 x i8] {_bytes_const(_MUL_CHUNK.reshape(-1))}",
        f"@multail = internal unnamed_addr constant [1024 x i8] {_bytes_const(_TAIL.reshape(-1))}",
        "define internal i64 @mul_latency(i32 %b32) nounwind readnone alwaysinline {",
        "  %b = zext i32 %b32 to i64",
        "  %a0 = add i64 0, " + str(MUL_BASE_CYCLES),  # cycles so far
        "  %o0 = add i64 0, 0",  # the table row: where the previous byte left the counter
    ]
    for k in range(3):  # byte k of rs2 (11 bits: the table looks 3 bits ahead), from row o{k}
        lines += [
            f"  %h{k} = lshr i64 %b, {8 * k}",
            f"  %x{k} = and i64 %h{k}, 2047",
            f"  %r{k} = shl i64 %o{k}, 11",
            f"  %w{k} = or i64 %r{k}, %x{k}",
            f"  %g{k} = getelementptr [8192 x i8], [8192 x i8]* @mulchunk, i64 0, i64 %w{k}",
            f"  %eb{k} = load i8, i8* %g{k}",
            f"  %e{k} = zext i8 %eb{k} to i64",
            f"  %s{k} = lshr i64 %e{k}, 4",
            f"  %a{k + 1} = add i64 %a{k}, %s{k}",
            f"  %o{k + 1} = and i64 %e{k}, 15",
        ]
    lines += [
        "  %top = lshr i64 %b, 24",
        "  %r3 = shl i64 %o3, 8",
        "  %w3 = or i64 %r3, %top",
        "  %g3 = getelementptr [1024 x i8], [1024 x i8]* @multail, i64 0, i64 %w3",
        "  %tb = load i8, i8* %g3",
        "  %t = zext i8 %tb to i64",
        "  %lat = add i64 %a3, %t",
        "  ret i64 %lat",
        "}",
    ]
    return "\n".join(lines)


_MUL_LATENCY_IR = _mul_latency_ir()
_FSHR_DECLARATION = "declare i32 @llvm.fshr.i32(i32, i32, i32)"


def emit_region(target: Target, region: Region, name: str = NAME_PLACEHOLDER) -> EmittedRegion:
    """The IR module of ``region``: one function named ``name``, its blocks numbered in address order.

    The dispatch loop passes the tile's per-operation counters as ``opc``.
    """
    w = _Writer(target, region, name)
    w.function()
    text = "\n".join([_MUL_LATENCY_IR if w.uses_mul else "", _FSHR_DECLARATION if w.uses_fshr else "", *w.lines, ""])
    return EmittedRegion(ir=text, function=name, blocks=dict(w.index))
