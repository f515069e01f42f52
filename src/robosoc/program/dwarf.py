"""Where a struct member lies: byte offsets from an ELF's DWARF debug information.

Firmware builds carry ``-g`` (toolchain/options.py), so the host can read a variable's fields by
name instead of copying the C layout into Python:

    offset = member_offset(elf_path, "est_t", "alt.h")   # bytes from the start of an est_t

Only what the host readers need: typedefs, structs, arrays and base types in any compilation unit.
"""

from __future__ import annotations

import functools
import hashlib
import json
import os
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import BinaryIO

from elftools.dwarf.die import DIE
from elftools.elf.elffile import ELFFile

from robosoc.program.elf import ElfError

_STRUCT_TAGS = ("DW_TAG_structure_type", "DW_TAG_union_type")
_QUALIFIERS = ("DW_TAG_typedef", "DW_TAG_const_type", "DW_TAG_volatile_type")


def _name(die: DIE) -> str | None:
    attr = die.attributes.get("DW_AT_name")
    return attr.value.decode() if attr is not None else None


def _strip(die: DIE) -> DIE:
    """The struct, array or base type behind typedefs and qualifiers."""
    while die.tag in _QUALIFIERS and "DW_AT_type" in die.attributes:
        die = die.get_DIE_from_attribute("DW_AT_type")
    return die


def _member_location(member: DIE) -> int:
    attr = member.attributes.get("DW_AT_data_member_location")
    if attr is None:
        return 0  # a union member, or the first member of some producers' structs
    if isinstance(attr.value, int):
        return attr.value
    # DWARF 2 style: a location expression DW_OP_plus_uconst <uleb128>
    expr = list(attr.value)
    if expr and expr[0] == 0x23:
        value, shift = 0, 0
        for byte in expr[1:]:
            value |= (byte & 0x7F) << shift
            shift += 7
            if not byte & 0x80:
                return value
    raise ElfError(f"member {_name(member)}: unsupported location {attr.value!r}")


def _top_dies(path: str, handle: BinaryIO) -> Iterator[DIE]:
    """Every top-level debug entry (types, variables, functions) of every compilation unit.

    Raises:
        ElfError: the file has no DWARF information.
    """
    elf = ELFFile(handle)
    if not elf.has_dwarf_info():
        raise ElfError(f"{path}: no DWARF debug information (build with -g)")
    for cu in elf.get_dwarf_info().iter_CUs():
        yield from cu.get_top_DIE().iter_children()


def _walk(struct: DIE, prefix: str, base: int, out: dict[str, tuple[int, int]]) -> None:
    for member in struct.iter_children():
        if member.tag != "DW_TAG_member" or _name(member) is None:
            continue
        key = f"{prefix}{_name(member)}"
        offset = base + _member_location(member)
        kind = _strip(member.get_DIE_from_attribute("DW_AT_type"))
        size = _byte_size(kind)
        out[key] = (offset, size)
        if kind.tag in _STRUCT_TAGS:
            _walk(kind, f"{key}.", offset, out)


def _byte_size(die: DIE) -> int:
    if "DW_AT_byte_size" in die.attributes:
        return int(die.attributes["DW_AT_byte_size"].value)
    if die.tag == "DW_TAG_array_type":
        element = _byte_size(_strip(die.get_DIE_from_attribute("DW_AT_type")))
        count = 1
        for sub in die.iter_children():
            if sub.tag == "DW_TAG_subrange_type":
                if "DW_AT_count" in sub.attributes:
                    count *= int(sub.attributes["DW_AT_count"].value)
                elif "DW_AT_upper_bound" in sub.attributes:
                    count *= int(sub.attributes["DW_AT_upper_bound"].value) + 1
        return element * count
    return 0


def _variable_layout(die: DIE) -> dict[str, tuple[int, int]]:
    """(dotted member path) -> (byte offset, byte size) of a file-scope variable, "" the whole."""
    holder = die
    if "DW_AT_type" not in holder.attributes and "DW_AT_specification" in holder.attributes:
        holder = holder.get_DIE_from_attribute("DW_AT_specification")
    kind = _strip(holder.get_DIE_from_attribute("DW_AT_type"))
    out: dict[str, tuple[int, int]] = {"": (0, _byte_size(kind))}
    if kind.tag in _STRUCT_TAGS:
        _walk(kind, "", 0, out)
    return out


def _variable_name(die: DIE) -> str | None:
    name = _name(die)
    if name is None and "DW_AT_specification" in die.attributes:
        name = _name(die.get_DIE_from_attribute("DW_AT_specification"))
    return name


Layout = dict[str, tuple[int, int]]


@dataclass(frozen=True)
class DebugIndex:
    """What the host readers look up in one ELF's DWARF, read in one walk over its top-level entries
    (:func:`debug_index`): the layout of every file-scope variable (a global, or a static of one
    compilation unit: several may share a name), and of every named struct or typedef (from the
    first compilation unit that defines it: every unit including its header has the same layout)."""

    path: str
    variables: dict[str, list[Layout]]
    types: dict[str, tuple[int, Layout]]  # name -> (byte size, members; none for a non-struct)
    #: names whose layout could not be read (the reason, raised when the name is looked up)
    problems: dict[str, str]

    def _check(self, name: str) -> None:
        if name in self.problems:
            raise ElfError(f"{self.path}: {name}: {self.problems[name]}")

    def variable_field(self, variable: str, member: str = "") -> tuple[int, int]:
        """As :func:`variable_field`."""
        self._check(variable)
        layouts = self.variables.get(variable, [])
        if not layouts:
            raise ElfError(
                f"{self.path}: no variable {variable!r} in the debug information (a global or a file-scope static)"
            )
        if len(layouts) > 1:
            raise ElfError(
                f"{self.path}: {len(layouts)} variables are called {variable!r} (statics of several files): rename one"
            )
        found = layouts[0].get(member)
        if found is None:
            members = ", ".join(m for m in layouts[0] if m and "." not in m) or "none"
            raise ElfError(f"{self.path}: variable {variable!r} has no member {member!r} (its members: {members})")
        return found

    def type_size(self, type_name: str) -> int:
        """As :func:`type_size`."""
        self._check(type_name)
        size = self.types.get(type_name, (0, {}))[0]
        if not size:
            raise ElfError(f"{self.path}: no type {type_name!r} in the debug information")
        return size

    def member_offset(self, type_name: str, member: str) -> tuple[int, int]:
        """As :func:`member_offset`."""
        self._check(type_name)
        found = self.types.get(type_name, (0, {}))[1].get(member)
        if found is None:
            raise ElfError(f"{self.path}: no struct member {type_name}.{member} in the debug information")
        return found

    def to_json(self) -> str:
        return json.dumps(
            {"variables": self.variables, "types": self.types, "problems": self.problems}, separators=(",", ":")
        )

    @classmethod
    def from_json(cls, path: str, text: str) -> DebugIndex:
        data = json.loads(text)

        def layout(raw: dict[str, list[int]]) -> Layout:
            return {k: (int(v[0]), int(v[1])) for k, v in raw.items()}

        return cls(
            path,
            {name: [layout(x) for x in found] for name, found in data["variables"].items()},
            {name: (int(size), layout(members)) for name, (size, members) in data["types"].items()},
            {str(name): str(why) for name, why in data["problems"].items()},
        )


def _read_index(path: str) -> DebugIndex:
    variables: dict[str, list[Layout]] = {}
    types: dict[str, tuple[int, Layout]] = {}
    problems: dict[str, str] = {}
    with open(path, "rb") as handle:
        for die in _top_dies(path, handle):
            name = None
            try:
                if die.tag == "DW_TAG_variable":
                    if "DW_AT_declaration" in die.attributes:
                        continue
                    name = _variable_name(die)
                    if name is not None:
                        variables.setdefault(name, []).append(_variable_layout(die))
                elif die.tag in (*_STRUCT_TAGS, "DW_TAG_typedef"):
                    name = _name(die)
                    known = types.get(name) if name is not None else (1, {})
                    if name is None or (known is not None and known[0]):
                        continue  # the first unit's definition with a size stands
                    body = _strip(die)
                    size = _byte_size(body)
                    members: Layout = {}
                    if body.tag in _STRUCT_TAGS:
                        _walk(body, "", 0, members)
                    if known is None or size:
                        types[name] = (size, members)
            except (ElfError, KeyError) as exc:  # said when the name is looked up, not before
                problems.setdefault(name or "?", str(exc).removeprefix(f"{path}: "))
    return DebugIndex(path, variables, types, problems)


@functools.lru_cache(maxsize=16)
def _index(path: str, mtime_ns: int, size: int, store: str | None) -> DebugIndex:
    if store is None:
        return _read_index(path)
    data = Path(path).read_bytes()
    kept = Path(store) / f"{hashlib.sha256(data).hexdigest()}-v{INDEX_VERSION}.json"
    try:
        return DebugIndex.from_json(path, kept.read_text())
    except (OSError, ValueError, KeyError, TypeError):
        pass  # not kept yet (or unreadable): read the DWARF
    index = _read_index(path)
    try:
        kept.parent.mkdir(parents=True, exist_ok=True)
        scratch = kept.with_name(f"{kept.name}.{os.getpid()}.partial")
        scratch.write_text(index.to_json())
        scratch.replace(kept)
    except OSError:
        pass  # a read-only cache: read again next time
    return index


#: Bumped when what an index holds changes (kept indexes of older versions are not read).
INDEX_VERSION = 1


def debug_index(path: Path | str, store: Path | None = None) -> DebugIndex:
    """The :class:`DebugIndex` of the ELF ``path`` (one walk over its DWARF per process and file
    version; with ``store``, a folder, kept there under the digest of the file's bytes, so later
    processes read it instead of the DWARF).

    Raises:
        ElfError: the file has no DWARF information.
    """
    p = Path(path)
    stat = p.stat()
    return _index(str(p), stat.st_mtime_ns, stat.st_size, None if store is None else str(store))


def variable_field(path: Path | str, variable: str, member: str = "") -> tuple[int, int]:
    """(byte offset from the variable's address, byte size) of ``member`` (dotted, "" for the whole
    variable) of the file-scope variable ``variable``.

    Raises:
        ElfError: no debug information, no such variable or member, or two variables of that name
            (statics of two files): the message names the file.
    """
    return debug_index(path).variable_field(variable, member)


def type_size(path: Path | str, type_name: str) -> int:
    """Bytes of the struct or typedef ``type_name`` (``sizeof``).

    Raises:
        ElfError: no debug information or no such type (the message names the file).
    """
    return debug_index(path).type_size(type_name)


def member_offset(path: Path | str, type_name: str, member: str) -> tuple[int, int]:
    """(byte offset, byte size) of ``member`` (dotted: ``"alt.h"``) in the struct type ``type_name``.

    Raises:
        ElfError: no debug information, or no such type or member (the message names the file).
    """
    return debug_index(path).member_offset(type_name, member)


__all__ = ["DebugIndex", "debug_index", "member_offset", "type_size", "variable_field"]
