"""Code and data size of a firmware image: per section and per function, read from the ELF.

What ``robosoc firmware size`` prints: the allocated sections (``.text``, ``.rodata``, ``.data``,
``.bss`` and any other the linker kept) with their sizes, and every function and data object of
the symbol table with its size, largest first, so that a build's cost in SRAM can be compared
across arithmetic and multiplier options.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from elftools.common.exceptions import ELFError
from elftools.elf.constants import SH_FLAGS
from elftools.elf.elffile import ELFFile

from robosoc.program.elf import ElfError, load_elf


@dataclass(frozen=True)
class SectionSize:
    name: str
    addr: int
    size: int
    kind: str  # "code", "read-only data", "data" or "zero-initialised data"


@dataclass(frozen=True)
class SymbolSize:
    name: str
    addr: int
    size: int
    kind: str  # "func" or "object"


@dataclass(frozen=True)
class CodeSize:
    """Sizes of one ELF: sections in address order, symbols largest first."""

    path: Path
    sections: list[SectionSize]
    symbols: list[SymbolSize]

    @property
    def code_bytes(self) -> int:
        return sum(s.size for s in self.sections if s.kind == "code")

    @property
    def data_bytes(self) -> int:
        return sum(s.size for s in self.sections if s.kind != "code")


def _kind(flags: int, sh_type: str) -> str:
    if flags & SH_FLAGS.SHF_EXECINSTR:
        return "code"
    if sh_type == "SHT_NOBITS":
        return "zero-initialised data"
    return "data" if flags & SH_FLAGS.SHF_WRITE else "read-only data"


def code_size(path: str | Path) -> CodeSize:
    """Sections and symbol sizes of the ELF at ``path``.

    Raises:
        ElfError: the file is missing, unreadable or not an RV32 executable (names the file).
    """
    path = Path(path)
    program = load_elf(path)
    try:
        with path.open("rb") as handle:
            elf = ELFFile(handle)
            sections = [
                SectionSize(s.name, s["sh_addr"], s["sh_size"], _kind(s["sh_flags"], s["sh_type"]))
                for s in elf.iter_sections()
                if s["sh_flags"] & SH_FLAGS.SHF_ALLOC and s["sh_size"] > 0
            ]
    except (OSError, ELFError) as exc:
        raise ElfError(f"{path}: cannot read sections: {exc}") from exc
    sections.sort(key=lambda s: s.addr)
    seen: set[tuple[int, str]] = set()
    symbols = []
    for sym in program.symbols:
        if sym.size > 0 and (sym.addr, sym.name) not in seen:
            seen.add((sym.addr, sym.name))
            symbols.append(SymbolSize(sym.name, sym.addr, sym.size, sym.kind))
    symbols.sort(key=lambda s: (-s.size, s.name))
    return CodeSize(path, sections, symbols)
