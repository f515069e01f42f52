"""Loading bare-metal RV32 ELF executables: loadable segments, entry point and symbols.

A :class:`Program` is what the simulator needs from an ELF file: the bytes to place in memory
(``PT_LOAD`` segments, with ``.bss``-style ``memsz > filesz`` tails zero-filled), the entry
point, and the symbol table to turn a pc into ``symbol+0xoffset`` in messages and profiles.
"""

import bisect
import functools
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from elftools.common.exceptions import ELFError as PyElfToolsError
from elftools.elf.constants import P_FLAGS
from elftools.elf.elffile import ELFFile
from elftools.elf.sections import SymbolTableSection

#: Largest segment an ELF may ask for (memsz) when no regions are given: the largest SRAM of a tile,
#: ``config.ranges.MAX_SRAM_BYTES`` (a test checks they agree), checked before the segment is made.
MAX_SEGMENT_BYTES = 1 << 30


EM_RISCV = "EM_RISCV"


class ElfError(ValueError):
    """The file is not a loadable RV32 little-endian executable for the given memory."""


@dataclass(frozen=True)
class Region:
    """An address range the loader may place segments in: ``[base, base + size)``."""

    base: int
    size: int
    name: str = "memory"

    @property
    def end(self) -> int:
        """First address past the region."""
        return self.base + self.size

    def contains(self, addr: int, length: int) -> bool:
        """True when ``[addr, addr + length)`` lies inside the region."""
        return self.base <= addr and addr + length <= self.end


@dataclass(frozen=True, order=True)
class Symbol:
    """A function or data object of the symbol table (``size`` is 0 when unknown)."""

    addr: int
    name: str
    size: int = 0
    kind: str = "func"  # "func" or "object"
    is_global: bool = True


@dataclass(frozen=True)
class Segment:
    """One loadable segment: ``data`` already includes the zero-filled tail."""

    addr: int
    data: bytes
    executable: bool
    writable: bool

    @property
    def end(self) -> int:
        """First address past the segment."""
        return self.addr + len(self.data)


@dataclass
class Program:
    """A loaded executable.

    Attributes:
        path: the ELF file.
        entry: the entry point (``_start``).
        segments: ``(address, bytes)`` of every PT_LOAD segment, zero-filled to its memory size.
        symbols: function and object symbols, sorted by address.
    """

    path: Path
    entry: int
    segments: list[tuple[int, bytes]]
    symbols: list[Symbol] = field(default_factory=list)
    segment_info: list[Segment] = field(default_factory=list)

    def __post_init__(self) -> None:
        self.symbols.sort()
        self._addrs = [s.addr for s in self.symbols]
        self._by_name: dict[str, Symbol] = {}
        for sym in self.symbols:
            known = self._by_name.get(sym.name)
            if known is None or (sym.is_global and not known.is_global):
                self._by_name[sym.name] = sym

    def symbol_at(self, pc: int) -> Symbol | None:
        """The symbol containing ``pc``.

        Candidates are the symbols at the nearest address at or below ``pc``; one whose size is known
        must cover ``pc`` (past its end, ``pc`` is in a gap and there is no symbol), one of size 0
        extends to the next symbol.  Among several, a global one with the plainest name wins
        (compiler-rt defines both ``__divdf3`` and ``compiler_rt.divdf3.__divdf3``).
        """
        i = bisect.bisect_right(self._addrs, pc)
        if i == 0:
            return None
        addr = self._addrs[i - 1]
        best: Symbol | None = None
        while i > 0 and self._addrs[i - 1] == addr:
            i -= 1
            sym = self.symbols[i]
            if sym.size and pc >= sym.addr + sym.size:
                continue
            if best is None or _preference(sym) < _preference(best):
                best = sym
        return best

    def symbolize(self, pc: int) -> str:
        """``"symbol+0xoff"`` for ``pc`` (``"symbol"`` at offset 0); the bare hex address if no symbol."""
        sym = self.symbol_at(pc)
        if sym is None:
            return f"0x{pc:08x}"
        offset = pc - sym.addr
        return sym.name if offset == 0 else f"{sym.name}+0x{offset:x}"

    def address_of(self, name: str) -> int:
        """Address of symbol ``name``.

        Raises:
            ElfError: no function or object of that name (the message names the file).
        """
        sym = self._by_name.get(name)
        if sym is None:
            raise ElfError(f"{self.path}: no symbol named '{name}'")
        return sym.addr

    def symbol(self, name: str) -> Symbol:
        """The :class:`Symbol` called ``name`` (raises :class:`ElfError` when absent)."""
        self.address_of(name)
        return self._by_name[name]

    def code_end(self, base: int) -> int:
        """Bytes from ``base`` to the end of the last executable segment (0 if there is none)."""
        ends = [seg.end - base for seg in self.segment_info if seg.executable]
        if not ends and not self.segment_info:  # no segment flags known: everything may be code
            ends = [addr + len(data) - base for addr, data in self.segments]
        return max([0, *ends])

    def read(self, addr: int, length: int) -> bytes:
        """Bytes of the loaded image at ``[addr, addr + length)``.

        Raises:
            ElfError: the range is not inside one segment.
        """
        for seg_addr, data in self.segments:
            if seg_addr <= addr and addr + length <= seg_addr + len(data):
                return data[addr - seg_addr : addr - seg_addr + length]
        raise ElfError(f"{self.path}: 0x{addr:08x}+{length} is not inside a loaded segment")


def _preference(sym: Symbol) -> tuple[int, int, int]:
    return (0 if sym.is_global else 1, sym.name.count("."), len(sym.name))


def _as_region(region: Region | tuple[int, int]) -> Region:
    if isinstance(region, Region):
        return region
    base, size = region
    return Region(base, size)


def load_elf(path: Path | str, regions: Sequence[Region | tuple[int, int]] | None = None) -> Program:
    """Read an RV32 little-endian executable.

    Args:
        path: the ELF file.
        regions: where segments may be placed, as :class:`Region` or ``(base, size)`` pairs;
            ``None`` accepts any address.  Every PT_LOAD segment must lie inside one region.

    Returns:
        The :class:`Program`.

    Raises:
        ElfError: not an ELF file, not 32-bit little-endian RISC-V, not an executable, a segment
            outside the allowed regions, or an entry point outside the executable segments.
            The message names the file, and the segment and addresses where relevant.
    """
    path = Path(path)
    allowed = [_as_region(r) for r in regions] if regions is not None else None
    try:
        stream = path.open("rb")
    except OSError as exc:
        raise ElfError(f"{path}: cannot open: {exc.strerror}") from exc
    with stream:
        if stream.read(4) != b"\x7fELF":
            raise ElfError(f"{path}: not an ELF file (no \\x7fELF magic)")
        stream.seek(0)
        try:
            elf = ELFFile(stream)
            return _read_program(path, elf, allowed)
        except PyElfToolsError as exc:
            raise ElfError(f"{path}: malformed ELF: {exc}") from exc


def load_elf_once(path: Path | str, regions: Sequence[Region]) -> Program:
    """:func:`load_elf`, read once per process for the same file as it is on disk (its size and
    modification time) and the same regions: a sweep or ``robosoc bench fly`` builds a chip, and
    loads its firmware, for every flight, and pyelftools takes some 5 ms to read it.  The program is
    shared: do not change it.

    Raises:
        ElfError: as :func:`load_elf`, and a file that cannot be looked at.
    """
    path = Path(path)
    try:
        status = path.stat()
    except OSError as exc:
        raise ElfError(f"{path}: cannot open: {exc.strerror}") from exc
    return _load_elf_version(path, status.st_size, status.st_mtime_ns, tuple(regions))


@functools.lru_cache(maxsize=32)
def _load_elf_version(path: Path, size: int, mtime_ns: int, regions: tuple[Region, ...]) -> Program:
    """:func:`load_elf` of one version of a file (``size`` and ``mtime_ns`` key the memo)."""
    return load_elf(path, regions)


def _read_program(path: Path, elf: ELFFile, allowed: list[Region] | None) -> Program:
    if elf.elfclass != 32:
        raise ElfError(f"{path}: ELF class is {elf.elfclass}-bit, expected 32-bit (RV32)")
    if not elf.little_endian:
        raise ElfError(f"{path}: big-endian ELF, expected little-endian RISC-V")
    machine = elf["e_machine"]
    if machine != EM_RISCV:
        raise ElfError(f"{path}: e_machine is {machine}, expected EM_RISCV")
    if elf["e_type"] != "ET_EXEC":
        raise ElfError(f"{path}: e_type is {elf['e_type']}, expected ET_EXEC (a linked executable)")

    infos: list[Segment] = []
    for index, seg in enumerate(elf.iter_segments()):
        if seg["p_type"] != "PT_LOAD" or seg["p_memsz"] == 0:
            continue
        addr, filesz, memsz = seg["p_paddr"], seg["p_filesz"], seg["p_memsz"]
        if filesz > memsz:
            raise ElfError(f"{path}: segment {index} at 0x{addr:08x} has filesz {filesz} > memsz {memsz}")
        if addr + memsz > 1 << 32:  # checked before the segment's bytes are made: memsz 0xfffffff0 is 4 GiB
            raise ElfError(
                f"{path}: segment {index} at 0x{addr:08x} ({memsz} bytes) ends beyond the 32-bit address space"
            )
        if allowed is None and memsz > MAX_SEGMENT_BYTES:
            raise ElfError(
                f"{path}: segment {index} at 0x{addr:08x} has memsz {memsz} bytes ({memsz / 2**30:.4g} GiB), "
                f"more than any tile's SRAM ({MAX_SEGMENT_BYTES >> 30} GiB)"
            )
        if allowed is not None and not any(r.contains(addr, memsz) for r in allowed):
            where = ", ".join(f"{r.name} 0x{r.base:08x}-0x{r.end - 1:08x}" for r in allowed)
            raise ElfError(
                f"{path}: segment {index} at 0x{addr:08x}-0x{addr + memsz - 1:08x} ({memsz} bytes) "
                f"is outside the allowed memory ({where})"
            )
        data = seg.data() + bytes(memsz - filesz)
        flags = seg["p_flags"]
        infos.append(Segment(addr, data, bool(flags & P_FLAGS.PF_X), bool(flags & P_FLAGS.PF_W)))

    if not infos:
        raise ElfError(f"{path}: no loadable (PT_LOAD) segments")
    entry = elf["e_entry"]
    if not any(s.executable and s.addr <= entry < s.end for s in infos):
        raise ElfError(f"{path}: entry point 0x{entry:08x} is not inside an executable segment")

    return Program(
        path=path,
        entry=entry,
        segments=[(s.addr, s.data) for s in infos],
        symbols=_read_symbols(elf),
        segment_info=infos,
    )


#: Elf32_Sym, little-endian: st_name, st_value, st_size, st_info, st_other, st_shndx.
_ELF32_SYM = np.dtype(
    [("name", "<u4"), ("value", "<u4"), ("size", "<u4"), ("info", "u1"), ("other", "u1"), ("shndx", "<u2")]
)
_STT_OBJECT, _STT_FUNC = 1, 2
_STB_GLOBAL, _STB_WEAK = 1, 2


def _read_symbols(elf: ELFFile) -> list[Symbol]:
    """The defined functions and data objects of ``.symtab``, read as one array (a firmware image has
    thousands of symbols; pyelftools parses them one by one, a thousand times slower)."""
    table = elf.get_section_by_name(".symtab")
    if not isinstance(table, SymbolTableSection):
        return []
    if table["sh_entsize"] != _ELF32_SYM.itemsize:
        raise ElfError(f".symtab entries are {table['sh_entsize']} bytes, expected {_ELF32_SYM.itemsize}")
    entries = np.frombuffer(table.data(), dtype=_ELF32_SYM, count=len(table.data()) // _ELF32_SYM.itemsize)
    strings = elf.get_section(table["sh_link"]).data()
    kinds = entries["info"] & 0xF
    binds = entries["info"] >> 4
    keep = ((kinds == _STT_FUNC) | (kinds == _STT_OBJECT)) & (entries["shndx"] != 0) & (entries["name"] != 0)
    symbols = []
    for entry, kind, bind in zip(entries[keep], kinds[keep], binds[keep], strict=True):
        start = int(entry["name"])
        name = strings[start : strings.index(b"\0", start)].decode("utf-8", "replace")
        if not name:
            continue
        symbols.append(
            Symbol(
                addr=int(entry["value"]),
                name=name,
                size=int(entry["size"]),
                kind="func" if kind == _STT_FUNC else "object",
                is_global=int(bind) in (_STB_GLOBAL, _STB_WEAK),
            )
        )
    return symbols


__all__ = ["ElfError", "Program", "Region", "Segment", "Symbol", "load_elf", "load_elf_once"]
