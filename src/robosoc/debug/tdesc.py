"""The target description GDB reads (``qXfer:features:read:target.xml``): an RV32 core, x0-x31 and pc.

With it GDB knows the architecture and the register set without ``set architecture``; there is
no CSR or FPU feature because HF-RISCV has neither.  Register numbers follow the order here:
0-31 are x0-x31, 32 is pc (the ``g`` packet's layout).
"""

from __future__ import annotations

#: ABI names of x0..x31 (GDB's riscv feature accepts these or x0..x31).
ABI_NAMES = (
    "zero", "ra", "sp", "gp", "tp", "t0", "t1", "t2", "fp", "s1", "a0", "a1", "a2", "a3", "a4", "a5",
    "a6", "a7", "s2", "s3", "s4", "s5", "s6", "s7", "s8", "s9", "s10", "s11", "t3", "t4", "t5", "t6",
)  # fmt: skip
PC_REGNUM = 32
NUM_REGS = 33

_TYPES = {"ra": "code_ptr", "sp": "data_ptr", "gp": "data_ptr", "tp": "data_ptr", "fp": "data_ptr"}


def target_xml() -> str:
    """The whole description as one XML document."""
    regs = [
        f'    <reg name="{name}" bitsize="32" type="{_TYPES.get(name, "int")}" regnum="{i}"/>'
        for i, name in enumerate(ABI_NAMES)
    ]
    regs.append(f'    <reg name="pc" bitsize="32" type="code_ptr" regnum="{PC_REGNUM}"/>')
    return (
        '<?xml version="1.0"?>\n'
        '<!DOCTYPE target SYSTEM "gdb-target.dtd">\n'
        "<target>\n"
        "  <architecture>riscv:rv32</architecture>\n"
        '  <feature name="org.gnu.gdb.riscv.cpu">\n' + "\n".join(regs) + "\n  </feature>\n</target>\n"
    )
