"""robosoc's CDR encoder on its own: the bytes of small messages written out by hand from the CDR
rules (header 00 01 00 00, alignment counted after it), defaults, constants, and refusals."""

from __future__ import annotations

import struct

import pytest

from robosoc.outputs.ros2_cdr import CdrEncoder, parse_fields

HEADER = b"\x00\x01\x00\x00"


def test_alignment_strings_sequences_and_fixed_arrays() -> None:
    encoder = CdrEncoder(
        {
            "p/Inner": "uint8 a\nfloat64 b\n",
            "p/Outer": "# a comment\nuint8 FLAG=3\nbool on\nstring name\nInner[] items\nint16[2] pair\n",
        }
    )
    data = encoder.encoder("p/Outer")({"on": True, "name": "ab", "items": [{"a": 7, "b": 1.5}], "pair": [-1, 2]})
    expected = (
        HEADER
        + b"\x01"  # on
        + b"\x00" * 3 + struct.pack("<I", 3) + b"ab\x00"  # name: aligned to 4, length with its NUL
        + b"\x00" + struct.pack("<I", 1)  # items: count, aligned to 4 (offset 8 + 1 pad)
        + b"\x07" + b"\x00" * 7 + struct.pack("<d", 1.5)  # Inner: a, then b aligned to 8
        + struct.pack("<hh", -1, 2)  # pair: no count
    )  # fmt: skip
    assert data == expected


def test_missing_fields_take_the_definitions_default_or_zero() -> None:
    encoder = CdrEncoder({"geometry_msgs/Quaternion": "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1\n"})
    assert encoder.encoder("geometry_msgs/Quaternion")({"x": 0.5}) == HEADER + struct.pack("<4d", 0.5, 0, 0, 1)


def test_what_the_encoder_does_not_take_is_refused() -> None:
    with pytest.raises(ValueError, match="bounded sequence 'xs'"):
        parse_fields("p/A", "int32[<=3] xs\n")
    with pytest.raises(ValueError, match="bounded string 's'"):
        parse_fields("p/A", "string<=5 s\n")
    with pytest.raises(KeyError, match="unknown type p/Missing"):
        CdrEncoder({"p/A": "Missing m\n"})
    encoder = CdrEncoder({"p/A": "uint8[4] pwm\n"})
    with pytest.raises(KeyError, match="p/B"):
        encoder.encoder("p/B")
    with pytest.raises(ValueError, match=r"p/A\.pwm has 4 elements, got 3"):
        encoder.encoder("p/A")({"pwm": [1, 2, 3]})
