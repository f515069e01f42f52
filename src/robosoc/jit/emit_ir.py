"""LLVM IR of one region: each block checks the next event, counts itself, then runs its instructions.

The IR is written as text (faster to produce than llvmlite's builder objects).  The function takes
the addresses of the dispatch context and of the core's arrays (registers, SRAM bytes, predecode
rows, translated-word map, count slots, state, counters), all distinct arrays, hence ``noalias``::

    i32 @name(ctx, regs, mem, dec, tmap, cnt, st, ctr)

and returns an X_* code of :mod:`robosoc.kernels.jit_dispatch`.  Guest registers stay in the
register array (one load/store each; LLVM forwards them inside a block), the cycle count is a
local that LLVM folds into one add per block.  Costs come from the timing classes of
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
from robosoc.jit.regions import Block, End, Insn, Region
from robosoc.kernels.core import _MUL_CHUNK
from robosoc.kernels.core_layout import C_MUL_STALL, C_TAKEN, S_MUL_END, S_MULHSU_COUNT, S_MULHSU_PC
from robosoc.kernels.jit_dispatch import CTX_BLOCK, CTX_CYC, CTX_LIMIT, CTX_PC, X_JUMP, X_LIMIT, X_SIDE, X_SMC

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
    return "c\"" + "".join(f"\\{b:02X}" for b in data) + "\""


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
    slots: list[list[tuple[int, int]]] = field(default_factory=list)  # histogram (opc index, delta) per slot


class _Writer:
    def __init__(self, target: Target, region: Region, slot_base: int) -> None:
        self.t = target
        self.region = region
        self.slot_base = slot_base
        self.slots: list[list[tuple[int, int]]] = []
        self.lines: list[str] = []
        self.n = 0
        self.uses_mul = False
        self.index = {pc: k for k, pc in enumerate(region.blocks)}

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

    # --- state ------------------------------------------------------------------------------
    def reg(self, r: int) -> str:
        if r == 0:
            return "0"
        v = self.tmp()
        self.emit(f"{v} = load i32, i32* %r{r}")
        return v

    def set_reg(self, rd: int, value: str) -> None:
        self.emit(f"store i32 {value}, i32* %r{rd if rd != 0 else SINK}")

    def cyc_add(self, n: int | str) -> None:
        a, b = self.tmp(), self.tmp()
        self.emit(f"{a} = load i64, i64* %cycp")
        self.emit(f"{b} = add i64 {a}, {n}")
        self.emit(f"store i64 {b}, i64* %cycp")

    def add_i64(self, ptr: str, n: int | str) -> None:
        a, b = self.tmp(), self.tmp()
        self.emit(f"{a} = load i64, i64* {ptr}")
        self.emit(f"{b} = add i64 {a}, {n}")
        self.emit(f"store i64 {b}, i64* {ptr}")

    def slot(self, hist: list[tuple[int, int]]) -> int:
        self.slots.append(hist)
        return self.slot_base + len(self.slots) - 1

    def count(self, slot: int) -> None:
        p = self.tmp()
        self.emit(f"{p} = getelementptr i64, i64* %cnt, i64 {slot}")
        self.add_i64(p, 1)

    def leave(self, code: int, pc: int | str, slot: int | None = None) -> None:
        """Write pc and cycle to ctx and return ``code``."""
        if isinstance(pc, str):
            z = self.tmp()
            self.emit(f"{z} = zext i32 {pc} to i64")
            pc = z
        self.emit(f"store i64 {pc}, i64* %ctx_pc")
        c = self.tmp()
        self.emit(f"{c} = load i64, i64* %cycp")
        self.emit(f"store i64 {c}, i64* %ctx_cyc")
        if slot is not None:
            self.count(slot)
        self.emit(f"ret i32 {code}")

    def goto(self, pc: int) -> None:
        """Continue at ``pc``: the block there, or leave the region."""
        if pc in self.index:
            self.emit(f"br label %b{self.index[pc]}")
        else:
            self.leave(X_JUMP, pc)

    def branch_out(self, cond: str, stem: str) -> str:
        """Branch to a new cold label when ``cond``; returns the cold label (emitted later by the caller)."""
        cold, ok = self.label(f"{stem}.x"), self.label(f"{stem}.ok")
        self.emit(f"br i1 {cond}, label %{cold}, label %{ok}")
        self.pending = ok
        return cold

    # --- instructions -------------------------------------------------------------------------
    def kc(self, insn: Insn) -> int:
        return 2 * insn.op + (((insn.pc - self.t.base) >> 2) & 1)

    def suffix(self, block: Block, k: int) -> list[tuple[int, int]]:
        return [(self.kc(i), -1) for i in block.insns[k:]]

    def block(self, block: Block) -> None:
        k = self.index[block.start]
        worst = sum(WORST_CYCLES[i.ins.timing] for i in block.insns[:-1])
        self.put_label(f"b{k}")
        c, e, ok = self.tmp(), self.tmp(), self.tmp()
        self.emit(f"{c} = load i64, i64* %cycp")
        self.emit(f"{e} = add i64 {c}, {worst}")
        self.emit(f"{ok} = icmp slt i64 {e}, %limit")
        self.emit(f"br i1 {ok}, label %b{k}.go, label %b{k}.lim")
        self.put_label(f"b{k}.lim")
        self.leave(X_LIMIT, block.start)
        self.put_label(f"b{k}.go")
        if block.insns:
            self.count(self.slot([(self.kc(i), 1) for i in block.insns]))
        for j, insn in enumerate(block.insns):
            self.insn(block, j, insn)
        last = block.insns[-1] if block.insns else None
        match block.end:
            case End.FALL:
                self.goto(block.next_pc)
            case End.SIDE:
                self.leave(X_SIDE, block.next_pc)
            case End.BRANCH | End.JUMP | End.CALL | End.JALR:
                assert last is not None
                self.control(block, last)

    def control(self, block: Block, insn: Insn) -> None:
        pc = insn.pc
        name = insn.name
        if name in _BRANCH:
            a, b, cond = self.reg(insn.rs1), self.reg(insn.rs2), self.tmp()
            self.emit(f"{cond} = icmp {_BRANCH[name]} i32 {a}, {b}")
            taken, fall = self.label("tk"), self.label("nt")
            self.emit(f"br i1 {cond}, label %{taken}, label %{fall}")
            self.put_label(taken)
            self.cyc_add(BRANCH_TAKEN_CYCLES)
            self.add_i64("%ctr_taken", 1)
            self.goto((pc + insn.imm) & M32)
            self.put_label(fall)
            self.cyc_add(BRANCH_NOT_TAKEN_CYCLES)
            self.goto(pc + 4)
        elif name == "jal":
            self.set_reg(insn.rd, str(_i32(pc + 4)))
            self.cyc_add(JUMP_CYCLES)
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
            cold = self.branch_out(bad, "jr")
            ok = self.pending
            self.put_label(cold)
            self.leave(X_SIDE, pc, self.slot(self.suffix(block, len(block.insns) - 1)))
            self.put_label(ok)
            self.set_reg(insn.rd, str(_i32(pc + 4)))
            self.cyc_add(JUMP_CYCLES)
            self.leave(X_JUMP, tgt)

    def insn(self, block: Block, j: int, insn: Insn) -> None:
        name = insn.name
        if insn.ins.timing in (Timing.BRANCH, Timing.JUMP):
            return  # the block's end
        if name in _LOADS or name in _STORES:
            self.memory(block, j, insn)
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
        elif name in ("slt", "sltu", "slti", "sltiu"):
            a = self.reg(insn.rs1)
            b = self.reg(insn.rs2) if name in ("slt", "sltu") else str(_i32(insn.imm))
            cond = self.tmp()
            self.emit(f"{cond} = icmp {'ult' if name.startswith('sltu') or name == 'sltiu' else 'slt'} i32 {a}, {b}")
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
        self.cyc_add(SINGLE_CYCLES)

    def memory(self, block: Block, j: int, insn: Insn) -> None:
        name = insn.name
        load = name in _LOADS
        bits, ext, align = _LOADS[name] if load else (_STORES[name][0], "", _STORES[name][1])
        a, addr, off = self.reg(insn.rs1), self.tmp(), self.tmp()
        self.emit(f"{addr} = add i32 {a}, {insn.imm}")
        self.emit(f"{off} = sub i32 {addr}, {_i32(self.t.base)}")
        bad = self.tmp()
        self.emit(f"{bad} = icmp uge i32 {off}, {_i32(self.t.mem_size)}")
        if align:
            m, mis, both = self.tmp(), self.tmp(), self.tmp()
            self.emit(f"{m} = and i32 {off}, {align}")
            self.emit(f"{mis} = icmp ne i32 {m}, 0")
            self.emit(f"{both} = or i1 {bad}, {mis}")
            bad = both
        cold = self.branch_out(bad, "m")
        ok = self.pending
        self.put_label(cold)
        self.leave(X_SIDE, insn.pc, self.slot(self.suffix(block, j)))
        self.put_label(ok)
        z, p = self.tmp(), self.tmp()
        self.emit(f"{z} = zext i32 {off} to i64")
        self.emit(f"{p} = getelementptr i8, i8* %mem, i64 {z}")
        ty = f"i{bits}"
        q = p
        if bits != 8:
            q = self.tmp()
            self.emit(f"{q} = bitcast i8* {p} to {ty}*")
        if load:
            v = self.tmp()
            self.emit(f"{v} = load {ty}, {ty}* {q}, align {bits // 8}")
            if bits != 32:
                w = self.tmp()
                self.emit(f"{w} = {ext} {ty} {v} to i32")
                v = w
            self.set_reg(insn.rd, v)
            self.cyc_add(MEMORY_CYCLES)
            return
        v = self.reg(insn.rs2)
        if bits != 32:
            w = self.tmp()
            self.emit(f"{w} = trunc i32 {v} to {ty}")
            v = w
        self.emit(f"store {ty} {v}, {ty}* {q}, align {bits // 8}")
        self.cyc_add(MEMORY_CYCLES)
        code_words = self.t.code_size >> 2
        if code_words == 0:
            return
        wi, inside = self.tmp(), self.tmp()
        self.emit(f"{wi} = lshr i32 {off}, 2")
        self.emit(f"{inside} = icmp ult i32 {wi}, {code_words}")
        code_lbl, cont = self.label("code"), self.label("cont")
        self.emit(f"br i1 {inside}, label %{code_lbl}, label %{cont}")
        self.put_label(code_lbl)
        wz, d, dp = self.tmp(), self.tmp(), self.tmp()
        self.emit(f"{wz} = zext i32 {wi} to i64")
        self.emit(f"{d} = shl i64 {wz}, 1")
        self.emit(f"{dp} = getelementptr i32, i32* %dec, i64 {d}")
        self.emit(f"store i32 0, i32* {dp}")  # the word may be code: the interpreter decodes it again
        tp, tv, hit = self.tmp(), self.tmp(), self.tmp()
        self.emit(f"{tp} = getelementptr i8, i8* %tmap, i64 {wz}")
        self.emit(f"{tv} = load i8, i8* {tp}")
        self.emit(f"{hit} = icmp ne i8 {tv}, 0")
        smc = self.label("smc")
        self.emit(f"br i1 {hit}, label %{smc}, label %{cont}")
        self.put_label(smc)
        self.leave(X_SMC, insn.pc + 4, self.slot(self.suffix(block, j + 1)))
        self.put_label(cont)

    def multiply(self, insn: Insn) -> None:
        self.uses_mul = True
        name = insn.name
        a, b = self.reg(insn.rs1), self.reg(insn.rs2)
        sa, sb, za, zb, v = self.tmp(), self.tmp(), self.tmp(), self.tmp(), self.tmp()
        self.emit(f"{sa} = sext i32 {a} to i64")
        self.emit(f"{sb} = sext i32 {b} to i64")
        self.emit(f"{za} = zext i32 {a} to i64")
        self.emit(f"{zb} = zext i32 {b} to i64")
        p, h = self.tmp(), self.tmp()
        if name == "mul":
            self.emit(f"{p} = mul i64 {sa}, {sb}")
            self.emit(f"{v} = trunc i64 {p} to i32")
        else:
            if name == "mulh":
                self.emit(f"{p} = mul i64 {sa}, {sb}")
                self.emit(f"{h} = ashr i64 {p}, 32")
            elif name == "mulhu" or self.t.rtl_errata:  # the RTL's MULHSU returns the MULHU result
                self.emit(f"{p} = mul i64 {za}, {zb}")
                self.emit(f"{h} = lshr i64 {p}, 32")
            else:
                self.emit(f"{p} = mul i64 {sa}, {zb}")
                self.emit(f"{h} = ashr i64 {p}, 32")
            self.emit(f"{v} = trunc i64 {h} to i32")
        self.set_reg(insn.rd, v)
        if name == "mulhsu":
            self.add_i64("%st_mulhsu_n", 1)
            old, neg, new = self.tmp(), self.tmp(), self.tmp()
            self.emit(f"{old} = load i64, i64* %st_mulhsu_pc")
            self.emit(f"{neg} = icmp slt i64 {old}, 0")
            self.emit(f"{new} = select i1 {neg}, i64 {insn.pc}, i64 {old}")
            self.emit(f"store i64 {new}, i64* %st_mulhsu_pc")
        # latency: three byte-table lookups as mul_latency does, then the tail table
        steps: list[str] = []
        off = "0"
        for k in range(3):
            sh, w, idx, base_i, gp, e8, e, s, o = (self.tmp() for _ in range(9))
            self.emit(f"{sh} = lshr i64 {zb}, {8 * k}")
            self.emit(f"{w} = and i64 {sh}, 2047")
            self.emit(f"{base_i} = shl i64 {off}, 11")
            self.emit(f"{idx} = or i64 {base_i}, {w}")
            self.emit(f"{gp} = getelementptr [8192 x i8], [8192 x i8]* @mulchunk, i64 0, i64 {idx}")
            self.emit(f"{e8} = load i8, i8* {gp}")
            self.emit(f"{e} = zext i8 {e8} to i64")
            self.emit(f"{s} = lshr i64 {e}, 4")
            self.emit(f"{o} = and i64 {e}, 15")
            steps.append(s)
            off = o
        top, base_i, idx, gp, t8, tail = (self.tmp() for _ in range(6))
        self.emit(f"{top} = lshr i64 {zb}, 24")
        self.emit(f"{base_i} = shl i64 {off}, 8")
        self.emit(f"{idx} = or i64 {base_i}, {top}")
        self.emit(f"{gp} = getelementptr [1024 x i8], [1024 x i8]* @multail, i64 0, i64 {idx}")
        self.emit(f"{t8} = load i8, i8* {gp}")
        self.emit(f"{tail} = zext i8 {t8} to i64")
        acc = tail
        for s in steps:
            nxt = self.tmp()
            self.emit(f"{nxt} = add i64 {acc}, {s}")
            acc = nxt
        lat = self.tmp()
        self.emit(f"{lat} = add i64 {acc}, {MUL_BASE_CYCLES}")
        stall = self.tmp()
        self.emit(f"{stall} = add i64 {lat}, -1")
        self.add_i64("%ctr_mulstall", stall)
        self.cyc_add(lat)
        c = self.tmp()
        self.emit(f"{c} = load i64, i64* %cycp")
        self.emit(f"store i64 {c}, i64* %st_mulend")  # the interrupt controller's erratum window


def emit_region(target: Target, region: Region, name: str = NAME_PLACEHOLDER) -> EmittedRegion:
    """The IR module of ``region`` as function ``name``.

    Count slots are numbered from 0: the dispatch loop passes the region's first slot as ``cnt``.
    """
    w = _Writer(target, region, 0)
    body_start = len(w.lines)
    for block in region.blocks.values():
        w.block(block)
    body = w.lines[body_start:]
    head = [
        f"define i32 @{name}(i8* noalias %ctxp, i8* noalias %regsp, i8* noalias %mem, i8* noalias %decp, "
        "i8* noalias %tmap, i8* noalias %cntp, i8* noalias %stp, i8* noalias %ctrp) nounwind {",
        "entry:",
        "  %ctx = bitcast i8* %ctxp to i64*",
        "  %regs = bitcast i8* %regsp to i32*",
        "  %dec = bitcast i8* %decp to i32*",
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
        "  %cycp = alloca i64",
        "  %cyc0 = load i64, i64* %ctx_cyc",
        "  store i64 %cyc0, i64* %cycp",
        "  %limit = load i64, i64* %ctx_limit",
        "  %blk = load i64, i64* %ctx_block",
        "  switch i64 %blk, label %bad [ " + " ".join(f"i64 {k}, label %b{k}" for k in w.index.values()) + " ]",
        "bad:",
        "  unreachable",
    ]
    globals_ = []
    if w.uses_mul:
        globals_ = [
            f"@mulchunk = internal unnamed_addr constant [8192 x i8] {_bytes_const(_MUL_CHUNK.reshape(-1))}",
            f"@multail = internal unnamed_addr constant [1024 x i8] {_bytes_const(_TAIL.reshape(-1))}",
        ]
    text = "\n".join([*globals_, *head, *body, "}", ""])
    return EmittedRegion(name=name, ir=text, block_index=dict(w.index), slots=w.slots)
