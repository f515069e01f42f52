"""Naming the raw counter arrays of a core: the only place that knows their layout.

Names come from the instruction table: one counter per instruction class (``jump``, ``branch``,
...), and the stall cycles of each timing class under the stall kind the table gives it.
"""

from __future__ import annotations

import numpy as np

from robosoc.isa.table import (
    BRANCH_NOT_TAKEN_CYCLES,
    BRANCH_TAKEN_CYCLES,
    CLASS_NAMES,
    CORE_STALL_KINDS,
    FIXED_EXTRA_CYCLES,
    INSTRUCTIONS,
    STALL_KIND,
    Timing,
)
from robosoc.kernels.core_layout import (
    C_ENTRY_STALL,
    C_IRQ,
    C_IRQ_LOST,
    C_MMIO,
    C_MUL_STALL,
    C_TAKEN,
    C_TRAP,
    OPC_SIZE,
)

# per operation number (row position + 1): class index, and fixed stall cycles per stall kind
_NOPS = len(INSTRUCTIONS) + 3
_OP_CLASS = np.full(_NOPS, -1, dtype=np.int64)
_OP_STALL = np.zeros((len(CORE_STALL_KINDS), _NOPS), dtype=np.int64)
for _k, _ins in enumerate(INSTRUCTIONS):
    if not _ins.unsupported:
        _OP_CLASS[_k + 1] = int(_ins.cls)
        if _ins.timing in STALL_KIND:
            _OP_STALL[CORE_STALL_KINDS.index(STALL_KIND[_ins.timing]), _k + 1] = FIXED_EXTRA_CYCLES[_ins.timing]


def op_totals(opc: np.ndarray) -> np.ndarray:
    """Instructions per operation number (the kernel counts in two banks per operation; a core's
    ``opc`` row goes on with the exact profile, not read here)."""
    return opc[0:OPC_SIZE:2] + opc[1:OPC_SIZE:2]


def per_operation(opc: np.ndarray) -> dict[str, int]:
    """Executed instructions per mnemonic (only those that executed)."""
    ops = op_totals(opc)
    return {ins.name: int(ops[k + 1]) for k, ins in enumerate(INSTRUCTIONS) if ops[k + 1]}


def counters_dict(ctr: np.ndarray, opc: np.ndarray, cycles: int) -> dict[str, int]:
    """All counters by name: instruction classes, stall cycles by kind, events, totals."""
    ops = op_totals(opc)[:_NOPS]
    by_class = np.zeros(len(CLASS_NAMES), dtype=np.int64)
    valid = _OP_CLASS >= 0
    np.add.at(by_class, _OP_CLASS[valid], ops[valid])
    out = {name: int(by_class[int(cls)]) for cls, name in CLASS_NAMES.items()}
    out["instructions"] = int(by_class.sum())
    out["cycles"] = int(cycles)
    stalls = _OP_STALL @ ops
    for k, kind in enumerate(CORE_STALL_KINDS):
        out[kind] = int(stalls[k])
    out[STALL_KIND[Timing.BRANCH]] += (BRANCH_TAKEN_CYCLES - BRANCH_NOT_TAKEN_CYCLES) * int(ctr[C_TAKEN])
    out[STALL_KIND[Timing.MULTIPLY]] += int(ctr[C_MUL_STALL])
    out["entry_cycle"] += int(ctr[C_ENTRY_STALL])
    out["taken_branches"] = int(ctr[C_TAKEN])
    out["interrupts"] = int(ctr[C_IRQ])
    out["interrupts_lost"] = int(ctr[C_IRQ_LOST])
    out["traps"] = int(ctr[C_TRAP])
    out["device_accesses"] = int(ctr[C_MMIO])
    return out
