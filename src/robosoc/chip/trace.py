"""Instruction traces: the slow, observable path beside the fast kernel loop.

Each step runs the same kernel for exactly one instruction (``until = cycle + 1``), so the trace
shows what the fast path does, cycle for cycle; it is meant for the first instructions of a
program or a window around a problem, not for whole runs.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np

from robosoc.chip.single import SingleCoreSoC
from robosoc.isa.disasm import ABI_NAMES, disassemble
from robosoc.kernels.core_layout import RUN_CHUNK, RUN_OUTPUT


@dataclass(frozen=True)
class TraceRecord:
    cycle: int  # cycle in which the instruction started
    pc: int
    symbol: str
    word: int
    text: str
    writes: tuple[tuple[int, int], ...]  # (register, new value) for every register it changed

    def __str__(self) -> str:
        regs = "  ".join(f"{ABI_NAMES[r]}=0x{v:08x}" for r, v in self.writes)
        return f"{self.cycle:>10}  {self.pc:08x}  {self.word:08x}  {self.text:<28} {self.symbol:<24} {regs}".rstrip()


def trace(soc: SingleCoreSoC, count: int) -> Iterator[TraceRecord]:
    """Execute up to ``count`` instructions one at a time, yielding what each did.

    Stops early when the program exits or fails (the failure is left for ``soc.run`` to report).
    """
    for _ in range(count):
        pc, cycle = soc.state.pc, soc.cycle
        word = soc.state.word(pc) if soc.state.base <= pc < soc.state.base + soc.state.size else 0
        before = soc.regs.copy()
        status = soc.step_until(cycle + 1)
        after = soc.regs
        changed = np.nonzero(before != after)[0]
        writes = tuple((int(r), int(after[r]) & 0xFFFFFFFF) for r in changed)
        yield TraceRecord(cycle, pc, soc.symbolize(pc), word, disassemble(word, pc), writes)
        if status not in (RUN_CHUNK, RUN_OUTPUT):
            return
