"""``robosoc bench core``: simulated MIPS of one core on an EKF-like workload.

The workload is ``firmware/bench/matrix_bench.c``: 7x7 Gauss-Jordan inverse and product, in
soft-float and in Q16.16, as the seed's EKF does.  After a warm-up run (JIT compile or load from
the numba cache) the program runs ``runs`` times on a fresh core each; each run's MIPS is
instructions / host seconds of the simulation loop with every counter on.
"""

from __future__ import annotations

import statistics
import time

from rich.console import Console
from rich.progress import Progress
from rich.table import Table

ITERATIONS = 300  # about 34 M instructions with the multiplier


def run_core_benchmark(
    runs: int = 7, mul: bool = True, iterations: int = ITERATIONS, console: Console | None = None
) -> float:
    """Print per-run figures, median and spread; returns the median MIPS.

    Raises:
        ValueError: ``runs`` or ``iterations`` below 1.
    """
    from robosoc.chip.elf import load_elf
    from robosoc.chip.single import SingleCoreSoC
    from robosoc.config.ranges import check_int
    from robosoc.firmware import MATRIX_BENCH_SOURCE
    from robosoc.toolchain import build_elf

    check_int("runs", runs, 1)
    check_int("iterations", iterations, 1)
    console = console or Console(stderr=False)
    elf = build_elf([MATRIX_BENCH_SOURCE], mul=mul, defines={"BENCH_ITERATIONS": iterations, "BENCH_QUIET": None})
    program = load_elf(elf)

    def one_run() -> tuple[int, int, float]:
        soc = SingleCoreSoC(mul=mul)
        soc.load(program)
        result = soc.run(max_cycles=10**11)
        if result.exit_code != 0:
            raise RuntimeError(f"benchmark workload failed its self-check (exit code {result.exit_code})")
        return result.instructions, result.cycles, result.host_seconds

    start = time.perf_counter()
    one_run()
    warm = time.perf_counter() - start

    rows = []
    with Progress(console=console, transient=True) as progress:
        task = progress.add_task("timed runs", total=runs)
        for _ in range(runs):
            rows.append(one_run())
            progress.advance(task)

    mips = [i / s / 1e6 for i, _, s in rows]
    mcps = [c / s / 1e6 for _, c, s in rows]
    instructions, cycles, _ = rows[0]
    table = Table(title=f"robosoc bench core ({'with' if mul else 'without'} multiplier)")
    table.add_column("run", justify="right")
    table.add_column("host s", justify="right")
    table.add_column("MIPS", justify="right")
    table.add_column("M cycles/s", justify="right")
    for k, ((_, _, s), m, c) in enumerate(zip(rows, mips, mcps, strict=True)):
        table.add_row(str(k + 1), f"{s:.3f}", f"{m:.1f}", f"{c:.1f}")
    console.print(table)
    med = statistics.median(mips)
    quartiles = statistics.quantiles(mips, n=4) if len(mips) >= 2 else [med, med, med]
    console.print(
        f"workload: matrix_bench.c x{iterations}, {instructions:,} instructions, {cycles:,} cycles "
        f"(CPI {cycles / instructions:.2f}); first run incl. JIT/cache load {warm:.2f} s"
    )
    console.print(
        f"MIPS median {med:.1f}, min {min(mips):.1f}, max {max(mips):.1f}, "
        f"IQR {quartiles[0]:.1f}..{quartiles[2]:.1f}; simulated {statistics.median(mcps):.1f} M cycles/s"
    )
    print(f"core: {med:.0f} MIPS")
    return med
