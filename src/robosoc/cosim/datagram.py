"""The datagrams of the decoupled mode (docs/decoupled.md): layout, encoding, strict decoding.

Every datagram is a 20-byte header and a payload, little-endian::

    offset size  field
    0      4     magic b"RSoC"
    4      1     version (:data:`VERSION`)
    5      1     kind: 1 hello, 2 sensor batch, 3 actuator commands, 4 bye, 5 telemetry
    6      2     flags (0)
    8      4     sequence number (data datagrams: 0, 1, 2 ... per sender; hello and bye: 0)
    12     4     payload length in bytes
    16     4     CRC-32 (zlib.crc32) of the header, with this field 0, and the payload
    20     ...   payload

Payloads:

* **hello** (chip → physics, repeated until the first sensor batch): an 8-byte digest of the
  scenario and vehicle the chip's firmware was built for, the sensor period in ns, and the names
  of the telemetry values the firmware publishes (its project's ``[[telemetry]]``, in order): what
  each telemetry entry holds.
* **sensor batch** (physics → chip): the physics' time ``now_ns`` when it left, a count, and that
  many readings ``(k, t_ns, sensor packet)``: every reading since the last send, each with its
  timestamp, plus the ``resend`` readings before them (the seed's latency compensation: the chip
  injects each reading at the cycle of its timestamp, whenever it arrives).
* **actuator commands** (chip → physics): the chip's time ``chip_now_ns`` (it has simulated up to
  there: every command that left before is in this or an earlier datagram), a count, and that
  many commands ``(seq, left_ns, pwm[4])``: the PWM command of sensor sample ``seq`` with the chip
  time it reached the I/O tile, newest last.
* **telemetry** (chip → physics): the chip's time, the number of values per entry, a count, and
  that many entries ``(k, t_ns, values as f64)``: the newest value of each name of the hello (NaN
  before its first read) after the read at the close of the period of sensor sample ``k`` (taken
  at ``t_ns``), newest last, plus the ``resend`` before them.  The flight log's columns of the
  firmware's telemetry, its estimate columns among them (:mod:`robosoc.host.telemetry`), as in
  lockstep.
* **bye**: why the sender stops, how many data datagrams it sent (so the peer can count losses at
  the end), and its final time in ns.

Times are integer nanoseconds of the flight (0 at the first sensor sample).  :func:`decode` never
raises: it returns a :class:`Datagram` or a :class:`Rejected` naming the class of bad input.
"""

from __future__ import annotations

import enum
import struct
import zlib
from dataclasses import dataclass

from robosoc.host import packets

__all__ = [
    "HEADER",
    "MAGIC",
    "MAX_DATAGRAM_BYTES",
    "VERSION",
    "Bye",
    "ByeReason",
    "Command",
    "CommandBatch",
    "Datagram",
    "Hello",
    "Kind",
    "Reading",
    "Rejected",
    "Rejection",
    "SensorBatch",
    "TelemetryBatch",
    "TelemetryEntry",
    "decode",
    "encode",
    "max_telemetry_entries",
]

MAGIC = b"RSoC"
VERSION = 2
"""2: the hello names the telemetry values, and telemetry entries replace version 1's estimates."""
HEADER = struct.Struct("<4sBBHIII")
HEADER_BYTES = HEADER.size
#: Longest datagram a side sends or accepts whole (one Ethernet frame's IP payload, less IP and UDP).
MAX_DATAGRAM_BYTES = 1472


class Kind(enum.IntEnum):
    HELLO = 1
    SENSORS = 2
    COMMANDS = 3
    BYE = 4
    TELEMETRY = 5


class ByeReason(enum.IntEnum):
    DONE = 0
    INTERRUPTED = 1
    PEER_LOST = 2
    ERROR = 3


class Rejection(enum.Enum):
    """Why a datagram was refused; :attr:`counter` says which link counter it goes to."""

    TRUNCATED = "truncated"  # shorter than its header or than the payload length it declares
    BAD_MAGIC = "bad_magic"  # does not start with MAGIC: not ours (garbage)
    BAD_VERSION = "bad_version"
    BAD_KIND = "bad_kind"
    BAD_LENGTH = "bad_length"  # longer than the header says (length mismatch)
    BAD_CHECKSUM = "bad_checksum"
    BAD_PAYLOAD = "bad_payload"  # the payload does not parse as its kind

    @property
    def counter(self) -> str:
        return "truncated" if self is Rejection.TRUNCATED else "garbage"


@dataclass(frozen=True)
class Hello:
    """``telemetry``: the names of the values of each :class:`TelemetryEntry` the chip sends."""

    digest: bytes
    sample_period_ns: int
    telemetry: tuple[str, ...] = ()


@dataclass(frozen=True)
class Reading:
    """Sensor sample ``k`` taken at ``t_ns``: the firmware's sensor packet (:data:`packets.SENSOR`)."""

    k: int
    t_ns: int
    packet: bytes


@dataclass(frozen=True)
class SensorBatch:
    now_ns: int
    readings: tuple[Reading, ...]


@dataclass(frozen=True)
class Command:
    """The PWM command of sensor sample ``seq``; it reached the I/O tile at chip time ``left_ns``."""

    seq: int
    left_ns: int
    pwm: tuple[int, int, int, int]


@dataclass(frozen=True)
class CommandBatch:
    chip_now_ns: int
    commands: tuple[Command, ...]


@dataclass(frozen=True)
class TelemetryEntry:
    """The firmware's telemetry after the read at the close of sensor sample ``k``'s period (the
    sample taken at ``t_ns``): the newest value of each name of the chip's hello, NaN before its
    first read."""

    k: int
    t_ns: int
    values: tuple[float, ...]


@dataclass(frozen=True)
class TelemetryBatch:
    chip_now_ns: int
    entries: tuple[TelemetryEntry, ...]


@dataclass(frozen=True)
class Bye:
    reason: ByeReason
    data_sent: int
    end_ns: int


Body = Hello | SensorBatch | CommandBatch | TelemetryBatch | Bye
KIND_OF: dict[type, Kind] = {
    Hello: Kind.HELLO,
    SensorBatch: Kind.SENSORS,
    CommandBatch: Kind.COMMANDS,
    Bye: Kind.BYE,
    TelemetryBatch: Kind.TELEMETRY,
}


@dataclass(frozen=True)
class Datagram:
    kind: Kind
    seq: int
    body: Body


@dataclass(frozen=True)
class Rejected:
    reason: Rejection
    detail: str
    size: int


_HELLO = struct.Struct("<8sQH")
_BATCH = struct.Struct("<QH")
_READING = struct.Struct("<IQ")
_COMMAND = struct.Struct("<IQ4H")
_BYE = struct.Struct("<BIQ")
_TELEMETRY = struct.Struct("<QHH")  # chip_now_ns, values per entry, entries
_ENTRY = struct.Struct("<IQ")  # k, t_ns; then the values, f64 each
_VALUE_BYTES = 8
SENSOR_BYTES = packets.SENSOR.size
READING_BYTES = _READING.size + SENSOR_BYTES
#: Most readings or commands one datagram holds.
MAX_READINGS = (MAX_DATAGRAM_BYTES - HEADER_BYTES - _BATCH.size) // READING_BYTES
MAX_COMMANDS = (MAX_DATAGRAM_BYTES - HEADER_BYTES - _BATCH.size) // _COMMAND.size
#: Longest telemetry name a hello carries (a byte gives its length).
MAX_NAME_BYTES = 255


def max_telemetry_entries(values: int) -> int:
    """Most telemetry entries of ``values`` values each that one datagram holds (0: not even one)."""
    return (MAX_DATAGRAM_BYTES - HEADER_BYTES - _TELEMETRY.size) // (_ENTRY.size + _VALUE_BYTES * values)


def _names_payload(names: tuple[str, ...]) -> bytes:
    parts = []
    for name in names:
        raw = name.encode("ascii")
        if not raw or len(raw) > MAX_NAME_BYTES:
            raise ValueError(f"hello: telemetry name {name!r} is not 1..{MAX_NAME_BYTES} bytes")
        parts += [bytes((len(raw),)), raw]
    return b"".join(parts)


def _names(payload: bytes, count: int) -> tuple[str, ...] | str:
    """The ``count`` names in ``payload`` (a length byte and ASCII each), or why they do not parse."""
    names: list[str] = []
    offset = 0
    for i in range(count):
        if offset >= len(payload):
            return f"hello: {count} telemetry names announced, {i} there"
        size = payload[offset]
        raw = payload[offset + 1 : offset + 1 + size]
        offset += 1 + size
        if len(raw) != size:
            return f"hello: telemetry name {i} cut short"
        if not raw.isascii() or not raw.decode("ascii").isidentifier():
            return f"hello: telemetry name {i} is not an identifier: {raw[:32]!r}"
        names.append(raw.decode("ascii"))
    if offset != len(payload):
        return f"hello: {len(payload) - offset} bytes after its {count} telemetry names"
    if len(set(names)) != len(names):
        return "hello: a telemetry name given twice"
    return tuple(names)


def _payload(body: Body) -> bytes:
    if isinstance(body, Hello):
        if len(body.digest) != 8:
            raise ValueError("hello: the digest is 8 bytes")
        payload = _HELLO.pack(body.digest, body.sample_period_ns, len(body.telemetry)) + _names_payload(body.telemetry)
        if HEADER_BYTES + len(payload) > MAX_DATAGRAM_BYTES:
            raise ValueError(f"hello: {len(body.telemetry)} telemetry names do not fit a datagram")
        return payload
    if isinstance(body, SensorBatch):
        if len(body.readings) > MAX_READINGS:
            raise ValueError(f"sensor batch: at most {MAX_READINGS} readings, got {len(body.readings)}")
        parts = [_BATCH.pack(body.now_ns, len(body.readings))]
        for r in body.readings:
            if len(r.packet) != SENSOR_BYTES:
                raise ValueError(f"reading {r.k}: a sensor packet is {SENSOR_BYTES} bytes, got {len(r.packet)}")
            parts += [_READING.pack(r.k, r.t_ns), r.packet]
        return b"".join(parts)
    if isinstance(body, CommandBatch):
        if len(body.commands) > MAX_COMMANDS:
            raise ValueError(f"command batch: at most {MAX_COMMANDS} commands, got {len(body.commands)}")
        parts = [_BATCH.pack(body.chip_now_ns, len(body.commands))]
        parts += [_COMMAND.pack(c.seq, c.left_ns, *c.pwm) for c in body.commands]
        return b"".join(parts)
    if isinstance(body, TelemetryBatch):
        values = len(body.entries[0].values) if body.entries else 0
        most = max_telemetry_entries(values)
        if len(body.entries) > most:
            raise ValueError(f"telemetry batch: at most {most} entries of {values} values, got {len(body.entries)}")
        parts = [_TELEMETRY.pack(body.chip_now_ns, values, len(body.entries))]
        for e in body.entries:
            if len(e.values) != values:
                raise ValueError(f"telemetry entry {e.k}: {len(e.values)} values, the batch's first has {values}")
            parts += [_ENTRY.pack(e.k, e.t_ns), struct.pack(f"<{values}d", *e.values)]
        return b"".join(parts)
    return _BYE.pack(int(body.reason), body.data_sent, body.end_ns)


def encode(body: Body, seq: int = 0) -> bytes:
    """The datagram carrying ``body`` with sequence number ``seq``.

    Raises:
        ValueError / struct.error: a field does not fit its layout (a bug of the caller).
    """
    payload = _payload(body)
    fields = (MAGIC, VERSION, KIND_OF[type(body)], 0, seq, len(payload))
    crc = zlib.crc32(HEADER.pack(*fields, 0) + payload)
    return HEADER.pack(*fields, crc) + payload


def _parse(kind: Kind, payload: bytes) -> Body | str:
    """The body, or why the payload does not parse."""
    if kind is Kind.HELLO:
        if len(payload) < _HELLO.size:
            return f"hello payload of {len(payload)} bytes, shorter than its {_HELLO.size}-byte head"
        digest, period, count = _HELLO.unpack_from(payload)
        if period <= 0:
            return "hello with a sensor period of 0"
        names = _names(payload[_HELLO.size :], count)
        return names if isinstance(names, str) else Hello(digest, period, names)
    if kind is Kind.BYE:
        if len(payload) != _BYE.size:
            return f"bye payload of {len(payload)} bytes, expected {_BYE.size}"
        reason, sent, end = _BYE.unpack(payload)
        if reason not in ByeReason._value2member_map_:
            return f"bye with unknown reason {reason}"
        return Bye(ByeReason(reason), sent, end)
    if kind is Kind.TELEMETRY:
        return _telemetry(payload)
    if len(payload) < _BATCH.size:
        return f"batch payload of {len(payload)} bytes, shorter than its {_BATCH.size}-byte head"
    now, count = _BATCH.unpack_from(payload)
    item = READING_BYTES if kind is Kind.SENSORS else _COMMAND.size
    if len(payload) != _BATCH.size + count * item:
        return f"{count} items need {_BATCH.size + count * item} payload bytes, got {len(payload)}"
    offset = _BATCH.size
    if kind is Kind.SENSORS:
        readings = []
        for _ in range(count):
            k, t = _READING.unpack_from(payload, offset)
            packet = payload[offset + _READING.size : offset + READING_BYTES]
            if int.from_bytes(packet[:2], "little") != packets.SENSOR.kind:
                return f"reading {k}: not a sensor packet"
            readings.append(Reading(k, t, packet))
            offset += READING_BYTES
        return SensorBatch(now, tuple(readings))
    commands = []
    for _ in range(count):
        seq, left, *pwm = _COMMAND.unpack_from(payload, offset)
        if max(pwm) > 255:
            return f"command {seq}: PWM {pwm} out of 0..255"
        commands.append(Command(seq, left, (pwm[0], pwm[1], pwm[2], pwm[3])))
        offset += _COMMAND.size
    return CommandBatch(now, tuple(commands))


def _telemetry(payload: bytes) -> TelemetryBatch | str:
    if len(payload) < _TELEMETRY.size:
        return f"telemetry payload of {len(payload)} bytes, shorter than its {_TELEMETRY.size}-byte head"
    now, values, count = _TELEMETRY.unpack_from(payload)
    item = _ENTRY.size + _VALUE_BYTES * values
    if len(payload) != _TELEMETRY.size + count * item:
        need = _TELEMETRY.size + count * item
        return f"{count} telemetry entries of {values} values need {need} payload bytes, got {len(payload)}"
    entries = []
    offset = _TELEMETRY.size
    row = struct.Struct(f"<{values}d")
    for _ in range(count):
        k, t = _ENTRY.unpack_from(payload, offset)
        entries.append(TelemetryEntry(k, t, row.unpack_from(payload, offset + _ENTRY.size)))
        offset += item
    return TelemetryBatch(now, tuple(entries))


def decode(data: bytes) -> Datagram | Rejected:
    """The datagram in ``data``, or what is wrong with it.  Never raises."""
    size = len(data)
    prefix = min(size, len(MAGIC))
    if data[:prefix] != MAGIC[:prefix]:
        return Rejected(Rejection.BAD_MAGIC, f"starts with {bytes(data[:8]).hex()}", size)
    if size < HEADER_BYTES:
        return Rejected(Rejection.TRUNCATED, f"{size} bytes, shorter than the {HEADER_BYTES}-byte header", size)
    _, version, kind, flags, seq, length, crc = HEADER.unpack_from(data)
    if version != VERSION:
        return Rejected(Rejection.BAD_VERSION, f"version {version}, expected {VERSION}", size)
    if kind not in Kind._value2member_map_:
        return Rejected(Rejection.BAD_KIND, f"unknown kind {kind}", size)
    if size < HEADER_BYTES + length:
        return Rejected(Rejection.TRUNCATED, f"{size - HEADER_BYTES} of {length} payload bytes", size)
    if size > HEADER_BYTES + length:
        return Rejected(Rejection.BAD_LENGTH, f"{size - HEADER_BYTES} payload bytes, the header says {length}", size)
    payload = bytes(data[HEADER_BYTES:])
    actual = zlib.crc32(HEADER.pack(MAGIC, version, kind, flags, seq, length, 0) + payload)
    if actual != crc:
        return Rejected(Rejection.BAD_CHECKSUM, f"CRC-32 {actual:08x}, the header says {crc:08x}", size)
    body = _parse(Kind(kind), payload)
    if isinstance(body, str):
        return Rejected(Rejection.BAD_PAYLOAD, body, size)
    return Datagram(Kind(kind), seq, body)
