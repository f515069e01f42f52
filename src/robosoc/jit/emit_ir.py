"""LLVM IR of one region: each block checks the next event, counts itself, then runs its instructions.

The IR is written as text (faster to produce than llvmlite's builder objects).  The function takes
the addresses of the dispatch context and of the core's arrays (registers, SRAM bytes, count
slots, state, counters), all distinct arrays, hence ``noalias``::

    i32 @name(ctx, regs, mem, cnt, st, ctr)

and returns an X_* code of :mod:`robosoc.kernels.jit_dispatch`.  Guest registers stay in the
register array (one load/store each; LLVM forwards them inside a block), the cycle count is a
local that LLVM folds into one add per block.  Loads outside SRAM, stores outside its data part
(devices, and the loaded code: self-modifying code) and misaligned accesses leave the region
before the instruction, for the interpreter.  Costs come from the timing classes of
:mod:`robosoc.isa.table`; instruction counts are count slots (see the dispatch module).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from robosoc.isa.table import (
    BRANCH_NOT_TAKEN_CYCLES,
    BRANCH_TAKEN_CYCLES,
    JUMP_CYCLES,
    MEMORY_CYCLES,
    MUL_BASE_CYCLES,
    SINGLE_CYCLES,
    Timing,
)
from robosoc.isa.table import Fmt
from robosoc.jit.regions import Block, End, Insn, Region
from robosoc.kernels.core import _MUL_CHUNK
from robosoc.kernels.core_layout import C_MUL_STALL, C_TAKEN, S_MUL_END, S_MULHSU_COUNT, S_MULHSU_PC
from robosoc.kernels.jit_dispatch import (
    CTX_BLOCK,
    CTX_CNT,
    CTX_CYC,
    CTX_ENTRY_BLK,
    CTX_ENTRY_FN,
    CTX_ENTRY_SLOT,
    CTX_LIMIT,
    CTX_PC,
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


_ALU_RR = {"add": "add", "sub": "sub", "xor": "xor", "or": "or", "and": "and"}
_ALU_RI = {"addi": "add", "xori": "xor", "ori": "or", "andi": "and"}
_SHIFT_I = {"slli": "shl", "srli": "lshr", "srai": "ashr"}
_SHIFT_R = {"sll": "shl", "srl": "lshr", "sra": "ashr"}
_BRANCH = {"beq": "eq", "bne": "ne", "blt": "slt", "bge": "sge", "bltu": "ult", "bgeu": "uge"}
_LOADS = {"lb": (8, "sext", 0), "lbu": (8, "zext", 0), "lh": (16, "sext", 1), "lhu": (16, "zext", 1), "lw": (32, "", 3)}
_STORES = {"sb": (8, 0), "sh": (16, 1), "sw": (32, 3)}


@dataclass(frozen=True)
class Target:
    """What the translated code is specialised for (all of it is part of the cache key)."""

    base: int
    mem_size: int
    code_size: int
    rtl_errata: bool


@dataclass
class EmittedRegion:
    name: str
    ir: str
    block_index: dict[int, int]  # block start pc -> switch value
    #: count slots: (histogram as (opc index, delta) pairs, next slot or -1); a slot's executions are
    #: also added to its next slot's (the chain of side-exit suffixes)
    slots: list[tuple[list[tuple[int, int]], int]] = field(default_factory=list)


class _Writer:
    """Writes one region.  Register values and the cycles since the last store of the cycle count
    are tracked per straight-line path, so an instruction is its operation plus one register store.
    """

    def __init__(self, target: Target, region: Region) -> None:
        self.t = target
        self.region = region
        self.slots: list[tuple[list[tuple[int, int]], int]] = []
        self.lines: list[str] = []
        self.n = 0
        self.uses_mul = False
        self.index = {pc: k for k, pc in enumerate(region.blocks)}
        self.exits: list[tuple[str, int, str, int, int]] = []  # (label, code, pc i64, cycles, slot)
        self.cur = "entry"
        self.regs: dict[int, str] = {}
        self.cyc = ""  # SSA value equal to the cycle count in %cycp
        self.pending = 0  # cycles of the instructions since then

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
    def reg(self, r: int) -> str:
        if r == 0:
            return "0"
        v = self.regs.get(r)
        if v is None:
            v = self.tmp()
            self.emit(f"{v} = load i32, i32* %r{r}")
            self.regs[r] = v
        return v

    def set_reg(self, rd: int, value: str) -> None:
        self.emit(f"store i32 {value}, i32* %r{rd if rd != 0 else SINK}")
        if rd != 0:
            self.regs[rd] = value

    def store_cycles(self, extra: int | str = 0) -> None:
        """Make %cycp hold the cycle count plus ``extra``."""
        v = self.cyc
        if self.pending:
            w = self.tmp()
            self.emit(f"{w} = add i64 {v}, {self.pending}")
            v = w
        if extra != 0:
            w = self.tmp()
            self.emit(f"{w} = add i64 {v}, {extra}")
            v = w
        if v != self.cyc:
            self.emit(f"store i64 {v}, i64* %cycp")
        self.cyc = v
        self.pending = 0

    def add_i64(self, ptr: str, n: int | str) -> None:
        a, b = self.tmp(), self.tmp()
        self.emit(f"{a} = load i64, i64* {ptr}")
        self.emit(f"{b} = add i64 {a}, {n}")
        self.emit(f"store i64 {b}, i64* {ptr}")

    def slot(self, hist: list[tuple[int, int]], nxt: int = -1) -> int:
        self.slots.append((hist, nxt))
        return len(self.slots) - 1

    def exit_edge(self, code: int, pc: int | str, slot: int = -1, cycles: int | None = None) -> str:
        """A new exit block for the current path (emitted at the end); the caller branches to it."""
        name = self.label("x")
        self.exits.append((name, code, str(pc), self.pending if cycles is None else cycles, slot))
        return name

    def leave(self, code: int, pc: int | str, slot: int = -1) -> None:
        if isinstance(pc, str):
            z = self.tmp()
            self.emit(f"{z} = zext i32 {pc} to i64")
            pc = z
        x = self.exit_edge(code, pc, slot)
        self.emit(f"br label %{x}")

    def goto(self, pc: int) -> None:
        """Continue at ``pc`` (cycles stored): the block there, or leave the region."""
        if pc in self.index:
            self.emit(f"br label %b{self.index[pc]}")
        else:
            self.leave(X_JUMP, pc)

    def cond_exit(self, cond: str, code: int, pc: int, slot: int, stem: str) -> None:
        """Leave through the shared exit when ``cond``, else go on in a new label."""
        ok = self.label(stem)
        x = self.exit_edge(code, pc, slot)
        self.emit(f"br i1 {cond}, label %{x}, label %{ok}")
        self.put_label(ok)

    # --- counting -----------------------------------------------------------------------------
    def kc(self, insn: Insn) -> int:
        return 2 * insn.op + (((insn.pc - self.t.base) >> 2) & 1)

    def block(self, block: Block) -> None:
        k = self.index[block.start]
        insns = block.insns
        worst = sum(WORST_CYCLES[i.ins.timing] for i in insns[:-1])
        self.put_label(f"b{k}")
        self.regs = {}
        c, e, ok = self.tmp(), self.tmp(), self.tmp()
        self.emit(f"{c} = load i64, i64* %cycp")
        self.cyc, self.pending = c, 0
        self.emit(f"{e} = add i64 {c}, {worst}")
        self.emit(f"{ok} = icmp slt i64 {e}, %limit")
        x = self.exit_edge(X_LIMIT, block.start, -1, 0)
        self.emit(f"br i1 {ok}, label %b{k}.go, label %{x}")
        self.put_label(f"b{k}.go")
        kcs = [self.kc(i) for i in insns]
        # side exits at instruction j leave j.. uncounted: a chain of suffix slots, one per exit point
        points = [j for j, i in enumerate(insns) if i.name in _LOADS or i.name in _STORES or i.name == "jalr"]
        self.suffix: dict[int, int] = {}
        nxt = -1
        ends = [*points[1:], len(insns)] if points else []
        for j, end in reversed(list(zip(points, ends, strict=True))):
            nxt = self.slot([(kc, -1) for kc in kcs[j:end]], nxt)
            self.suffix[j] = nxt
        if insns:
            slot = self.slot([(kc, 1) for kc in kcs])
            self.add_i64(f"%cnt.{slot}", 1)
        for j, insn in enumerate(insns):
            self.insn(j, insn)
        match block.end:
            case End.FALL:
                self.store_cycles()
                self.goto(block.next_pc)
            case End.SIDE:
                self.leave(X_SIDE, block.next_pc)
            case End.BRANCH | End.JUMP | End.CALL | End.JALR:
                self.control(len(insns) - 1, insns[-1])

    # --- instructions -------------------------------------------------------------------------
    def control(self, j: int, insn: Insn) -> None:
        pc = insn.pc
        name = insn.name
        if name in _BRANCH:
            a, b, cond = self.reg(insn.rs1), self.reg(insn.rs2), self.tmp()
            self.emit(f"{cond} = icmp {_BRANCH[name]} i32 {a}, {b}")
            taken, fall = self.label("tk"), self.label("nt")
            self.emit(f"br i1 {cond}, label %{taken}, label %{fall}")
            cyc, pending = self.cyc, self.pending
            self.put_label(taken)
            self.store_cycles(BRANCH_TAKEN_CYCLES)
            self.add_i64("%ctr_taken", 1)
            self.goto((pc + insn.imm) & M32)
            self.put_label(fall)
            self.cyc, self.pending = cyc, pending
            self.store_cycles(BRANCH_NOT_TAKEN_CYCLES)
            self.goto(pc + 4)
        elif name == "jal":
            self.set_reg(insn.rd, str(_i32(pc + 4)))
            self.store_cycles(JUMP_CYCLES)
            target = (pc + insn.imm) & M32
            if insn.rd == 0:
                self.goto(target)
            else:
                self.leave(X_JUMP, target)
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
            self.cond_exit(bad, X_SIDE, pc, self.suffix[j], "jr")
            self.set_reg(insn.rd, str(_i32(pc + 4)))
            self.store_cycles(JUMP_CYCLES)
            self.leave(X_JUMP, tgt)

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
        bits, ext, align = _LOADS[name] if load else (_STORES[name][0], "", _STORES[name][1])
        a, addr, off = self.reg(insn.rs1), self.tmp(), self.tmp()
        self.emit(f"{addr} = add i32 {a}, {insn.imm}")
        self.emit(f"{off} = sub i32 {addr}, {_i32(self.t.base)}")
        bad = self.tmp()
        if load:
            self.emit(f"{bad} = icmp uge i32 {off}, {_i32(self.t.mem_size)}")
        else:  # stores into the loaded code are the interpreter's (self-modifying code)
            data = self.tmp()
            self.emit(f"{data} = sub i32 {off}, {_i32(self.t.code_size)}")
            self.emit(f"{bad} = icmp uge i32 {data}, {_i32(self.t.mem_size - self.t.code_size)}")
        if align:
            m, mis, both = self.tmp(), self.tmp(), self.tmp()
            self.emit(f"{m} = and i32 {off}, {align}")
            self.emit(f"{mis} = icmp ne i32 {m}, 0")
            self.emit(f"{both} = or i1 {bad}, {mis}")
            bad = both
        self.cond_exit(bad, X_SIDE, insn.pc, self.suffix[j], "m")
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
        if name == "mulhsu":
            self.add_i64("%st_mulhsu_n", 1)
            old, neg, new = self.tmp(), self.tmp(), self.tmp()
            self.emit(f"{old} = load i64, i64* %st_mulhsu_pc")
            self.emit(f"{neg} = icmp slt i64 {old}, 0")
            self.emit(f"{new} = select i1 {neg}, i64 {insn.pc}, i64 {old}")
            self.emit(f"store i64 {new}, i64* %st_mulhsu_pc")
        lat, stall = self.tmp(), self.tmp()
        self.emit(f"{lat} = call i64 @mul_latency(i32 {b})")
        self.emit(f"{stall} = add i64 {lat}, -1")
        self.add_i64("%ctr_mulstall", stall)
        self.store_cycles(lat)
        self.emit(f"store i64 {self.cyc}, i64* %st_mulend")  # the interrupt controller's erratum window


#: leave(ctx, cnt, cycle, pc, slot, code): the region's way out: pc and cycle to ctx, one count to
#: ``slot`` (none when negative), returns ``code``.  Out of line: exits are many and cold.
_LEAVE_IR = f"""
define internal i32 @leave(i64* %ctx, i64* %cnt, i64 %cyc, i64 %pc, i64 %slot, i32 %code) noinline nounwind {{
  %p = getelementptr i64, i64* %ctx, i64 {CTX_PC}
  store i64 %pc, i64* %p
  %c = getelementptr i64, i64* %ctx, i64 {CTX_CYC}
  store i64 %cyc, i64* %c
  %has = icmp sge i64 %slot, 0
  br i1 %has, label %count, label %done
count:
  %sp = getelementptr i64, i64* %cnt, i64 %slot
  %n0 = load i64, i64* %sp
  %n1 = add i64 %n0, 1
  store i64 %n1, i64* %sp
  br label %done
done:
  ret i32 %code
}}
"""

_PARAMS = (
    "i8* noalias %ctxp, i8* noalias %regsp, i8* noalias %mem, i8* noalias %cntp, i8* noalias %stp, i8* noalias %ctrp"
)
_ARGS = "i8* %ctxp, i8* %regsp, i8* %mem, i8* %cntp, i8* %stp, i8* %ctrp"


def _jump_ir(target: Target) -> str:
    """jump(region arguments): continue at ctx's pc in the region with a block there, else return X_JUMP."""
    return f"""
define internal i32 @jump({_PARAMS}) nounwind {{
  %ctx = bitcast i8* %ctxp to i64*
  %pp = getelementptr i64, i64* %ctx, i64 {CTX_PC}
  %pc = load i64, i64* %pp
  %off = sub i64 %pc, {target.base}
  %i = lshr i64 %off, 2
  %fp = getelementptr i64, i64* %ctx, i64 {CTX_ENTRY_FN}
  %fa = load i64, i64* %fp
  %ft = inttoptr i64 %fa to i64*
  %fe = getelementptr i64, i64* %ft, i64 %i
  %fn = load i64, i64* %fe
  %none = icmp eq i64 %fn, 0
  br i1 %none, label %out, label %go
out:
  ret i32 {X_JUMP}
go:
  %bp = getelementptr i64, i64* %ctx, i64 {CTX_ENTRY_BLK}
  %ba = load i64, i64* %bp
  %bt = inttoptr i64 %ba to i64*
  %be = getelementptr i64, i64* %bt, i64 %i
  %blk = load i64, i64* %be
  %bo = getelementptr i64, i64* %ctx, i64 {CTX_BLOCK}
  store i64 %blk, i64* %bo
  %sp = getelementptr i64, i64* %ctx, i64 {CTX_ENTRY_SLOT}
  %sa = load i64, i64* %sp
  %stt = inttoptr i64 %sa to i64*
  %se = getelementptr i64, i64* %stt, i64 %i
  %slot = load i64, i64* %se
  %cp = getelementptr i64, i64* %ctx, i64 {CTX_CNT}
  %ca = load i64, i64* %cp
  %so = shl i64 %slot, 3
  %cn = add i64 %ca, %so
  %cntp2 = inttoptr i64 %cn to i8*
  %f = inttoptr i64 %fn to i32 ({", ".join(["i8*"] * 6)})*
  %r = musttail call i32 %f(i8* %ctxp, i8* %regsp, i8* %mem, i8* %cntp2, i8* %stp, i8* %ctrp)
  ret i32 %r
}}
"""


_SET = {"slt": "slt", "slti": "slt", "sltu": "ult", "sltiu": "ult"}

#: mul_latency(i32 rs2) -> i64: three byte-table lookups as kernels.core.mul_latency does, then the tail
_MUL_LATENCY_IR = f"""
@mulchunk = internal unnamed_addr constant [8192 x i8] {_bytes_const(_MUL_CHUNK.reshape(-1))}
@multail = internal unnamed_addr constant [1024 x i8] {_bytes_const(_TAIL.reshape(-1))}
define internal i64 @mul_latency(i32 %b32) nounwind readnone {{
  %b = zext i32 %b32 to i64
  %w0 = and i64 %b, 2047
  %g0 = getelementptr [8192 x i8], [8192 x i8]* @mulchunk, i64 0, i64 %w0
  %e0b = load i8, i8* %g0
  %e0 = zext i8 %e0b to i64
  %s0 = lshr i64 %e0, 4
  %o0 = and i64 %e0, 15
  %h1 = lshr i64 %b, 8
  %w1a = and i64 %h1, 2047
  %o0s = shl i64 %o0, 11
  %w1 = or i64 %o0s, %w1a
  %g1 = getelementptr [8192 x i8], [8192 x i8]* @mulchunk, i64 0, i64 %w1
  %e1b = load i8, i8* %g1
  %e1 = zext i8 %e1b to i64
  %s1 = lshr i64 %e1, 4
  %o1 = and i64 %e1, 15
  %h2 = lshr i64 %b, 16
  %w2a = and i64 %h2, 2047
  %o1s = shl i64 %o1, 11
  %w2 = or i64 %o1s, %w2a
  %g2 = getelementptr [8192 x i8], [8192 x i8]* @mulchunk, i64 0, i64 %w2
  %e2b = load i8, i8* %g2
  %e2 = zext i8 %e2b to i64
  %s2 = lshr i64 %e2, 4
  %o2 = and i64 %e2, 15
  %top = lshr i64 %b, 24
  %o2s = shl i64 %o2, 8
  %w3 = or i64 %o2s, %top
  %g3 = getelementptr [1024 x i8], [1024 x i8]* @multail, i64 0, i64 %w3
  %tb = load i8, i8* %g3
  %t = zext i8 %tb to i64
  %a1 = add i64 %t, %s0
  %a2 = add i64 %a1, %s1
  %a3 = add i64 %a2, %s2
  %lat = add i64 %a3, {MUL_BASE_CYCLES}
  ret i64 %lat
}}
"""


def emit_region(target: Target, region: Region, name: str = NAME_PLACEHOLDER) -> EmittedRegion:
    """The IR module of ``region`` as function ``name``.

    Count slots are numbered from 0: the dispatch loop passes the region's first slot as ``cnt``.
    """
    w = _Writer(target, region)
    for block in region.blocks.values():
        w.block(block)
    body = w.lines
    exit_lines = []
    for label, code, pc, cycles, slot in w.exits:
        exit_lines += [f"{label}:", f"  %{label}.c = load i64, i64* %cycp", f"  %{label}.d = add i64 %{label}.c, {cycles}"]
        if code == X_JUMP:  # straight into the region translated there, if any (same signature: a true tail call)
            exit_lines += [
                f"  store i64 {pc}, i64* %ctx_pc",
                f"  store i64 %{label}.d, i64* %ctx_cyc",
                f"  %{label}.r = musttail call i32 @jump({_ARGS})",
                f"  ret i32 %{label}.r",
            ]
        else:
            exit_lines += [
                f"  %{label}.r = tail call i32 @leave(i64* %ctx, i64* %cnt, i64 %{label}.d, i64 {pc}, i64 {slot}, i32 {code})",
                f"  ret i32 %{label}.r",
            ]
    slot_geps = [f"  %cnt.{s} = getelementptr i64, i64* %cnt, i64 {s}" for s in range(len(w.slots))]
    head = [
        f"define i32 @{name}({_PARAMS}) nounwind {{",
        "entry:",
        "  %ctx = bitcast i8* %ctxp to i64*",
        "  %regs = bitcast i8* %regsp to i32*",
        "  %cnt = bitcast i8* %cntp to i64*",
        "  %st = bitcast i8* %stp to i64*",
        "  %ctr = bitcast i8* %ctrp to i64*",
        f"  %ctx_pc = getelementptr i64, i64* %ctx, i64 {CTX_PC}",
        f"  %ctx_cyc = getelementptr i64, i64* %ctx, i64 {CTX_CYC}",
        f"  %ctx_limit = getelementptr i64, i64* %ctx, i64 {CTX_LIMIT}",
        f"  %ctx_block = getelementptr i64, i64* %ctx, i64 {CTX_BLOCK}",
        f"  %ctr_taken = getelementptr i64, i64* %ctr, i64 {C_TAKEN}",
        f"  %ctr_mulstall = getelementptr i64, i64* %ctr, i64 {C_MUL_STALL}",
        f"  %st_mulend = getelementptr i64, i64* %st, i64 {S_MUL_END}",
        f"  %st_mulhsu_n = getelementptr i64, i64* %st, i64 {S_MULHSU_COUNT}",
        f"  %st_mulhsu_pc = getelementptr i64, i64* %st, i64 {S_MULHSU_PC}",
        *(f"  %r{r} = getelementptr i32, i32* %regs, i64 {r}" for r in range(1, SINK + 1)),
        *slot_geps,
        "  %cycp = alloca i64",
        "  %cyc0 = load i64, i64* %ctx_cyc",
        "  store i64 %cyc0, i64* %cycp",
        "  %limit = load i64, i64* %ctx_limit",
        "  %blk = load i64, i64* %ctx_block",
        "  switch i64 %blk, label %bad [ " + " ".join(f"i64 {k}, label %b{k}" for k in w.index.values()) + " ]",
        "bad:",
        "  unreachable",
    ]
    text = "\n".join([_LEAVE_IR, _jump_ir(target), _MUL_LATENCY_IR if w.uses_mul else "", *head, *body, *exit_lines, "}", ""])
    return EmittedRegion(name=name, ir=text, block_index=dict(w.index), slots=w.slots)
