"""Matrices and quaternions over real_t in both builds against numpy and control/quaternion.py.

real_check.c runs every routine on pseudo-random inputs; real_reference.py recomputes each result
in float64 and states the bounds (fixed: LSB; float: the float32 rounding bound of a sum of
products).  Many inputs run host-native; a few per build run on the core, where every result must
be the host's, bit for bit.
"""

import pytest
from real_reference import BOUNDS, INCLUDE_DIRS, errors, real_check_sources

from robosoc.firmware import ARITHS, arith_defines
from robosoc.toolchain import build_elf, compile_native, run_native

single = pytest.importorskip("robosoc.chip.single")

HOST_COUNT = 400
CORE_COUNT = 4


def _host_output(arith: str, count: int) -> str:
    exe = compile_native(
        real_check_sources(), include_dirs=INCLUDE_DIRS, defines={"CHECK_COUNT": count, **arith_defines(arith)}
    )
    code, out = run_native(exe, timeout=300)
    assert code == 0
    return out.decode()


def _assert_within_bounds(text: str, arith: str) -> None:
    worst = errors(text, arith)
    assert set(worst) == set(BOUNDS[arith])
    for op, error in worst.items():
        assert error <= BOUNDS[arith][op], f"{arith} {op}: error {error:.3g} above {BOUNDS[arith][op]}"


@pytest.mark.parametrize("arith", ARITHS)
def test_routines_within_bounds_host(arith: str) -> None:
    _assert_within_bounds(_host_output(arith, HOST_COUNT), arith)


@pytest.mark.parametrize("mul", [True, False], ids=["mul", "no-mul"])
@pytest.mark.parametrize("arith", ARITHS)
def test_routines_on_core_equal_host(arith: str, mul: bool) -> None:
    elf = build_elf(
        real_check_sources(),
        mul=mul,
        include_dirs=INCLUDE_DIRS,
        defines={"CHECK_COUNT": CORE_COUNT, **arith_defines(arith)},
    )
    result = single.run_elf(elf, mul=mul, max_cycles=2_000_000_000)
    assert result.exit_code == 0
    core = result.output.decode()
    _assert_within_bounds(core, arith)

    def results(text: str) -> list[str]:
        return [line.rsplit("|", 1)[0] for line in text.splitlines()]

    assert results(core) == results(_host_output(arith, CORE_COUNT))
