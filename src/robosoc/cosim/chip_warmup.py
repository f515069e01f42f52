"""The chip simulator's first run: numba compiles its kernels once, and says so while it does.

numba compiles the chip's kernels (:mod:`robosoc.kernels`) the first time they run and keeps them
in its on-disk cache (under ``$ROBOSOC_CACHE/numba/<digest of the kernel sources>``).  On a fresh
install that takes on the order of a minute of CPU, during which a flight would sit silently at
0 %.  A flight therefore first checks the cache (:func:`kernels_cached`) and, when it is empty,
tells the user and compiles by running a throwaway chip (:func:`compile_kernels`), so that the
flight's progress bar and real-time factor measure flying only.  The firmware build (the zig
compiler, a separate process) runs meanwhile in a thread (:func:`prepare_chip`): on a fresh install
it is cold too, and the two together use both cores of a 2-core machine.
"""

from __future__ import annotations

from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import TypeVar

from robosoc.config.chip import ChipConfig

T = TypeVar("T")

#: The kernel whose compiled form marks the cache as filled (the MPSoC's main loop).
MARKER = "chip.run_chip-*.nbi"

COMPILING = "compiling the chip simulator with numba (first run only, cached afterwards; about a minute) ..."

#: ``jal x0, 0``: a core spinning on one instruction, enough to make numba compile everything.
SPIN = (0x0000006F).to_bytes(4, "little")


def numba_cache_dir() -> Path:
    """The folder numba keeps robosoc's compiled kernels in (set by :mod:`robosoc.kernels`)."""
    import numba

    import robosoc.kernels  # noqa: F401  (sets numba's cache folder)

    return Path(numba.config.CACHE_DIR)


def kernels_cached() -> bool:
    """Whether numba's cache holds the compiled chip kernels."""
    return any(numba_cache_dir().rglob(MARKER))


def compile_kernels(chip: ChipConfig) -> None:
    """Run a throwaway ``chip`` whose first core spins, so that numba compiles (and caches) the chip's
    kernels: the main loop with the cores, devices and NoC it calls, and the accounting."""
    from robosoc.chip.core_state import SRAM_BASE
    from robosoc.chip.elf import Program, Segment
    from robosoc.chip.mpsoc import MPSoC

    mpsoc = MPSoC(chip)
    spin = Program(Path("<spin>"), SRAM_BASE, [(SRAM_BASE, SPIN)], segment_info=[Segment(SRAM_BASE, SPIN, True, False)])
    mpsoc.load(mpsoc.core_tiles()[0], spin)
    mpsoc.step(10_000)
    mpsoc.finish_accounting()


def prepare_chip(chip: ChipConfig, build: Callable[[], T], on_status: Callable[[str], None]) -> T:
    """``build()`` (the firmware), and the chip kernels compiled if the cache lacks them: then
    ``on_status`` is told first, and the build runs in a thread meanwhile.  Returns what ``build`` did."""
    if kernels_cached():
        return build()
    on_status(COMPILING)
    with ThreadPoolExecutor(max_workers=1) as pool:
        built = pool.submit(build)
        compile_kernels(chip)
        return built.result()
