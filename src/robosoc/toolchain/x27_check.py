"""Post-link check that only the interrupt entry writes x27 (s11).

The interrupt return sequence loads the return address into s11 and jumps through it, so an
interrupt taken while other code keeps a value in s11 destroys that value.  Programs are compiled
with ``-ffixed-x27`` and compiler-rt with the ``reserve_x27`` CPU feature, so normally nothing
else touches s11; hand-written assembly or foreign objects may.  This module decodes every word of
the executable segments with the instruction table (:func:`robosoc.isa.table.writes_rd` says which
encodings write ``rd`` = bits 11:7).
"""

from dataclasses import dataclass
from pathlib import Path

from robosoc.firmware import IRQ_ENTRY_SYMBOL
from robosoc.isa.table import lookup
from robosoc.isa.table import writes_rd as _row_writes_rd
from robosoc.program.elf import Program, load_elf

X27 = 27
#: Registers the runtime owns: s11 holds the return address of the interrupt return sequence and
#: tp is its IRQ_STATUS store's base and value (crt/irq_entry.S); only the entry may write them.
RESERVED_REGISTERS: dict[int, str] = {X27: "s11", 4: "tp"}


@dataclass(frozen=True)
class X27Write:
    """One instruction that writes x27: where, in which function, and the word."""

    addr: int
    word: int
    function: str
    kind: str
    register: int = X27

    def describe(self) -> str:
        """``0x40000184 (__divdf3+0x34): op-imm 0x01e95d93``."""
        return f"0x{self.addr:08x} ({self.function}): {self.kind} 0x{self.word:08x}"


def writes_register(word: int, reg: int) -> bool:
    """True when the 32-bit instruction ``word`` has ``rd == reg`` in a format that writes rd."""
    if (word >> 7) & 0x1F != reg:
        return False
    row = lookup(word)
    return row is not None and _row_writes_rd(row)


def find_x27_writes(program: Program, allowed_function: str = IRQ_ENTRY_SYMBOL) -> list[X27Write]:
    """Every instruction outside ``allowed_function`` in an executable segment that writes x27 or tp."""
    allowed_range: tuple[int, int] | None = None
    try:
        entry = program.symbol(allowed_function)
        allowed_range = (entry.addr, entry.addr + max(entry.size, 4))
    except ValueError:
        allowed_range = None
    found: list[X27Write] = []
    for seg in program.segment_info:
        if not seg.executable:
            continue
        data = seg.data
        for offset in range(0, len(data) - 3, 4):
            word = int.from_bytes(data[offset : offset + 4], "little")
            reg = next((r for r in RESERVED_REGISTERS if writes_register(word, r)), None)
            if reg is None:
                continue
            addr = seg.addr + offset
            if allowed_range is not None and allowed_range[0] <= addr < allowed_range[1]:
                continue
            row = lookup(word)
            assert row is not None  # writes_register found its row
            found.append(X27Write(addr, word, program.symbolize(addr), row.name, reg))
    return found


def check_x27(elf_path: Path, label: str | None = None) -> list[str]:
    """Warning texts (one per offending function) for the ELF; empty when only the entry writes x27.

    ``label`` names the program in the texts (default: the ELF path).
    """
    writes = find_x27_writes(load_elf(elf_path))
    by_function: dict[tuple[str, int], list[X27Write]] = {}
    for write in writes:
        name = write.function.split("+", 1)[0]
        by_function.setdefault((name, write.register), []).append(write)
    return [
        f"{label or elf_path}: {name} writes x{reg} ({RESERVED_REGISTERS[reg]}), which the interrupt return "
        f"sequence owns; an interrupt taken while it runs corrupts {RESERVED_REGISTERS[reg]} "
        f"({len(ws)} instruction(s), first at {ws[0].describe()})"
        for (name, reg), ws in by_function.items()
    ]
