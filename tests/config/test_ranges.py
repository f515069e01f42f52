"""The range rules every user-given number goes through: bounds inclusive, messages exact.

Expected texts are written from the rules in the module docstring (``<name>: <reason>, got
<value>``; bounds as people read them), boundaries on both sides of each limit.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from robosoc.config.ranges import (
    MAX_SEED,
    MAX_SRAM_BYTES,
    MIN_SRAM_BYTES,
    check_float,
    check_int,
    check_seed,
    check_sram_bytes,
    describe,
)


@pytest.mark.parametrize(
    ("value", "text"),
    [
        (4096, "4096"),
        (9_999_999, "9999999"),
        (10**7, "10**7"),
        (10**10, "10**10"),
        (2 * 10**7, "20000000"),
        (10**7 + 1, "10000001"),
        ((1 << 20) - 1, "1048575"),
        (1 << 20, "2**20"),
        ((1 << 21) - 1, "2**21-1"),
        ((1 << 20) + 1, "1048577"),
        (2**30, "2**30"),
        (2**62, "2**62"),
        (2**63 - 1, "2**63-1"),
        (0.001, "0.001"),
        (2.5, "2.5"),
        (1e7, "1e+07"),
        (-3, "-3"),
    ],
)
def test_describe_writes_bounds_as_people_read_them(value, text):
    assert describe(value) == text


def test_check_int_accepts_its_bounds_and_returns_a_plain_int():
    assert check_int("n", 5, 5, 9) == 5
    assert check_int("n", 9, 5, 9) == 9
    got = check_int("n", np.int64(7), 5, 9)
    assert got == 7 and type(got) is int
    assert check_int("n", -(10**30)) == -(10**30)  # no bounds: anything integral


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (("n", 4, 5, 9), "n: must be between 5 and 9, got 4"),
        (("n", 10, 5, 9), "n: must be between 5 and 9, got 10"),
        (("--cycles", 0, 1, 2**62, "cycles"), "--cycles: must be between 1 and 2**62 cycles, got 0"),
        (("n", 4, 5), "n: must be >= 5, got 4"),
        (("n", 4, 5, None, "s"), "n: must be >= 5 s, got 4"),
        (("n", 10, None, 9), "n: must be <= 9, got 10"),
        (("n", 10, None, 9, "tiles"), "n: must be <= 9 tiles, got 10"),
        (("n", 1.5, 0, 9), "n: expected an integer, got 1.5"),
        (("n", 3.0, 0, 9), "n: expected an integer, got 3.0"),
        (("n", True, 0, 9), "n: expected an integer, got True"),
        (("n", "3", 0, 9), "n: expected an integer, got '3'"),
    ],
)
def test_check_int_refusals(args, message):
    with pytest.raises(ValueError) as info:
        check_int(*args)
    assert str(info.value) == message


def test_check_float_accepts_its_bounds_and_returns_a_float():
    assert check_float("x", 0, 0.0, 1.0) == 0.0
    assert check_float("x", 1, 0.0, 1.0) == 1.0
    got = check_float("x", np.float32(0.5), 0.0, 1.0)
    assert got == 0.5 and type(got) is float
    assert check_float("x", 1e-300, 0.0, lo_open=True) == 1e-300
    assert check_float("x", -1e300) == -1e300


@pytest.mark.parametrize(
    ("args", "kwargs", "message"),
    [
        (("x", True), {}, "x: expected a number, got True"),
        (("x", "1.0"), {}, "x: expected a number, got '1.0'"),
        (("x", None), {}, "x: expected a number, got None"),
        (("x", math.nan), {}, "x: must be a finite number, got nan"),
        (("x", math.inf, 0.0, 1.0), {}, "x: must be a finite number, got inf"),
        (("x", -math.inf), {}, "x: must be a finite number, got -inf"),
        (("x", -0.5, 0.0, 1.0), {}, "x: must be in [0, 1], got -0.5"),
        (("x", 1.5, 0.0, 1.0), {"unit": "s"}, "x: must be in [0, 1] s, got 1.5"),
        (("x", 0.0, 0.0, 2.5), {"lo_open": True}, "x: must be in (0, 2.5], got 0"),
        (("x", 0.0, 0.0), {"lo_open": True, "unit": "m"}, "x: must be > 0 m, got 0"),
        (("x", -1.0, 0.0), {}, "x: must be >= 0, got -1"),
        (("x", 7.0, None, 3.0), {"unit": "Hz"}, "x: must be <= 3 Hz, got 7"),
        (("x", 7.0, None, 3.0), {}, "x: must be <= 3, got 7"),
    ],
)
def test_check_float_refusals(args, kwargs, message):
    with pytest.raises(ValueError) as info:
        check_float(*args, **kwargs)
    assert str(info.value) == message


def test_seeds_span_zero_to_the_largest_signed_64_bit_integer():
    assert check_seed("seed", 0) == 0
    assert check_seed("seed", MAX_SEED) == 2**63 - 1
    for bad in (-1, 2**63):
        with pytest.raises(ValueError) as info:
            check_seed("--seed", bad)
        assert str(info.value) == f"--seed: must be between 0 and 2**63-1, got {bad}"


def test_sram_sizes_are_whole_words_from_4_kib_to_1_gib():
    assert (MIN_SRAM_BYTES, MAX_SRAM_BYTES) == (4096, 1 << 30)
    assert check_sram_bytes("sram", 4096) == 4096
    assert check_sram_bytes("sram", 1 << 30) == 1 << 30
    assert check_sram_bytes("sram", 4100) == 4100
    cases = {
        4092: "sram: must be between 4096 and 2**30 bytes, got 4092",
        (1 << 30) + 4: "sram: must be between 4096 and 2**30 bytes, got 1073741828",
        4098: "sram: must be a multiple of 4 bytes, got 4098",
        4097: "sram: must be a multiple of 4 bytes, got 4097",
    }
    for value, message in cases.items():
        with pytest.raises(ValueError) as info:
            check_sram_bytes("sram", value)
        assert str(info.value) == message
