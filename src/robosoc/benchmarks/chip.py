"""``robosoc bench chip``: simulated core-cycles per host second of the whole MPSoC.

Three measurements, each after a warm-up (JIT or cache load):

* busy: every core of a 2x2, a 4x4 and an 8x8 mesh runs the EKF-like matrix workload (no
  traffic); M core-cycles per host second (simulated cycles times cores);
* sleeping: every core of a 2x2 and a 16x16 mesh wakes on a 1 ms timer tick, works briefly and
  sleeps; reported as a real-time factor (simulated seconds per host second) at the configured
  clock (4 ns: 250 MHz);
* the NoC alone under uniform random traffic on 8x8 (see :mod:`robosoc.benchmarks.noc`).

The last line is ``chip: <median> Mcycles/s`` for the busy 4x4 mesh.  With ``engine`` jit or auto
the cores run translated code; the warm-up run translates it, so the timed runs measure running.
"""

from __future__ import annotations

import statistics
import time
from typing import TYPE_CHECKING

from rich.console import Console
from rich.table import Table

if TYPE_CHECKING:
    from robosoc.chip.engines import Engine


def _build(source: str, mul: bool, defines: dict[str, str | int | None]):
    from robosoc.firmware import FIRMWARE_DIR
    from robosoc.program.elf import load_elf
    from robosoc.toolchain import build_elf

    return load_elf(build_elf([FIRMWARE_DIR / "bench" / source], mul=mul, defines=defines))


def _busy(width: int, height: int, cycles: int, runs: int, engine: Engine) -> list[float]:
    from robosoc.chip.mpsoc import MPSoC
    from robosoc.config.chip import ChipConfig

    program = _build("matrix_bench.c", True, {"BENCH_ITERATIONS": 100000, "BENCH_QUIET": None})
    rates = []
    for k in range(runs + 1):
        chip = MPSoC(ChipConfig(width=width, height=height), engine=engine)
        chip.load_all(program)
        start = time.perf_counter()
        chip.step(cycles)
        seconds = time.perf_counter() - start
        if k:  # the first run is the warm-up
            rates.append(len(chip.core_tiles()) * cycles / seconds / 1e6)
    return rates


def _sleeping(width: int, height: int, ticks: int, runs: int, engine: Engine) -> tuple[list[float], float]:
    from robosoc.chip.mpsoc import MPSoC
    from robosoc.config.chip import ChipConfig

    program = _build("sleepy_tick.c", True, {"TICKS": ticks})
    factors = []
    awake = 0.0
    for k in range(runs + 1):
        chip = MPSoC(ChipConfig(width=width, height=height), engine=engine)
        chip.load_all(program)
        result = chip.run(max_cycles=(ticks + 2) * 250_000)
        simulated_s = result.cycles * chip.clock_ns * 1e-9
        if k:
            factors.append(simulated_s / result.host_seconds)
            c = chip.counters(chip.core_tiles()[0])
            awake = 1.0 - c["sleep_cycle"] / c["cycles"]
    return factors, awake


def run_chip_benchmark(
    runs: int = 5,
    cycles: int = 2_000_000,
    ticks: int = 40,
    noc: bool = True,
    console: Console | None = None,
    engine: str | Engine = "interp",
) -> float:
    """Print the figures; returns the median M core-cycles/s of the busy 4x4 mesh.

    Raises:
        ValueError: ``runs``, ``cycles`` or ``ticks`` below 1 (or ``cycles`` beyond 2**62), or an
            unknown ``engine``.
    """
    from robosoc.chip.engines import resolve_engine
    from robosoc.config.ranges import MAX_CYCLES, check_int

    chosen = resolve_engine(engine)  # an unknown name fails before anything runs

    check_int("runs", runs, 1)
    check_int("cycles", cycles, 1, MAX_CYCLES, "cycles")
    check_int("ticks", ticks, 1)
    console = console or Console()
    table = Table(title=f"robosoc bench chip (engine {chosen.name})")
    table.add_column("case")
    table.add_column("median", justify="right")
    table.add_column("min..max", justify="right")
    rows = {}
    for w, h in ((2, 2), (4, 4), (8, 8)):
        rates = _busy(w, h, cycles, runs, chosen)
        rows[(w, h)] = rates
        table.add_row(f"{w}x{h} all cores busy (M core-cycles/s)", f"{statistics.median(rates):.1f}",
                      f"{min(rates):.1f}..{max(rates):.1f}")  # fmt: skip
    for w, h in ((2, 2), (16, 16)):
        factors, awake = _sleeping(w, h, ticks, runs, chosen)
        table.add_row(
            f"{w}x{h} sleeping, 1 ms tick, {awake:.1%} awake (x real time at 250 MHz)",
            f"{statistics.median(factors):.2f}",
            f"{min(factors):.2f}..{max(factors):.2f}",
        )
    console.print(table)
    if noc:
        from robosoc.benchmarks.noc import run_noc_benchmark

        run_noc_benchmark(width=8, height=8, cycles=5_000, console=console, arbiters=("hermes",), gating=(False,))
    median = statistics.median(rows[(4, 4)])
    print(f"chip: {median:.0f} Mcycles/s")
    return median
