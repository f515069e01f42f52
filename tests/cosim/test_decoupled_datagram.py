"""The decoupled mode's datagrams: the documented layout, round trips, and every class of bad input."""

from __future__ import annotations

import math
import struct
import zlib

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from robosoc.cosim.datagram import (
    MAX_COMMANDS,
    MAX_DATAGRAM_BYTES,
    MAX_READINGS,
    Bye,
    ByeReason,
    Command,
    CommandBatch,
    Datagram,
    Hello,
    Kind,
    Reading,
    Rejected,
    Rejection,
    SensorBatch,
    TelemetryBatch,
    TelemetryEntry,
    decode,
    encode,
    max_telemetry_entries,
)
from robosoc.host import packets


def sensor_packet(k: int) -> bytes:
    values = {f.name: (0,) * f.count if f.count > 1 else 0 for f in packets.SENSOR.fields}
    values.update(kind=packets.SENSOR.kind, seq=k, time_us=10_000 * k, dt_us=10_000, baro_altitude=0.25 * k)
    return packets.SENSOR.pack(values)


BODIES = [
    Hello(b"\x01\x02\x03\x04\x05\x06\x07\x08", 10_000_000),
    Hello(b"\x01\x02\x03\x04\x05\x06\x07\x08", 10_000_000, ("est_qw", "jobs_done", "x" * 255)),
    SensorBatch(30_000_000, tuple(Reading(k, k * 10_000_000, sensor_packet(k)) for k in (1, 2, 3))),
    SensorBatch(0, ()),
    CommandBatch(12_345_678, (Command(7, 70_135_000, (0, 17, 200, 255)), Command(8, 80_134_996, (1, 2, 3, 4)))),
    Bye(ByeReason.INTERRUPTED, 1234, 9_990_000_000),
    TelemetryBatch(
        40_000_000,
        (
            TelemetryEntry(2, 20_000_000, (1.0, 0.0, -0.5, 2.0**-16, 0.25, -1e-3)),
            TelemetryEntry(3, 30_000_000, (0.75, 1e-300, 3.0, -4.0, math.inf, math.nan)),
        ),
    ),
    TelemetryBatch(7, ()),
]


@pytest.mark.parametrize("body", BODIES, ids=lambda b: type(b).__name__)
def test_round_trip(body) -> None:
    d = decode(encode(body, seq=41))
    assert isinstance(d, Datagram)
    kinds = {
        Hello: Kind.HELLO, SensorBatch: Kind.SENSORS, CommandBatch: Kind.COMMANDS, Bye: Kind.BYE,
        TelemetryBatch: Kind.TELEMETRY,
    }  # fmt: skip
    assert d.seq == 41 and d.kind is kinds[type(body)]
    assert repr(d.body) == repr(body)  # NaN is not equal to itself, its repr is


def test_the_documented_layout() -> None:
    """A command datagram built by hand from the layout table in the module docstring decodes."""
    payload = struct.pack("<QH", 5_000_000, 1) + struct.pack("<IQ4H", 3, 4_999_000, 10, 20, 30, 40)
    header = struct.pack("<4sBBHIII", b"RSoC", 2, 3, 0, 99, len(payload), 0)
    crc = zlib.crc32(header + payload)
    d = decode(struct.pack("<4sBBHIII", b"RSoC", 2, 3, 0, 99, len(payload), crc) + payload)
    assert d == Datagram(Kind.COMMANDS, 99, CommandBatch(5_000_000, (Command(3, 4_999_000, (10, 20, 30, 40)),)))


def test_the_largest_batches_fit_one_datagram() -> None:
    readings = tuple(Reading(k, k, sensor_packet(k)) for k in range(MAX_READINGS))
    assert len(encode(SensorBatch(0, readings))) <= MAX_DATAGRAM_BYTES
    commands = tuple(Command(k, k, (1, 2, 3, 4)) for k in range(MAX_COMMANDS))
    assert len(encode(CommandBatch(0, commands))) <= MAX_DATAGRAM_BYTES
    for values in (0, 1, 6, 40, 178):
        most = max_telemetry_entries(values)
        entries = tuple(TelemetryEntry(k, k, (0.5,) * values) for k in range(most))
        assert most >= 1 and len(encode(TelemetryBatch(0, entries))) <= MAX_DATAGRAM_BYTES
        # one more entry would not fit: 20-byte header, 12-byte head, 12 + 8 * values per entry
        assert 20 + 12 + (most + 1) * (12 + 8 * values) > MAX_DATAGRAM_BYTES
        with pytest.raises(ValueError, match="at most"):
            encode(TelemetryBatch(0, (*entries, entries[0])))
    assert max_telemetry_entries(179) == 0  # 20 + 12 + 12 + 8 * 179 = 1476 bytes
    with pytest.raises(ValueError, match="2 values, the batch's first has 1"):
        encode(TelemetryBatch(0, (TelemetryEntry(0, 0, (1.0,)), TelemetryEntry(1, 1, (1.0, 2.0)))))
    with pytest.raises(ValueError, match="do not fit"):
        encode(Hello(bytes(8), 1, tuple(f"n{i:0>9}" for i in range(200))))  # 200 * 11 bytes
    with pytest.raises(ValueError, match="at most"):
        encode(SensorBatch(0, (*readings, readings[0])))


def rejected(data: bytes) -> Rejection:
    result = decode(data)
    assert isinstance(result, Rejected), result
    return result.reason


GOOD = encode(BODIES[4], seq=5)


def _datagram(kind: int, payload: bytes, seq: int = 3, version: int = 2) -> bytes:
    header = struct.pack("<4sBBHIII", b"RSoC", version, kind, 0, seq, len(payload), 0)
    crc = zlib.crc32(header + payload)
    return struct.pack("<4sBBHIII", b"RSoC", version, kind, 0, seq, len(payload), crc) + payload


def test_the_documented_telemetry_and_hello_layouts() -> None:
    """A telemetry datagram (kind 5: chip time u64, values per entry u16, entries u16, then per
    entry k u32, t_ns u64, the values f64) and a hello (digest, period u64, names u16, then each
    name as a length byte and ASCII) built by hand from docs/decoupled.md decode."""
    payload = struct.pack("<QHH", 7, 2, 1) + struct.pack("<IQ2d", 4, 40_000_000, 0.5, -0.125)
    d = decode(_datagram(5, payload))
    assert d == Datagram(Kind.TELEMETRY, 3, TelemetryBatch(7, (TelemetryEntry(4, 40_000_000, (0.5, -0.125)),)))
    hello = struct.pack("<8sQH", b"digest!!", 10_000_000, 2) + b"\x06est_qw" + b"\x04jobs"
    d = decode(_datagram(1, hello, seq=0))
    assert d == Datagram(Kind.HELLO, 0, Hello(b"digest!!", 10_000_000, ("est_qw", "jobs")))


def test_a_version_1_peer_and_bad_telemetry_or_names_are_refused() -> None:
    """Version 1 (before telemetry) is refused as another version; a telemetry payload whose size
    is not its count of entries of its count of values, and a hello whose names are cut short, are
    not identifiers, are repeated or leave bytes over, do not parse."""
    result = decode(_datagram(3, struct.pack("<QH", 0, 0), version=1))
    assert isinstance(result, Rejected) and result.reason is Rejection.BAD_VERSION
    assert "version 1, expected 2" in result.detail
    entry = struct.pack("<IQ2d", 4, 40_000_000, 0.5, -0.125)
    for payload in (struct.pack("<QHH", 7, 3, 1) + entry, struct.pack("<QHH", 7, 2, 2) + entry, b"\x00" * 11):
        assert rejected(_datagram(5, payload)) is Rejection.BAD_PAYLOAD
    head = struct.pack("<8sQH", b"digest!!", 10_000_000, 2)
    for names in (b"\x04jobs", b"\x04jobs\x09est", b"\x04jobs\x031ab", b"\x04jobs\x04jobs", b"\x01a\x01b\x00",
                  b"\x01a\x02\xc3\xa9"):  # fmt: skip
        assert rejected(_datagram(1, head + names, seq=0)) is Rejection.BAD_PAYLOAD, names


def test_every_bad_input_class() -> None:
    assert rejected(b"") is Rejection.TRUNCATED
    assert rejected(GOOD[:10]) is Rejection.TRUNCATED  # inside the header
    assert rejected(GOOD[:-1]) is Rejection.TRUNCATED  # inside the payload
    assert rejected(b"GET / HTTP/1.1\r\n\r\n") is Rejection.BAD_MAGIC
    assert rejected(b"\x00" * 40) is Rejection.BAD_MAGIC
    assert rejected(GOOD[:4] + bytes([1]) + GOOD[5:]) is Rejection.BAD_VERSION
    assert rejected(GOOD[:5] + bytes([9]) + GOOD[6:]) is Rejection.BAD_KIND
    assert rejected(GOOD + b"\x00") is Rejection.BAD_LENGTH  # longer than the header says
    flipped = bytearray(GOOD)
    flipped[-3] ^= 0x10
    assert rejected(bytes(flipped)) is Rejection.BAD_CHECKSUM
    # a well-formed datagram whose payload does not parse as its kind (count and size disagree)
    payload = struct.pack("<QH", 0, 2) + struct.pack("<IQ4H", 1, 1, 1, 1, 1, 1)
    wrong = _datagram(3, payload, seq=0)
    assert rejected(wrong) is Rejection.BAD_PAYLOAD
    assert {r.counter for r in Rejection} == {"truncated", "garbage"}
    assert Rejection.TRUNCATED.counter == "truncated" and Rejection.BAD_LENGTH.counter == "garbage"


def test_every_single_bit_flip_and_every_cut_is_rejected() -> None:
    for i in range(len(GOOD)):
        assert rejected(GOOD[:i]) is Rejection.TRUNCATED
        for bit in range(8):
            data = bytearray(GOOD)
            data[i] ^= 1 << bit
            rejected(bytes(data))


@settings(max_examples=300, deadline=None)
@given(st.binary(max_size=200), st.integers(0, 2))
def test_decode_never_raises(data: bytes, prefix: int) -> None:
    data = (b"RSoC\x02" if prefix == 1 else GOOD[:20] if prefix == 2 else b"") + data
    result = decode(data)
    assert isinstance(result, Datagram | Rejected)
    if isinstance(result, Datagram):
        assert decode(encode(result.body, result.seq)) == result
