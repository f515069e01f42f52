"""ROS 2 messages as CDR bytes, encoded from their ``.msg`` definitions (the flight's few types).

What rosbag2 stores and Foxglove decodes for the ``cdr`` message encoding: the 4-byte
encapsulation header (``00 01 00 00``: plain CDR, little endian), then the fields in order, each
primitive aligned to its size from the end of the header; a string is a ``uint32`` length
(counting its NUL) then its UTF-8 bytes and the NUL; a fixed array ``T[N]`` is its ``N`` elements;
an unbounded sequence ``T[]`` is a ``uint32`` count then its elements; a nested message is its
fields.  A message is given as a dict (field name → value, nested dicts and lists), as
:func:`robosoc.outputs.ros2_flight.row_messages` builds them; a missing field is its default in
the definition, or zero.

Written here so that robosoc imports no private module of ``mcap-ros2-support``; the tests check
the bytes against the ``rosbags`` serializer.
"""

from __future__ import annotations

import struct
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

_PRIMITIVES: dict[str, str] = {
    "bool": "?", "byte": "B", "char": "B", "int8": "b", "uint8": "B", "int16": "h", "uint16": "H",
    "int32": "i", "uint32": "I", "int64": "q", "uint64": "Q", "float32": "f", "float64": "d",
}  # fmt: skip
_HEADER = b"\x00\x01\x00\x00"  # CDR_LE


@dataclass(frozen=True)
class _Field:
    name: str
    kind: str  # a primitive, "string" or a message type "pkg/Type"
    length: int | None  # None: a single value; -1: an unbounded sequence; N: a fixed array
    default: object = None  # a primitive's default value in the definition (None: zero)


def _default(kind: str, length: int | None, tokens: list[str]) -> object:
    if not tokens or length is not None or kind not in _PRIMITIVES:
        return None
    if kind == "bool":
        return tokens[0].lower() == "true"
    return float(tokens[0]) if kind.startswith("float") else int(tokens[0], 0)


def parse_fields(datatype: str, text: str) -> list[_Field]:
    """The fields of a ``.msg`` definition (constants and comments left out); a type without a
    package is in ``datatype``'s package.

    Raises:
        ValueError: a field this encoder does not handle (bounded sequences or strings).
    """
    package = datatype.split("/")[0]
    fields = []
    for raw in text.splitlines():
        line = raw.split("#")[0].strip()
        if not line:
            continue
        if "=" in line.replace("<=", ""):
            continue  # a constant
        kind, name, *default = line.split()
        length = None
        if "[" in kind:
            kind, bound = kind[:-1].split("[")
            if bound.startswith("<="):
                raise ValueError(f"{datatype}: bounded sequence {name!r} is not supported")
            length = int(bound) if bound else -1
        if "<=" in kind:
            raise ValueError(f"{datatype}: bounded string {name!r} is not supported")
        if kind not in _PRIMITIVES and kind != "string" and "/" not in kind:
            kind = f"{package}/{kind}"
        fields.append(_Field(name, kind, length, _default(kind, length, default)))
    return fields


class _Writer:
    def __init__(self) -> None:
        self.data = bytearray(_HEADER)

    def align(self, size: int) -> None:
        pad = -(len(self.data) - len(_HEADER)) % size
        self.data += b"\x00" * pad

    def primitive(self, kind: str, value: Any) -> None:  # a number of the kind the definition names
        code = _PRIMITIVES[kind]
        size = struct.calcsize(code)
        self.align(size)
        if kind == "bool":
            value = bool(value)
        elif code in "bBhHiIqQ":
            value = int(value)
        self.data += struct.pack("<" + code, value)

    def string(self, value: str) -> None:
        raw = value.encode()
        self.primitive("uint32", len(raw) + 1)
        self.data += raw + b"\x00"


class CdrEncoder:
    """Encodes messages of the types in ``definitions`` (``pkg/Type`` → ``.msg`` text).

    Raises:
        KeyError: a field's type is not in ``definitions``.
    """

    def __init__(self, definitions: Mapping[str, str]) -> None:
        self._fields = {kind: parse_fields(kind, text) for kind, text in definitions.items()}
        for kind, fields in self._fields.items():
            for f in fields:
                if f.kind not in _PRIMITIVES and f.kind != "string" and f.kind not in self._fields:
                    raise KeyError(f"{kind}: field {f.name!r} has the unknown type {f.kind}")

    def encoder(self, datatype: str) -> Callable[[Mapping[str, object]], bytes]:
        """A function encoding a message (a dict) of ``datatype`` to CDR bytes."""
        if datatype not in self._fields:
            raise KeyError(f"unknown message type {datatype}")

        def encode(message: Mapping[str, object]) -> bytes:
            out = _Writer()
            self._message(out, datatype, message)
            return bytes(out.data)

        return encode

    def _message(self, out: _Writer, datatype: str, message: Mapping[str, Any]) -> None:
        for f in self._fields[datatype]:
            value = message.get(f.name, f.default)
            if f.length is None:
                self._value(out, f.kind, value)
                continue
            items = list(value) if value is not None else []
            if f.length < 0:
                out.primitive("uint32", len(items))
            elif value is None:
                items = [None] * f.length
            elif len(items) != f.length:
                raise ValueError(f"{datatype}.{f.name} has {f.length} elements, got {len(items)}")
            for item in items:
                self._value(out, f.kind, item)

    def _value(self, out: _Writer, kind: str, value: Any) -> None:  # of the type the definitions give it
        if kind == "string":
            out.string("" if value is None else str(value))
        elif kind in _PRIMITIVES:
            out.primitive(kind, 0 if value is None else value)
        else:
            self._message(out, kind, value if value is not None else {})


__all__ = ["CdrEncoder", "parse_fields"]
