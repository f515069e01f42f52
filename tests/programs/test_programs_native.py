"""The test programs compiled for the host print results that Python recomputes independently."""

import re
import zlib

import numpy as np
import pytest
from line_checks import APPROXIMATE, EXACT, check_line, s32
from program_list import PROGRAMS

from robosoc.toolchain import compile_native, run_native


def native_output(name: str) -> tuple[int, bytes]:
    sources, defines, _ = PROGRAMS[name]
    return run_native(compile_native(sources, defines=defines))


@pytest.mark.parametrize("name", ["int32_arith", "int64_arith", "softfloat", "fixed_q16"])
def test_every_reported_operation_matches_python(name: str) -> None:
    code, out = native_output(name)
    assert code == 0
    lines = out.decode().splitlines()
    checked = [line for line in lines if line.split()[0] in EXACT or line.split()[0] in APPROXIMATE]
    assert len(checked) > 100
    errors = [e for e in map(check_line, lines) if e]
    assert errors == []


def lcg(state: int) -> int:
    return (state * 1103515245 + 12345) & 0xFFFFFFFF


def test_crc_sort_string_matches_python() -> None:
    code, out = native_output("crc_sort_string")
    assert code == 7
    lines = out.decode().splitlines()
    assert lines[0] == f"crc32 00000009 00000000 {zlib.crc32(b'123456789'):08x}"
    state, buf = 12345, bytearray()
    for _ in range(1024):
        state = lcg(state)
        buf.append((state >> 16) & 0xFF)
    assert lines[1] == f"crc32lcg 00000400 00003039 {zlib.crc32(bytes(buf)):08x}"
    numbers = []
    for _ in range(200):
        state = lcg(state)
        numbers.append(s32(state) >> 7)
    sorted_lines = [line for line in lines if line.startswith("sorted ")]
    assert [s32(int(line.split()[3], 16)) for line in sorted_lines] == sorted(numbers)
    assert "reversed " + "robosoc on hf-riscv"[::-1] in lines
    assert "strcmp 1 1 1" in lines
    assert f"printf -42|4000000000|beef|00001234|   -7|Q|str|-1234567890123456789|{0x0123456789ABCDEF:x}|%" in lines
    assert lines[-1] == f"{-(2**31)} {2**32 - 1} {-(2**63)} {2**64 - 1}"


def test_matrix_inverse_matches_numpy() -> None:
    code, out = native_output("matrix7")
    assert code == 0
    rows: dict[str, list[list[int]]] = {}
    for line in out.decode().splitlines():
        m = re.match(r"(\w+)\[(\d)\] (.*)", line)
        if m:
            rows.setdefault(m.group(1), []).append([int(x, 16) for x in m.group(3).split()])
    a = np.array([[(4 * (4 + i) if i == j else (i * 7 + j * 3) % 5 - 2) / 4 for j in range(7)] for i in range(7)])
    inverse = np.linalg.inv(a)
    inv_f = np.array(rows["inv_f"], dtype=np.uint32).view(np.float32).astype(float)
    inv_q = np.array(rows["inv_q"], dtype=np.uint32).view(np.int32) / 65536
    assert np.allclose(inv_f, inverse, atol=1e-6)
    assert np.allclose(inv_q, inverse, atol=64 / 65536)
    assert out.decode().splitlines()[-1] == "iterations 2 failures 0"
