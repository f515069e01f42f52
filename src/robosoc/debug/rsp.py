"""GDB remote serial protocol framing: bytes from the wire to events, payloads to frames.

A packet is ``$payload#cc`` where ``cc`` is the modulo-256 sum of the payload bytes in two hex
digits.  Outside packets the wire carries acknowledgements (``+``/``-``) and the interrupt byte
0x03 (GDB's Ctrl-C); anything else there is noise and is dropped.  A ``$`` inside a packet starts
a new packet (the partial one is dropped, as a truncated packet must be).  A payload longer than
:data:`MAX_PAYLOAD` is not kept: its checksum is still followed, and the reader reports it as
:class:`Oversized` so that the server can answer with an error instead of buffering without
bound.  Nothing here touches sockets or the simulator.
"""

from __future__ import annotations

from dataclasses import dataclass

#: Largest payload the server accepts (advertised to GDB as ``PacketSize``).
MAX_PAYLOAD = 0x4000

INTERRUPT = 0x03
_ESCAPE = 0x7D  # '}'
_MUST_ESCAPE = frozenset(b"$#}*")
_HEX = frozenset(b"0123456789abcdefABCDEF")


@dataclass(frozen=True)
class Packet:
    """A packet whose checksum matched; ``payload`` as sent (binary data still escaped)."""

    payload: bytes


@dataclass(frozen=True)
class BadChecksum:
    """A complete packet whose checksum did not match (or was not two hex digits)."""


@dataclass(frozen=True)
class Oversized:
    """A complete packet with a good checksum but a payload longer than :data:`MAX_PAYLOAD`."""

    length: int


@dataclass(frozen=True)
class Ack:
    """``+``: the peer received our last packet."""


@dataclass(frozen=True)
class Nack:
    """``-``: the peer wants our last packet again."""


@dataclass(frozen=True)
class Interrupt:
    """The 0x03 byte: stop the target."""


Event = Packet | BadChecksum | Oversized | Ack | Nack | Interrupt

_IDLE, _DATA, _SUM1, _SUM2 = range(4)


class PacketReader:
    """Turns the received byte stream into :data:`Event` values, however it is split."""

    def __init__(self, max_payload: int = MAX_PAYLOAD) -> None:
        self.max_payload = max_payload
        self._state = _IDLE
        self._data = bytearray()
        self._length = 0
        self._sum = 0
        self._digits = bytearray()

    def feed(self, chunk: bytes) -> list[Event]:
        """Events completed by ``chunk`` (in wire order)."""
        events: list[Event] = []
        for byte in chunk:
            event = self._byte(byte)
            if event is not None:
                events.append(event)
        return events

    def _start(self) -> None:
        self._state = _DATA
        self._data.clear()
        self._length = 0
        self._sum = 0

    def _byte(self, byte: int) -> Event | None:
        if self._state == _IDLE:
            if byte == ord("$"):
                self._start()
            elif byte == ord("+"):
                return Ack()
            elif byte == ord("-"):
                return Nack()
            elif byte == INTERRUPT:
                return Interrupt()
            return None
        if self._state == _DATA:
            if byte == ord("$"):
                self._start()  # the previous packet was truncated: drop it
            elif byte == ord("#"):
                self._state = _SUM1
                self._digits.clear()
            else:
                self._sum = (self._sum + byte) & 0xFF
                self._length += 1
                if self._length <= self.max_payload:
                    self._data.append(byte)
            return None
        self._digits.append(byte)
        if self._state == _SUM1:
            self._state = _SUM2
            return None
        self._state = _IDLE
        digits = bytes(self._digits)
        if not all(d in _HEX for d in digits) or int(digits, 16) != self._sum:
            return BadChecksum()
        if self._length > self.max_payload:
            return Oversized(self._length)
        return Packet(bytes(self._data))


def checksum(payload: bytes) -> int:
    return sum(payload) & 0xFF


def frame(payload: bytes) -> bytes:
    """``$payload#cc`` (the payload must already be escaped if it carries binary data)."""
    return b"$" + payload + b"#" + f"{checksum(payload):02x}".encode()


def escape_binary(data: bytes) -> bytes:
    """Binary data for a payload: ``$ # } *`` become ``}`` followed by the byte XOR 0x20."""
    out = bytearray()
    for byte in data:
        if byte in _MUST_ESCAPE:
            out += bytes((_ESCAPE, byte ^ 0x20))
        else:
            out.append(byte)
    return bytes(out)


def unescape_binary(data: bytes) -> bytes:
    """The inverse of :func:`escape_binary`.

    Raises:
        ValueError: the data ends in the middle of an escape.
    """
    out = bytearray()
    it = iter(data)
    for byte in it:
        if byte == _ESCAPE:
            nxt = next(it, None)
            if nxt is None:
                raise ValueError("binary data ends with an escape character")
            out.append(nxt ^ 0x20)
        else:
            out.append(byte)
    return bytes(out)
