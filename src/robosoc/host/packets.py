"""Packet formats between the I/O tile and the firmware tasks, written once.

This module is the single source of the application packets' layout and units, and of the
message ports the quadrotor project's travel to (:data:`PORTS`):

- ``sensor``: one sensor sample, I/O tile → estimator (EKF) task;
- ``estimate``: the state estimate, estimator task → PID task;
- ``pwm``: four PWM values and the sample's sequence number, PID task → I/O tile;
- ``position``: the newest position fix and the mission's position setpoint, I/O tile → a firmware
  project that declares a message of it (docs/firmware-projects.md), with every sensor sample.

``include/robosoc_packets.h`` (the C structs) is generated from it (``python -m
robosoc.host.packets``); a test checks the file is up to date, and the header's own
``_Static_assert`` lines make every C build check each offset and size.

**Encoding.**  A packet is a little-endian C struct without padding: ``u16`` and ``u32`` are
unsigned integers, ``q16`` a signed Q16.16 number (an ``int32`` holding value · 65536, rounded to
nearest), the number format of the seed's firmware.  On the NoC the struct's bytes are 16-bit
flits in memory order (flit k = byte 2k | byte 2k+1 << 8), as the network interface's DMA copies
them.  A packet must fit one NoC packet (:mod:`robosoc.config.packet_layout`, whose layout rule
also checks the formats a firmware project declares): :data:`MAX_PAYLOAD_FLITS` = 58 flits.
Every packet starts with ``kind`` (a per-format tag, so that a stray or malformed packet is
recognised) and ``flags``.
"""

from __future__ import annotations

import functools
import struct
import sys
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Literal

from robosoc.config.packet_layout import (
    FIELD_BYTES,
    MAX_PAYLOAD_FLITS,
    MESSAGE_HEADER_FLITS,
    NOC_HEADER_FLITS,
    LayoutError,
    lay_out,
)
from robosoc.firmware import INCLUDE_DIR

FieldType = Literal["u16", "u32", "q16"]

Q16_ONE = 65536
Q16_MIN = -(2**31)
Q16_MAX = 2**31 - 1

_STRUCT_CODE: dict[str, str] = {"u16": "H", "u32": "I", "q16": "i"}
_C_TYPE: dict[str, str] = {"u16": "uint16_t", "u32": "uint32_t", "q16": "int32_t"}
_SIZE = FIELD_BYTES

Value = int | float | tuple[int, ...] | tuple[float, ...]


@dataclass(frozen=True)
class Field:
    """One field: ``count`` values of ``type`` in ``unit``."""

    name: str
    type: FieldType
    unit: str
    doc: str
    count: int = 1

    @property
    def size(self) -> int:
        """Bytes."""
        return _SIZE[self.type] * self.count


@dataclass(frozen=True)
class PacketFormat:
    """The layout of one application packet (a C struct without padding)."""

    name: str
    kind: int
    doc: str
    fields: tuple[Field, ...]

    def __post_init__(self) -> None:
        try:  # the one layout rule (config/packet_layout.py): no padding, one NoC packet
            lay_out([(f.name, f.type, f.count) for f in self.fields])
        except LayoutError as exc:
            where = self.name if exc.index is None else f"{self.name}.{self.fields[exc.index].name}"
            raise ValueError(f"{where}: {exc.reason}") from None
        if self.fields[:2] != HEAD_FIELDS:
            raise ValueError(f"{self.name}: must start with the kind and flags fields")

    @functools.cached_property
    def size(self) -> int:
        """Bytes."""
        return sum(f.size for f in self.fields)

    @property
    def flits(self) -> int:
        """16-bit flits."""
        return self.size // 2

    @property
    def offsets(self) -> dict[str, int]:
        """Byte offset of every field."""
        out: dict[str, int] = {}
        offset = 0
        for f in self.fields:
            out[f.name] = offset
            offset += f.size
        return out

    @property
    def c_name(self) -> str:
        """The C struct's name."""
        return f"robosoc_{self.name}_packet"

    @functools.cached_property
    def _struct(self) -> struct.Struct:
        return struct.Struct("<" + "".join(f"{f.count}{_STRUCT_CODE[f.type]}" for f in self.fields))

    @functools.cached_property
    def _decoders(self) -> tuple[tuple[str, int, int, bool], ...]:
        """Per field: its name, where its values start in the struct's tuple, how many, and whether
        they are q16 (worked out once: a flight unpacks a PWM packet per sample)."""
        out = []
        start = 0
        for f in self.fields:
            out.append((f.name, start, f.count, f.type == "q16"))
            start += f.count
        return tuple(out)

    @functools.cached_property
    def _names(self) -> frozenset[str]:
        return frozenset(f.name for f in self.fields)

    def pack(self, values: Mapping[str, Value]) -> bytes:
        """The packet's bytes.  ``kind`` is filled in; missing fields are 0; q16 fields take floats.

        Raises:
            ValueError: an unknown field, a wrong number of values, or a value out of range.
        """
        unknown = values.keys() - self._names
        if unknown:
            raise ValueError(f"{self.name}: unknown fields {sorted(unknown)}")
        raw: list[int] = []
        for f in self.fields:
            value = self.kind if f.name == "kind" else values.get(f.name, 0 if f.count == 1 else (0,) * f.count)
            # (tuples first: a flight packs one sensor packet per sample, and the ABC check is slow)
            items = list(value) if type(value) is tuple or isinstance(value, Sequence) else [value]
            if len(items) != f.count:
                raise ValueError(f"{self.name}.{f.name}: {len(items)} values, expected {f.count}")
            raw.extend(_encode(f, v) for v in items)
        return self._struct.pack(*raw)

    def pack_words(self, words: Sequence[int]) -> bytes:
        """The packet's bytes from every value already encoded (``kind`` included), in the fields'
        order: what :meth:`pack` makes of them, for a caller that checked their ranges itself.

        Raises:
            struct.error: a wrong number of values, or one out of its type's range.
        """
        return self._struct.pack(*words)

    def unpack(self, data: bytes) -> dict[str, Value]:
        """The fields of a packet's bytes (q16 fields as floats, arrays as tuples).

        Raises:
            ValueError: wrong length or wrong kind.
        """
        if len(data) != self.size:
            raise ValueError(f"{self.name}: {len(data)} bytes, expected {self.size}")
        raw = self._struct.unpack(data)
        out: dict[str, Value] = {}
        for name, start, count, q16 in self._decoders:
            if count == 1:
                out[name] = raw[start] / Q16_ONE if q16 else raw[start]
            else:
                items = raw[start : start + count]
                out[name] = tuple(v / Q16_ONE for v in items) if q16 else items
        if out["kind"] != self.kind:
            raise ValueError(f"{self.name}: kind 0x{out['kind']:04x}, expected 0x{self.kind:04x}")
        return out


def scalar(values: Mapping[str, Value], name: str) -> int | float:
    """Field ``name`` of unpacked ``values``, a one-value field.

    Raises:
        TypeError: the field is an array.
    """
    value = values[name]
    if isinstance(value, tuple):
        raise TypeError(f"{name}: an array field, not one value")
    return value


def array(values: Mapping[str, Value], name: str) -> tuple[int, ...] | tuple[float, ...]:
    """Field ``name`` of unpacked ``values``, an array field.

    Raises:
        TypeError: the field holds one value.
    """
    value = values[name]
    if not isinstance(value, tuple):
        raise TypeError(f"{name}: a one-value field, not an array")
    return value


def _encode(f: Field, value: float) -> int:
    if f.type == "q16":
        scaled = round(float(value) * Q16_ONE)
        if not Q16_MIN <= scaled <= Q16_MAX:
            raise ValueError(f"{f.name}: {value} is outside the Q16.16 range")
        return scaled
    limit = 0xFFFF if f.type == "u16" else 0xFFFFFFFF
    if int(value) != value or not 0 <= int(value) <= limit:
        raise ValueError(f"{f.name}: {value} is not a {f.type}")
    return int(value)


def to_flits(data: bytes) -> list[int]:
    """A packet's bytes as 16-bit flits (little-endian pairs, as the DMA copies memory)."""
    if len(data) % 2:
        raise ValueError("a packet is a whole number of flits")
    return list(struct.unpack(f"<{len(data) // 2}H", data))


def from_flits(flits: Sequence[int]) -> bytes:
    """Inverse of :func:`to_flits`."""
    return struct.pack(f"<{len(flits)}H", *flits)


def q16(value: float) -> int:
    """A value in Q16.16 (rounded to nearest), as the packets carry it."""
    return round(value * Q16_ONE)


HEAD_FIELDS = (
    Field("kind", "u16", "-", "format tag (ROBOSOC_*_KIND): a packet with another tag is malformed"),
    Field(
        "flags", "u16", "-", "bit 0 armed (ROBOSOC_FLAG_ARMED), bit 1 low battery (ROBOSOC_FLAG_LOW_BATTERY); others 0"
    ),
)

SENSOR = PacketFormat(
    "sensor",
    0x5201,
    "One sensor sample, I/O tile -> estimator task (body frame FLU).",
    (
        *HEAD_FIELDS,
        Field("seq", "u32", "-", "sample number, 0 for the first sample of a flight"),
        Field("time_us", "u32", "us", "sample time since the start of the flight"),
        Field("dt_us", "u32", "us", "time since the previous sample (the sample period for the first)"),
        Field("gyro", "q16", "rad/s", "body rates p, q, r", 3),
        Field("accel", "q16", "m/s^2", "specific force (at rest: +g along body up)", 3),
        Field("mag", "q16", "unit field", "magnetic field", 3),
        Field("baro_altitude", "q16", "m", "barometric altitude"),
        Field("setpoint", "q16", "rad, rad, rad, m", "roll, pitch, yaw and height setpoints", 4),
        Field("height_feedforward", "q16", "m/s, m/s^2", "the height setpoint profile's rate and acceleration", 2),
    ),
)

ESTIMATE = PacketFormat(
    "estimate",
    0x5202,
    "The state estimate after one sensor sample, estimator task -> PID task.",
    (
        *HEAD_FIELDS,
        Field("seq", "u32", "-", "the sensor sample's number"),
        Field("time_us", "u32", "us", "the sensor sample's time"),
        Field("dt_us", "u32", "us", "the sensor sample's dt_us"),
        Field("quaternion", "q16", "-", "attitude w, x, y, z (body -> world)", 4),
        Field("rate", "q16", "rad/s", "bias-corrected body rates p, q, r", 3),
        Field("height", "q16", "m", "estimated height"),
        Field("vertical_velocity", "q16", "m/s", "estimated vertical velocity"),
        Field("setpoint", "q16", "rad, rad, rad, m", "the sensor sample's setpoints, forwarded", 4),
        Field("height_feedforward", "q16", "m/s, m/s^2", "the sensor sample's height_feedforward, forwarded", 2),
    ),
)

PWM = PacketFormat(
    "pwm",
    0x5203,
    "The motor command for one sensor sample, PID task -> I/O tile.",
    (
        *HEAD_FIELDS,
        Field("seq", "u32", "-", "the sensor sample's number"),
        Field("pwm", "u16", "PWM count (0-255)", "motors 0-3", 4),
    ),
)

POSITION = PacketFormat(
    "position",
    0x5204,
    "The newest position fix and the position setpoint, I/O tile -> a project's task (world frame, z up).",
    (
        *HEAD_FIELDS,
        Field("seq", "u32", "-", "the sensor sample's number (its sensor packet has the same)"),
        Field("time_us", "u32", "us", "the sensor sample's time"),
        Field("fix_time_us", "u32", "us", "when the fix was taken (at most one fix period before time_us)"),
        Field("fix_number", "u32", "-", "the fix's number, 0 for the first: a new fix when it changes"),
        Field("position", "q16", "m", "the fix: position x, y, z of the body origin", 3),
        Field("velocity", "q16", "m/s", "the fix: velocity x, y, z", 3),
        Field("setpoint", "q16", "m", "position setpoint x, y, z (z: the sensor packet's height setpoint)", 3),
        Field("setpoint_velocity", "q16", "m/s", "the setpoint's rate (feed-forward)", 3),
        Field("setpoint_accel", "q16", "m/s^2", "the setpoint's acceleration (feed-forward)", 3),
    ),
)

FORMATS: tuple[PacketFormat, ...] = (SENSOR, ESTIMATE, PWM, POSITION)
FLAG_ARMED = 1
FLAG_LOW_BATTERY = 2
"""Set by the I/O tile in a battery flight once the pack is below its reserve (docs/power.md): the
firmware built with the failsafe lands and disarms."""


@dataclass(frozen=True)
class Port:
    """A kernel message port (``os_task_event``/``os_recv``) of the flight application."""

    name: str
    number: int
    tile: str
    doc: str


SENSOR_PORT = 1
"""Sensor packets arrive on this port of the estimator's tile."""
ESTIMATE_PORT = 2
"""Estimate packets arrive on this port of the PID task's tile."""
PWM_PORT = 3
"""PWM packets arrive on this port of the I/O tile."""
PORTS: tuple[Port, ...] = (
    Port("sensor", SENSOR_PORT, "estimator tile", "sensor packets, I/O tile -> estimator task"),
    Port("estimate", ESTIMATE_PORT, "PID tile", "estimate packets, estimator task -> PID task"),
    Port("pwm", PWM_PORT, "I/O tile", "PWM packets, PID task -> I/O tile"),
)

HEADER_PATH = INCLUDE_DIR / "robosoc_packets.h"


def c_header() -> str:
    """The text of ``include/robosoc_packets.h``."""
    lines = [
        "/*",
        " * robosoc_packets.h - the application packets' layout and units.",
        " *",
        " * GENERATED from src/robosoc/host/packets.py (python -m robosoc.host.packets): edit",
        " * that file, not this one.  Little-endian structs without padding; q16 fields are Q16.16",
        " * (int32 holding value * 65536).  On the NoC a packet's bytes are 16-bit flits in memory order.",
        " * The asserts make every build check the layout the Python side uses.",
        " */",
        "#ifndef ROBOSOC_PACKETS_H",
        "#define ROBOSOC_PACKETS_H",
        "",
        "#include <stddef.h>",
        "#include <stdint.h>",
        "",
        f"#define ROBOSOC_NOC_HEADER_FLITS {NOC_HEADER_FLITS}",
        f"#define ROBOSOC_MESSAGE_HEADER_FLITS {MESSAGE_HEADER_FLITS}",
        f"#define ROBOSOC_MAX_PAYLOAD_FLITS {MAX_PAYLOAD_FLITS}",
        f"#define ROBOSOC_FLAG_ARMED {FLAG_ARMED}u",
        f"#define ROBOSOC_FLAG_LOW_BATTERY {FLAG_LOW_BATTERY}u",
        "",
        "/* Message ports of the flight application (kernel ports, below OS_MSG_PORTS) */",
        *(f"#define ROBOSOC_{port.name.upper()}_PORT {port.number}u /* {port.tile}: {port.doc} */" for port in PORTS),
    ]
    for fmt in FORMATS:
        upper = fmt.name.upper()
        lines += [
            "",
            f"/* {fmt.doc} */",
            f"#define ROBOSOC_{upper}_KIND 0x{fmt.kind:04x}u",
            f"#define ROBOSOC_{upper}_BYTES {fmt.size}u",
            f"#define ROBOSOC_{upper}_FLITS {fmt.flits}u",
            f"struct {fmt.c_name} {{",
        ]
        for f in fmt.fields:
            dims = f"[{f.count}]" if f.count > 1 else ""
            unit = "" if f.unit == "-" else f" [{f.unit}]"
            lines.append(
                f"    {_C_TYPE[f.type]} {f.name}{dims}; /* {f.doc}{unit}{' (Q16.16)' if f.type == 'q16' else ''} */"
            )
        lines.append("};")
        lines.append(f'_Static_assert(sizeof(struct {fmt.c_name}) == {fmt.size}, "{fmt.name} packet size");')
        for name, offset in fmt.offsets.items():
            lines.append(
                f'_Static_assert(offsetof(struct {fmt.c_name}, {name}) == {offset}, "{fmt.name}.{name} offset");'
            )
    lines += ["", "#endif /* ROBOSOC_PACKETS_H */", ""]
    return "\n".join(lines)


def markdown_tables() -> str:
    """The formats as markdown tables (docs/firmware-libraries.md quotes this text; a test checks it)."""
    out: list[str] = []
    for fmt in FORMATS:
        out += [
            f"**{fmt.name}** (`struct {fmt.c_name}`, kind 0x{fmt.kind:04x}, {fmt.size} bytes, {fmt.flits} flits): "
            f"{fmt.doc}",
            "",
            "| byte | field | type | unit | meaning |",
            "|---|---|---|---|---|",
        ]
        offsets = fmt.offsets
        for f in fmt.fields:
            kind = f"{f.type}[{f.count}]" if f.count > 1 else f.type
            out.append(f"| {offsets[f.name]} | {f.name} | {kind} | {f.unit} | {f.doc} |")
        out.append("")
    return "\n".join(out)


def main(argv: Sequence[str] | None = None) -> int:
    """Write (or with ``--check`` compare) ``include/robosoc_packets.h``."""
    args = list(sys.argv[1:] if argv is None else argv)
    text = c_header()
    if args == ["--check"]:
        current = HEADER_PATH.read_text() if HEADER_PATH.is_file() else ""
        if current != text:
            print(f"{HEADER_PATH} is out of date: run python -m robosoc.host.packets", file=sys.stderr)
            return 1
        return 0
    HEADER_PATH.write_text(text)
    print(HEADER_PATH)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
