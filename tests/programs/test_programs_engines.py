"""Every test program gives the same run with every engine (docs/translation.md): the translated
code must leave the core exactly as the interpreter does -- cycles, every counter, the state,
registers and memory, the output and the exit code."""

import warnings

import numpy as np
import pytest
from program_list import PROGRAMS

from robosoc.chip.single import SingleCoreSoC
from robosoc.kernels.jit_dispatch import CTX_STEPS
from robosoc.program.elf import load_elf
from robosoc.toolchain import build_elf

MAX_CYCLES = 2_000_000_000


def run(elf, mul: bool, engine: str) -> tuple[SingleCoreSoC, object]:
    soc = SingleCoreSoC(mul=mul, engine=engine)
    soc.load(load_elf(elf, soc.regions()))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return soc, soc.run(max_cycles=MAX_CYCLES)


@pytest.mark.parametrize("engine", ["jit", "auto"])
@pytest.mark.parametrize("mul", [False, True], ids=["no-mul", "mul"])
@pytest.mark.parametrize("name", sorted(PROGRAMS))
def test_engine_runs_the_program_as_the_interpreter_does(name: str, mul: bool, engine: str) -> None:
    sources, defines, exit_code = PROGRAMS[name]
    elf = build_elf(sources, mul=mul, defines=defines)
    ref_soc, ref = run(elf, mul, "interp")
    soc, got = run(elf, mul, engine)
    assert got.exit_code == ref.exit_code == exit_code
    assert got.output == ref.output
    assert got.counters == ref.counters
    assert got.errata == ref.errata
    for name_ in ("st", "ctr", "opc", "regs", "m8"):
        assert np.array_equal(getattr(soc.state, name_), getattr(ref_soc.state, name_)), name_
    if engine == "jit":  # translated code did the work, not the interpreter behind it (device accesses are its)
        steps = int(soc.translator.tables().ctx[CTX_STEPS]) - got.counters["device_accesses"]
        assert steps < got.instructions // 100, f"{steps} of {got.instructions} instructions interpreted"
