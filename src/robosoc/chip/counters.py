"""Naming the raw counter arrays of a core: the only place that knows their layout."""

from __future__ import annotations

import numpy as np

from robosoc.isa.table import INSTRUCTIONS, OP, Cls
from robosoc.kernels.core_layout import C_ENTRY_STALL, C_IRQ, C_MMIO, C_MUL_STALL, C_TAKEN, C_TRAP

CLASS_NAMES = {Cls.JUMP: "jump", Cls.BRANCH: "branch", Cls.MEMORY: "memory", Cls.ADD: "add",
               Cls.LOGIC: "logic", Cls.OTHER: "other", Cls.MUL: "mul", Cls.SYSTEM: "system"}  # fmt: skip

# operation number -> class index, for the executable rows of the table
_OP_CLASS = np.full(256, -1, dtype=np.int64)
for _k, _ins in enumerate(INSTRUCTIONS):
    if not _ins.unsupported:
        _OP_CLASS[_k + 1] = int(_ins.cls)


def op_totals(opc: np.ndarray) -> np.ndarray:
    """Instructions per operation number (the kernel counts in two banks per operation)."""
    return opc[0::2] + opc[1::2]


def per_operation(opc: np.ndarray) -> dict[str, int]:
    """Executed instructions per mnemonic (only those that executed)."""
    ops = op_totals(opc)
    return {ins.name: int(ops[k + 1]) for k, ins in enumerate(INSTRUCTIONS) if ops[k + 1]}


def counters_dict(ctr: np.ndarray, opc: np.ndarray, cycles: int) -> dict[str, int]:
    """All counters by name: instruction classes, stall cycles by kind, events, totals."""
    opc = op_totals(opc)
    by_class = np.zeros(len(CLASS_NAMES), dtype=np.int64)
    valid = _OP_CLASS >= 0
    np.add.at(by_class, _OP_CLASS[valid], opc[valid])
    out = {name: int(by_class[int(cls)]) for cls, name in CLASS_NAMES.items()}
    out["instructions"] = int(by_class.sum())
    out["cycles"] = int(cycles)
    jumps = int(opc[OP["jal"]] + opc[OP["jalr"]])
    loads_stores = out["memory"]
    out["branch_cycle"] = 2 * (int(ctr[C_TAKEN]) + jumps)
    out["memory_cycle"] = 2 * loads_stores
    out["mul_cycle"] = int(ctr[C_MUL_STALL])
    out["entry_cycle"] = int(ctr[C_ENTRY_STALL])
    out["taken_branches"] = int(ctr[C_TAKEN])
    out["interrupts"] = int(ctr[C_IRQ])
    out["traps"] = int(ctr[C_TRAP])
    out["device_accesses"] = int(ctr[C_MMIO])
    return out
