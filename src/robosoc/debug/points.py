"""Breakpoints and watchpoints as GDB inserts them, and which instructions the core must stop before.

Breakpoints (Z0 software, Z1 hardware: the same thing here) mark their instruction.  Watchpoints
(Z2 write, Z3 read, Z4 access) mark every load and/or store of the loaded code: the core stops
before each, the stub computes the address from the registers (rs1 + offset) and reports the
watchpoint only when the access overlaps a watched range; otherwise the core executes the
access and runs on.  The program sees nothing of this (marks live in the predecode table and
cost no cycle), GDB sees the stop before the access as it expects on RISC-V (a "non-steppable"
watchpoint: GDB steps over the access itself and compares the values).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import IntEnum

import numpy as np

from robosoc.isa.fields import imm_i, imm_s, rs1
from robosoc.isa.table import Fmt, lookup

M32 = 0xFFFFFFFF
_LOAD, _STORE = 0x03, 0x23
_SIZES = {"lb": 1, "lbu": 1, "lh": 2, "lhu": 2, "lw": 4, "sb": 1, "sh": 2, "sw": 4}


class Kind(IntEnum):
    """The Z packet types."""

    SOFTWARE = 0
    HARDWARE = 1
    WRITE = 2
    READ = 3
    ACCESS = 4


#: Stop-reply keyword of each watchpoint kind.
WATCH_KEYWORDS = {Kind.WRITE: "watch", Kind.READ: "rwatch", Kind.ACCESS: "awatch"}


@dataclass(frozen=True)
class Access:
    """The memory access an instruction is about to make."""

    addr: int
    size: int
    store: bool


def memory_access(word: int, regs: np.ndarray) -> Access | None:
    """The access of the load or store ``word`` with the registers ``regs`` (None: not one)."""
    ins = lookup(word)
    if ins is None or ins.fmt not in (Fmt.LOAD, Fmt.S):
        return None
    store = ins.fmt == Fmt.S
    offset = imm_s(word) if store else imm_i(word)
    return Access((int(regs[rs1(word)]) + offset) & M32, _SIZES[ins.name], store)


@dataclass
class Points:
    """The breakpoints and watchpoints GDB has inserted."""

    breaks: dict[int, Kind] = field(default_factory=dict)
    watches: set[tuple[Kind, int, int]] = field(default_factory=set)

    def insert(self, kind: Kind, addr: int, length: int) -> None:
        if kind in (Kind.SOFTWARE, Kind.HARDWARE):
            self.breaks[addr] = kind
        else:
            self.watches.add((kind, addr, length))

    def remove(self, kind: Kind, addr: int, length: int) -> None:
        if kind in (Kind.SOFTWARE, Kind.HARDWARE):
            self.breaks.pop(addr, None)
        else:
            self.watches.discard((kind, addr, length))

    def clear(self) -> None:
        self.breaks.clear()
        self.watches.clear()

    def marks(self, code: np.ndarray, base: int) -> np.ndarray:
        """Which words of ``code`` (the loaded code's words from ``base``) the core must stop before."""
        opcode = code.view(np.uint32) & 0x7F
        kinds = {kind for kind, _, _ in self.watches}
        loads = bool(kinds & {Kind.READ, Kind.ACCESS})
        stores = bool(kinds & {Kind.WRITE, Kind.ACCESS})
        mask = ((opcode == _LOAD) & loads) | ((opcode == _STORE) & stores)
        for addr in self.breaks:
            i = (addr - base) // 4
            if 0 <= i < len(mask):
                mask[i] = True
        return mask

    def watch_hit(self, word: int, regs: np.ndarray) -> tuple[Kind, int] | None:
        """The watchpoint the instruction ``word`` is about to trigger: (kind, first watched byte it touches)."""
        if not self.watches:
            return None
        access = memory_access(word, regs)
        if access is None:
            return None
        for kind, addr, length in sorted(self.watches):
            if (kind == Kind.WRITE and not access.store) or (kind == Kind.READ and access.store):
                continue
            lo = max(addr, access.addr)
            if lo < min(addr + length, access.addr + access.size):
                return kind, lo
        return None
