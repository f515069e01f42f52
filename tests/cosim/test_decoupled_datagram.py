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
    MAX_ESTIMATES,
    MAX_READINGS,
    Bye,
    ByeReason,
    Command,
    CommandBatch,
    Datagram,
    EstimateBatch,
    Hello,
    Kind,
    Reading,
    Rejected,
    Rejection,
    SensorBatch,
    StateEstimate,
    decode,
    encode,
)
from robosoc.host import packets


def sensor_packet(k: int) -> bytes:
    values = {f.name: (0,) * f.count if f.count > 1 else 0 for f in packets.SENSOR.fields}
    values.update(kind=packets.SENSOR.kind, seq=k, time_us=10_000 * k, dt_us=10_000, baro_altitude=0.25 * k)
    return packets.SENSOR.pack(values)


BODIES = [
    Hello(b"\x01\x02\x03\x04\x05\x06\x07\x08", 10_000_000),
    SensorBatch(30_000_000, tuple(Reading(k, k * 10_000_000, sensor_packet(k)) for k in (1, 2, 3))),
    SensorBatch(0, ()),
    CommandBatch(12_345_678, (Command(7, 70_135_000, (0, 17, 200, 255)), Command(8, 80_134_996, (1, 2, 3, 4)))),
    Bye(ByeReason.INTERRUPTED, 1234, 9_990_000_000),
    EstimateBatch(
        40_000_000,
        (
            StateEstimate(2, 20_000_000, (1.0, 0.0, -0.5, 2.0**-16), 0.25, -1e-3),
            StateEstimate(3, 30_000_000, (0.75, 1e-300, 3.0, -4.0), math.inf, math.nan),
        ),
    ),
]


@pytest.mark.parametrize("body", BODIES, ids=lambda b: type(b).__name__)
def test_round_trip(body) -> None:
    d = decode(encode(body, seq=41))
    assert isinstance(d, Datagram)
    kinds = {
        Hello: Kind.HELLO, SensorBatch: Kind.SENSORS, CommandBatch: Kind.COMMANDS, Bye: Kind.BYE,
        EstimateBatch: Kind.ESTIMATES,
    }  # fmt: skip
    assert d.seq == 41 and d.kind is kinds[type(body)]
    assert repr(d.body) == repr(body)  # NaN is not equal to itself, its repr is


def test_the_documented_layout() -> None:
    """A command datagram built by hand from the layout table in the module docstring decodes."""
    payload = struct.pack("<QH", 5_000_000, 1) + struct.pack("<IQ4H", 3, 4_999_000, 10, 20, 30, 40)
    header = struct.pack("<4sBBHIII", b"RSoC", 1, 3, 0, 99, len(payload), 0)
    crc = zlib.crc32(header + payload)
    d = decode(struct.pack("<4sBBHIII", b"RSoC", 1, 3, 0, 99, len(payload), crc) + payload)
    assert d == Datagram(Kind.COMMANDS, 99, CommandBatch(5_000_000, (Command(3, 4_999_000, (10, 20, 30, 40)),)))


def test_the_largest_batches_fit_one_datagram() -> None:
    readings = tuple(Reading(k, k, sensor_packet(k)) for k in range(MAX_READINGS))
    assert len(encode(SensorBatch(0, readings))) <= MAX_DATAGRAM_BYTES
    commands = tuple(Command(k, k, (1, 2, 3, 4)) for k in range(MAX_COMMANDS))
    assert len(encode(CommandBatch(0, commands))) <= MAX_DATAGRAM_BYTES
    estimates = tuple(StateEstimate(k, k, (1.0, 0.0, 0.0, 0.0), 1.0, 0.0) for k in range(MAX_ESTIMATES))
    assert len(encode(EstimateBatch(0, estimates))) <= MAX_DATAGRAM_BYTES
    with pytest.raises(ValueError, match="at most"):
        encode(EstimateBatch(0, (*estimates, estimates[0])))
    with pytest.raises(ValueError, match="at most"):
        encode(SensorBatch(0, (*readings, readings[0])))


def rejected(data: bytes) -> Rejection:
    result = decode(data)
    assert isinstance(result, Rejected), result
    return result.reason


GOOD = encode(BODIES[3], seq=5)


def test_the_documented_estimate_layout() -> None:
    """An estimate datagram built by hand from the docstring's layout (kind 5, f64 fields) decodes."""
    payload = struct.pack("<QH", 7, 1) + struct.pack("<IQ6d", 4, 40_000_000, 0.5, 0.5, -0.5, 0.5, 1.25, -0.125)
    header = struct.pack("<4sBBHIII", b"RSoC", 1, 5, 0, 3, len(payload), 0)
    crc = zlib.crc32(header + payload)
    d = decode(struct.pack("<4sBBHIII", b"RSoC", 1, 5, 0, 3, len(payload), crc) + payload)
    assert d == Datagram(
        Kind.ESTIMATES, 3, EstimateBatch(7, (StateEstimate(4, 40_000_000, (0.5, 0.5, -0.5, 0.5), 1.25, -0.125),))
    )


def test_every_bad_input_class() -> None:
    assert rejected(b"") is Rejection.TRUNCATED
    assert rejected(GOOD[:10]) is Rejection.TRUNCATED  # inside the header
    assert rejected(GOOD[:-1]) is Rejection.TRUNCATED  # inside the payload
    assert rejected(b"GET / HTTP/1.1\r\n\r\n") is Rejection.BAD_MAGIC
    assert rejected(b"\x00" * 40) is Rejection.BAD_MAGIC
    assert rejected(GOOD[:4] + bytes([2]) + GOOD[5:]) is Rejection.BAD_VERSION
    assert rejected(GOOD[:5] + bytes([9]) + GOOD[6:]) is Rejection.BAD_KIND
    assert rejected(GOOD + b"\x00") is Rejection.BAD_LENGTH  # longer than the header says
    flipped = bytearray(GOOD)
    flipped[-3] ^= 0x10
    assert rejected(bytes(flipped)) is Rejection.BAD_CHECKSUM
    # a well-formed datagram whose payload does not parse as its kind (count and size disagree)
    payload = struct.pack("<QH", 0, 2) + struct.pack("<IQ4H", 1, 1, 1, 1, 1, 1)
    header = struct.pack("<4sBBHIII", b"RSoC", 1, 3, 0, 0, len(payload), 0)
    wrong = struct.pack("<4sBBHIII", b"RSoC", 1, 3, 0, 0, len(payload), zlib.crc32(header + payload)) + payload
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
    data = (b"RSoC\x01" if prefix == 1 else GOOD[:20] if prefix == 2 else b"") + data
    result = decode(data)
    assert isinstance(result, Datagram | Rejected)
    if isinstance(result, Datagram):
        assert decode(encode(result.body, result.seq)) == result
