"""The Q16.16 and single-precision libraries against float64, within the documented bounds.

lib_check.c calls every function on pseudo-random inputs (spread over all magnitudes, with the
saturating cases); lib_reference.py recomputes each result in float64 from the printed operands.
Thousands of inputs per function run host-native (the same C, integer arithmetic and IEEE float
operations give the same bits); a subset runs on the simulated core with and without the
multiplier, where the results must also be the host's, bit for bit.
"""

import pytest
from lib_reference import BOUNDS, lib_check_sources, max_errors, parse_lines

from robosoc.firmware import MATH_DIR
from robosoc.toolchain import build_elf, compile_native, run_native

single = pytest.importorskip("robosoc.chip.single")

HOST_COUNT = 5000
CORE_COUNT = 120
ALL_OPS = {*BOUNDS, "mul64"}


def _host_lines(count: int, seed: int = 12345) -> str:
    exe = compile_native(
        lib_check_sources(), include_dirs=[MATH_DIR], defines={"CHECK_COUNT": count, "CHECK_SEED": seed}
    )
    code, out = run_native(exe, timeout=300)
    assert code == 0
    return out.decode()


def _assert_within_bounds(text: str, count: int) -> None:
    worst = max_errors(parse_lines(text))
    assert set(worst) == ALL_OPS
    for op, (error, calls) in worst.items():
        assert calls >= count, op  # the Q16.16 functions also run every pair of edge operands
        bound = BOUNDS[op].bound if op in BOUNDS else 0.0
        assert error <= bound, (
            f"{op}: error {error:.3g} above the bound {bound} {BOUNDS[op].unit if op in BOUNDS else ''}"
        )


@pytest.mark.parametrize("seed", [12345, 99991])
def test_library_within_bounds_host(seed: int) -> None:
    _assert_within_bounds(_host_lines(HOST_COUNT, seed), HOST_COUNT)


@pytest.mark.parametrize("mul", [True, False], ids=["mul", "no-mul"])
def test_library_within_bounds_on_core_and_equal_to_host(mul: bool) -> None:
    elf = build_elf(lib_check_sources(), mul=mul, include_dirs=[MATH_DIR], defines={"CHECK_COUNT": CORE_COUNT})
    result = single.run_elf(elf, mul=mul, max_cycles=2_000_000_000)
    assert result.exit_code == 0
    core = result.output.decode()
    _assert_within_bounds(core, CORE_COUNT)

    def results(text: str) -> list[list[str]]:
        return [line.split()[:4] for line in text.splitlines()]

    assert results(core) == results(_host_lines(CORE_COUNT))
