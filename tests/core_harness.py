"""Running hand-assembled words on a fresh single-core SoC (tests only)."""

from __future__ import annotations

import rv32_asm as A
from robosoc.chip.core_state import SRAM_BASE
from robosoc.chip.single import RunResult, SingleCoreSoC

EXIT_SEQUENCE_CYCLES = 1 + 1 + 3  # lui + addi + sw


def exit_with(reg: int) -> list[int]:
    """Store ``reg`` to the exit trap (t6 is clobbered)."""
    return [*A.li(31, 0xE0000000), A.store("sw", reg, 31, 0)]


def make_soc(
    words: list[int], mul: bool = True, sram_size: int = 64 * 1024, errata: str = "spec", engine: str = "interp"
) -> SingleCoreSoC:
    """A fresh SoC with ``words`` at the start of SRAM and the pc there.

    ``errata``: "spec" (RISC-V results, the RTL's errata only reported) or "rtl" (reproduce them);
    ``engine``: "interp", "jit" or "auto".  The whole SRAM counts as code (stores anywhere may
    modify instructions).
    """
    soc = SingleCoreSoC(mul=mul, sram_size=sram_size, errata=errata, engine=engine)
    soc.state.write(SRAM_BASE, A.words_to_bytes(words))
    soc.state.pc = SRAM_BASE
    return soc


def run_words(
    words: list[int], mul: bool = True, max_cycles: int | None = 1_000_000, errata: str = "spec", engine: str = "interp"
) -> tuple[SingleCoreSoC, RunResult]:
    soc = make_soc(words, mul, errata=errata, engine=engine)
    result = soc.run(max_cycles=max_cycles)
    return soc, result
