"""Where a struct member lies: byte offsets from an ELF's DWARF debug information.

Firmware builds carry ``-g`` (toolchain/options.py), so the host can read a variable's fields by
name instead of copying the C layout into Python:

    offset = member_offset(elf_path, "est_t", "alt.h")   # bytes from the start of an est_t

Only what the host readers need: typedefs, structs, arrays and base types in any compilation unit.
"""

from __future__ import annotations

import functools
from collections.abc import Iterator
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


@functools.lru_cache(maxsize=64)
def _members(path: str, mtime_ns: int, type_name: str) -> dict[str, tuple[int, int]]:
    """(dotted member path) -> (byte offset, byte size) for the struct ``type_name``, from the first
    compilation unit that defines it (every unit including its header has the same layout)."""
    with open(path, "rb") as handle:
        for die in _top_dies(path, handle):
            if die.tag not in (*_STRUCT_TAGS, "DW_TAG_typedef") or _name(die) != type_name:
                continue
            body = _strip(die)
            if body.tag in _STRUCT_TAGS:
                out: dict[str, tuple[int, int]] = {}
                _walk(body, "", 0, out)
                return out
    return {}


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


@functools.lru_cache(maxsize=64)
def _variables(path: str, mtime_ns: int, name: str) -> list[dict[str, tuple[int, int]]]:
    """The layouts of every variable called ``name`` defined at file scope (a global, or a static
    of one compilation unit): for each, (dotted member path) -> (byte offset, byte size), with
    "" the whole variable."""
    found = []
    with open(path, "rb") as handle:
        for die in _top_dies(path, handle):
            if die.tag != "DW_TAG_variable" or "DW_AT_declaration" in die.attributes:
                continue
            if _name(die) != name and not (
                "DW_AT_specification" in die.attributes
                and _name(die.get_DIE_from_attribute("DW_AT_specification")) == name
            ):
                continue
            holder = die
            if "DW_AT_type" not in holder.attributes and "DW_AT_specification" in holder.attributes:
                holder = holder.get_DIE_from_attribute("DW_AT_specification")
            kind = _strip(holder.get_DIE_from_attribute("DW_AT_type"))
            out: dict[str, tuple[int, int]] = {"": (0, _byte_size(kind))}
            if kind.tag in _STRUCT_TAGS:
                _walk(kind, "", 0, out)
            found.append(out)
    return found


def variable_field(path: Path | str, variable: str, member: str = "") -> tuple[int, int]:
    """(byte offset from the variable's address, byte size) of ``member`` (dotted, "" for the whole
    variable) of the file-scope variable ``variable``.

    Raises:
        ElfError: no debug information, no such variable or member, or two variables of that name
            (statics of two files): the message names the file.
    """
    p = Path(path)
    layouts = _variables(str(p), p.stat().st_mtime_ns, variable)
    if not layouts:
        raise ElfError(f"{p}: no variable {variable!r} in the debug information (a global or a file-scope static)")
    if len(layouts) > 1:
        raise ElfError(f"{p}: {len(layouts)} variables are called {variable!r} (statics of several files): rename one")
    found = layouts[0].get(member)
    if found is None:
        members = ", ".join(m for m in layouts[0] if m and "." not in m) or "none"
        raise ElfError(f"{p}: variable {variable!r} has no member {member!r} (its members: {members})")
    return found


@functools.lru_cache(maxsize=64)
def _type_size(path: str, mtime_ns: int, type_name: str) -> int:
    with open(path, "rb") as handle:
        for die in _top_dies(path, handle):
            if die.tag in (*_STRUCT_TAGS, "DW_TAG_typedef") and _name(die) == type_name:
                size = _byte_size(_strip(die))
                if size:
                    return size
    return 0


def type_size(path: Path | str, type_name: str) -> int:
    """Bytes of the struct or typedef ``type_name`` (``sizeof``).

    Raises:
        ElfError: no debug information or no such type (the message names the file).
    """
    p = Path(path)
    size = _type_size(str(p), p.stat().st_mtime_ns, type_name)
    if not size:
        raise ElfError(f"{p}: no type {type_name!r} in the debug information")
    return size


def member_offset(path: Path | str, type_name: str, member: str) -> tuple[int, int]:
    """(byte offset, byte size) of ``member`` (dotted: ``"alt.h"``) in the struct type ``type_name``.

    Raises:
        ElfError: no debug information, or no such type or member (the message names the file).
    """
    p = Path(path)
    found = _members(str(p), p.stat().st_mtime_ns, type_name).get(member)
    if found is None:
        raise ElfError(f"{p}: no struct member {type_name}.{member} in the debug information")
    return found


__all__ = ["member_offset", "type_size", "variable_field"]
