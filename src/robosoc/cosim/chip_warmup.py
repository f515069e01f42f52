"""The chip simulator's first run: numba compiles its kernels once, and says so while it does.

numba compiles the chip's kernels (:mod:`robosoc.kernels`) the first time they run and keeps them
in its on-disk cache (under ``$ROBOSOC_CACHE/numba/<digest of the kernel sources>``).  On a fresh
install that takes about half a minute of CPU, during which a flight would sit silently at
0 %.  A flight therefore first checks the cache (:func:`kernels_cached`) and, when it is empty,
tells the user and compiles by running a throwaway chip (:func:`compile_kernels`), so that the
flight's progress bar and real-time factor measure flying only.  The firmware build (the zig
compiler, a separate process) runs meanwhile in a thread (:func:`prepare_chip`): on a fresh install
it is cold too.

numba compiles one function at a time, in one thread, but a callee (``cache=True``) that another
process has compiled meanwhile is loaded from the cache when the caller's compilation reaches it.
:func:`compile_kernels` therefore splits the main loop's callees in two groups: a child process
compiles the interpreter and the dispatch loop that calls it (:data:`CHILD_KERNELS`, the largest)
while this one compiles the others (:data:`PARENT_KERNELS`), each for the exact argument types the
main loop calls them with; then this process compiles the main loop, which finds both groups in the
cache.
"""

from __future__ import annotations

import os
import pickle
import subprocess
import sys
import tempfile
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import IO, TYPE_CHECKING, Any, TypeVar

from robosoc.config.chip import ChipConfig

if TYPE_CHECKING:
    from robosoc.chip.mpsoc import MPSoC

T = TypeVar("T")

COMPILING = "compiling the chip simulator with numba (first run only, cached afterwards; about half a minute) ..."

#: ``jal x0, 0``: a core spinning on one instruction, enough to make numba compile everything.
SPIN = (0x0000006F).to_bytes(4, "little")


def numba_cache_dir() -> Path:
    """The folder numba keeps robosoc's compiled kernels in (set by :mod:`robosoc.kernels`)."""
    import numba

    import robosoc.kernels  # noqa: F401  (sets numba's cache folder)

    return Path(numba.config.CACHE_DIR)  # type: ignore[attr-defined]  # numba.config: made at run time


def kernels_cached() -> bool:
    """Whether numba's cache holds the compiled chip kernels (the MPSoC's main loop, which calls the rest)."""
    from robosoc.kernels import compiled_or_cached
    from robosoc.kernels.chip import run_chip

    return compiled_or_cached(run_chip)


#: Callees of the main loop a child process compiles (module, function): the interpreter and the
#: dispatch loop, which calls it; 13 and 2.4 s of CPU, about 40 % of the whole compilation
#: (2026-11-28: the interpreter took 31 s before numba stopped copying its IR into a wrapper).
CHILD_KERNELS = (("core", "run_cores"), ("jit_dispatch", "run_translated"))
#: Callees of the main loop (and the functions a flight calls around it) this process compiles
#: meanwhile, largest first (about 12 s of CPU): the main loop itself then compiles alone, about 6 s.
PARENT_KERNELS = (
    ("chip", "_noc_advance"),
    ("chip", "ni_access"),
    ("dev_irq", "irq_event"),
    ("soc_bus", "mmio_store"),
    ("soc_bus", "mmio_load"),
    ("chip", "bad_pcs"),
    ("chip", "_take_deliveries"),
    ("chip", "_wake_if_due"),
    ("stop_queue", "pop"),
    ("core", "decode_word"),
    ("chip", "account_all"),
    ("chip", "_noc_next"),
    ("chip", "_keep_output"),
    ("chip", "_stop_address"),
    ("stop_queue", "push"),
    ("dev_irq", "trap"),
    # the dispatch loop's own callees, ready in the cache before the child reaches them
    ("jit_dispatch", "forget_if_changed"),
)


def throwaway_chip(chip: ChipConfig) -> MPSoC:
    """An MPSoC of ``chip`` whose first core spins (building it compiles nothing)."""
    from robosoc.chip.core_state import SRAM_BASE
    from robosoc.chip.mpsoc import MPSoC
    from robosoc.program.elf import Program, Segment

    mpsoc = MPSoC(chip)
    spin = Program(Path("<spin>"), SRAM_BASE, [(SRAM_BASE, SPIN)], segment_info=[Segment(SRAM_BASE, SPIN, True, False)])
    mpsoc.load(mpsoc.core_tiles()[0], spin)
    return mpsoc


def kernel_signatures(mpsoc: MPSoC) -> dict[tuple[str, str], tuple[Any, ...]]:
    """The numba argument types with which the main loop calls each of :data:`CHILD_KERNELS` and
    :data:`PARENT_KERNELS` on ``mpsoc``'s arrays (any other type would compile a second version)."""
    import numpy as np
    from numba import typeof, types

    from robosoc.kernels.jit_dispatch import empty_tables

    core, noc, book = mpsoc.cores.arrays(), mpsoc.noc, mpsoc.book()
    i64 = types.int64
    st, cst, row = typeof(core.st), typeof(book.cst), typeof(core.st[0])
    tiles = typeof(np.zeros(1, dtype=np.int64))  # a slice of a row of the chip's work array
    jit = typeof(empty_tables())  # a tile's translation tables
    return {
        ("core", "run_cores"): (typeof(core), tiles, i64),
        ("jit_dispatch", "run_translated"): (typeof(core), tiles, i64, jit, i64, i64),
        ("chip", "ni_access"): (i64, typeof(core), typeof(book), typeof(noc)),
        ("chip", "_take_deliveries"): (st, typeof(book), typeof(noc)),
        ("chip", "_wake_if_due"): (i64, st, cst, i64),
        ("chip", "_noc_next"): (typeof(noc), cst),
        ("chip", "_noc_advance"): (typeof(noc), cst, i64),
        ("dev_irq", "irq_event"): (row, typeof(core.ctr[0]), i64, i64),
        ("soc_bus", "mmio_store"): (row, typeof(core.out[0]), i64, i64, i64),
        ("soc_bus", "mmio_load"): (row, i64, i64),
        ("core", "decode_word"): (typeof(core.m32[0, 0]), typeof(core.dec[0]), types.uint64),
        ("chip", "_keep_output"): (i64, st, cst, typeof(core.out), typeof(book.xout)),
        ("dev_irq", "trap"): (row, i64, i64),
        ("chip", "bad_pcs"): (st, cst),
        ("chip", "account_all"): (typeof(core), typeof(book)),
        ("chip", "_stop_address"): (i64, typeof(core)),
        ("stop_queue", "push"): (tiles, tiles, tiles, tiles, i64, i64),
        ("stop_queue", "pop"): (tiles, tiles, tiles, tiles),
        ("jit_dispatch", "forget_if_changed"): (jit, typeof(core.m32[0]), typeof(core.dec[0])),
    }


def compile_callees(chip: ChipConfig, which: tuple[tuple[str, str], ...]) -> None:
    """Compile (and cache) the kernels ``which`` for the types the main loop calls them with."""
    import importlib

    signatures = kernel_signatures(throwaway_chip(chip))
    for module, name in which:
        getattr(importlib.import_module(f"robosoc.kernels.{module}"), name).compile(signatures[module, name])


def _compile_in_child() -> None:
    """The child process: compile :data:`CHILD_KERNELS` for the pickled ChipConfig on stdin."""
    compile_callees(pickle.load(sys.stdin.buffer), CHILD_KERNELS)


def _start_child(chip: ChipConfig, err: IO[bytes]) -> subprocess.Popen[bytes]:
    """A fresh interpreter (not multiprocessing, which would re-run the caller's script) on the
    same robosoc and numba cache, compiling :data:`CHILD_KERNELS`; its error output goes to ``err``."""
    import robosoc

    env = dict(os.environ, NUMBA_CACHE_DIR=str(numba_cache_dir()))
    env["PYTHONPATH"] = os.pathsep.join([str(Path(robosoc.__file__).parent.parent), env.get("PYTHONPATH", "")])
    code = f"from {__name__} import _compile_in_child; _compile_in_child()"
    child = subprocess.Popen([sys.executable, "-c", code], stdin=subprocess.PIPE, stderr=err, env=env)
    assert child.stdin is not None
    child.stdin.write(pickle.dumps(chip))
    child.stdin.close()
    return child


def compile_kernels(chip: ChipConfig) -> None:
    """Run a throwaway ``chip`` whose first core spins, so that numba compiles (and caches) the chip's
    kernels: the main loop with the cores, devices and NoC it calls, the accounting and the
    period's close.  Half of
    the main loop's callees are compiled in a child process meanwhile.

    Raises:
        RuntimeError: the child process failed (its error output is in the message).
    """
    with tempfile.TemporaryFile() as err:
        child = _start_child(chip, err)
        try:
            compile_callees(chip, PARENT_KERNELS)
        finally:
            child.wait()
        if child.returncode != 0:
            err.seek(0)
            raise RuntimeError(
                f"compiling the chip kernels in a child process failed:\n{err.read().decode(errors='replace')}"
            )
    import numpy as np

    from robosoc.chip.mpsoc import account_counter_map
    from robosoc.kernels.noc import ROUTER_COUNTS

    mpsoc = throwaway_chip(chip)
    mpsoc.step(10_000)
    mpsoc.finish_accounting()
    # and what a flight's period close calls: the accounting rows' counters, the routers' activity
    rows = np.zeros(1, dtype=np.int64)
    previous = np.zeros((1, mpsoc.acc.shape[-1]), dtype=np.int64)
    counters = np.zeros((1, len(account_counter_map()[0])), dtype=np.int64)
    mpsoc.close_accounts(rows, rows, previous, counters, np.zeros(len(ROUTER_COUNTS), dtype=np.int64))
    mpsoc.noc_counters()


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
