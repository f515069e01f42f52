"""How a message's payload is laid out: its field types, the C struct without padding, and how
much of one NoC packet it may fill.

The rules here serve both the packet formats robosoc's host speaks (:mod:`robosoc.host.packets`)
and the formats a firmware project declares for its messages (:mod:`robosoc.config.project`), so
that both are checked by one rule:

* a field is ``count`` values of one type; each type has its size in bytes (:data:`FIELD_BYTES`):
  ``u16``, ``u32`` and ``i32`` integers, ``q16`` a Q16.16 number in an ``int32``, ``f32`` an IEEE
  single, ``real`` the build's ``real_t`` (soft-float ``float`` or Q16.16: 4 bytes either way);
* fields follow each other in order without padding: each starts at a multiple of its type's size
  and the whole is a multiple of its largest type's size, so the C compiler's layout of the
  struct is exactly the bytes the host reads (the generated headers assert each offset);
* a payload fits one NoC packet: 64 flits (the network interface's memories), minus the 2-flit
  NoC header (destination, size) and the 4 flits of the on-chip messaging header, leaves
  :data:`MAX_PAYLOAD_FLITS` = 58 16-bit flits, :data:`MAX_PAYLOAD_BYTES` = 116 bytes.
"""

from __future__ import annotations

from collections.abc import Sequence

from robosoc.config.chip import NI_MEMORY_FLITS

__all__ = [
    "FIELD_BYTES",
    "FIELD_TYPES",
    "MAX_PACKET_FLITS",
    "MAX_PAYLOAD_BYTES",
    "MAX_PAYLOAD_FLITS",
    "MESSAGE_HEADER_FLITS",
    "NOC_HEADER_FLITS",
    "LayoutError",
    "lay_out",
]

NOC_HEADER_FLITS = 2
"""Flit 0 destination, flit 1 size (platform.md §4)."""
MESSAGE_HEADER_FLITS = 4
"""Reserved for the on-chip messaging layer's header (ports, length, sequence)."""
MAX_PACKET_FLITS = NI_MEMORY_FLITS
"""Longest NoC packet, header included (the network interface's memories hold 64 flits)."""
MAX_PAYLOAD_FLITS = MAX_PACKET_FLITS - NOC_HEADER_FLITS - MESSAGE_HEADER_FLITS
"""Flits left for an application packet."""
MAX_PAYLOAD_BYTES = 2 * MAX_PAYLOAD_FLITS
"""Bytes left for an application packet (16-bit flits)."""

FIELD_BYTES: dict[str, int] = {"u16": 2, "u32": 4, "i32": 4, "q16": 4, "f32": 4, "real": 4}
"""Bytes of one value of each field type."""
FIELD_TYPES = tuple(FIELD_BYTES)


class LayoutError(ValueError):
    """A layout that would need padding or does not fit one packet; ``index`` is the field at fault
    (``None``: the whole)."""

    def __init__(self, index: int | None, reason: str) -> None:
        super().__init__(reason)
        self.index = index
        self.reason = reason


def lay_out(fields: Sequence[tuple[str, str, int]]) -> tuple[int, ...]:
    """The byte offset of each field (name, type, count), laid out in order without padding.

    Raises:
        LayoutError: a field not at a multiple of its type's size, a size the C struct would pad
            at its end, or more than :data:`MAX_PAYLOAD_BYTES` bytes.
    """
    offsets: list[int] = []
    offset = 0
    for i, (name, kind, count) in enumerate(fields):
        size = FIELD_BYTES[kind]
        if offset % size:
            raise LayoutError(
                i,
                f"{name!r} ({kind}) would start at byte {offset}, not a multiple of {size}: the C struct "
                f"would be padded before it (put the {size}-byte fields first, or add a u16 before it)",
            )
        offsets.append(offset)
        offset += size * count
    align = max((FIELD_BYTES[kind] for _, kind, _ in fields), default=1)
    if offset % align:
        raise LayoutError(
            None,
            f"{offset} bytes, not a multiple of {align} (its largest field type): the C struct would be padded "
            "at its end (add a u16)",
        )
    if offset > MAX_PAYLOAD_BYTES:
        raise LayoutError(
            None,
            f"{offset} bytes, more than the {MAX_PAYLOAD_BYTES} of one NoC packet's payload "
            f"({MAX_PAYLOAD_FLITS} flits of 16 bits)",
        )
    return tuple(offsets)
