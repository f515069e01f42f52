"""``robosoc bench core``: simulated MIPS of one core on an EKF-like workload.

The workload is ``firmware/bench/matrix_bench.c``: 7x7 Gauss-Jordan inverse and product, in
soft-float and in Q16.16, as the seed's EKF does.  After untimed warm-up runs (JIT compile or load
from the numba cache; with a translating engine also the translation of the program's code: runs
until one translated nothing new, at most WARMUP_MAX_SECONDS; ``auto`` warms up and compiles in the
background over several runs of this short program) the program runs ``runs`` times on a fresh
core each; each run's MIPS is instructions / host seconds
of the simulation loop with every counter on.  With ``engine`` jit or auto and ``compare``, the
interpreter runs in the same loop, alternating with the engine, and the ratio is printed; the
results of both engines must be identical (cycles, counters, output), else the benchmark fails.
"""

from __future__ import annotations

import statistics
import time
from typing import TYPE_CHECKING

from rich.console import Console
from rich.progress import Progress
from rich.table import Table

if TYPE_CHECKING:
    from robosoc.chip.engines import Engine
    from robosoc.chip.single import SingleCoreSoC

ITERATIONS = 300  # about 34 M instructions with the multiplier
#: untimed runs of a translating engine stop after this long even if it still translates
WARMUP_MAX_SECONDS = 30.0


def run_core_benchmark(
    runs: int = 7,
    mul: bool = True,
    iterations: int = ITERATIONS,
    engine: str | Engine = "interp",
    compare: bool = True,
    console: Console | None = None,
) -> float:
    """Print per-run figures, median and spread; returns the median MIPS of ``engine``.

    Raises:
        ValueError: ``runs`` or ``iterations`` below 1, or an unknown engine.
        RuntimeError: the workload failed its self-check, or two engines disagreed.
    """
    from robosoc.chip.engines import INTERP, resolve_engine
    from robosoc.chip.single import SingleCoreSoC
    from robosoc.config.ranges import check_int
    from robosoc.firmware import MATRIX_BENCH_SOURCE
    from robosoc.program.elf import load_elf
    from robosoc.toolchain import build_elf

    check_int("runs", runs, 1)
    check_int("iterations", iterations, 1)
    chosen = resolve_engine(engine)
    console = console or Console(stderr=False)
    elf = build_elf([MATRIX_BENCH_SOURCE], mul=mul, defines={"BENCH_ITERATIONS": iterations, "BENCH_QUIET": None})
    program = load_elf(elf)
    engines = [chosen.name] if not chosen.translates or not compare else [chosen.name, INTERP.name]
    reference: dict[str, int] | None = None

    def one_run(name: str) -> tuple[int, int, float, bool]:
        """Instructions, cycles and host seconds of a run, and whether it translated nothing new."""
        nonlocal reference
        soc = SingleCoreSoC(mul=mul, engine=name)
        soc.load(program)
        result = soc.run(max_cycles=10**11)
        if result.exit_code != 0:
            raise RuntimeError(f"benchmark workload failed its self-check (exit code {result.exit_code})")
        if reference is None:
            reference = result.counters
        elif result.counters != reference:
            raise RuntimeError(f"engine {name} gave other counters than the first run: the engines disagree")
        return result.instructions, result.cycles, result.host_seconds, _settled(soc)

    warm: dict[str, float] = {}
    warm_runs: dict[str, int] = {}
    for name in engines:
        start = time.perf_counter()
        warm_runs[name] = 1
        while not one_run(name)[3] and time.perf_counter() - start < WARMUP_MAX_SECONDS:
            warm_runs[name] += 1
        warm[name] = time.perf_counter() - start

    rows: dict[str, list[tuple[int, int, float]]] = {name: [] for name in engines}
    with Progress(console=console, transient=True) as progress:
        task = progress.add_task("timed runs", total=runs * len(engines))
        for _ in range(runs):
            for name in engines:
                rows[name].append(one_run(name)[:3])
                progress.advance(task)

    medians: dict[str, float] = {}
    for name in engines:
        medians[name] = _report(console, name, rows[name], mul, iterations, warm[name], warm_runs[name])
    if chosen.translates:
        _report_translation(console)
    if len(engines) > 1:
        console.print(
            f"{chosen.name} / interp: {medians[chosen.name] / medians['interp']:.2f}x "
            f"(median {medians[chosen.name]:.1f} against {medians['interp']:.1f} MIPS, alternating runs)"
        )
    print(f"core: {medians[chosen.name]:.0f} MIPS")
    return medians[chosen.name]


def _settled(soc: SingleCoreSoC) -> bool:
    """Whether a run's translator (if any) may translate and entered (found and written, or loaded
    from an earlier run's record), handed over or put off nothing: the next runs will run what is
    translated now."""
    from robosoc.jit.policy import NEVER_ASK

    translator = soc.translator
    if translator is None:
        return True
    s = translator.stats
    new = s.regions or s.recorded or s.background or s.deferred or translator.compiling()
    return not new and translator.ask_threshold() != NEVER_ASK


def _report(
    console: Console,
    engine: str,
    rows: list[tuple[int, int, float]],
    mul: bool,
    iterations: int,
    warm: float,
    warm_runs: int,
) -> float:
    mips = [i / s / 1e6 for i, _, s in rows]
    mcps = [c / s / 1e6 for _, c, s in rows]
    instructions, cycles, _ = rows[0]
    table = Table(title=f"robosoc bench core ({'with' if mul else 'without'} multiplier, engine {engine})")
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
        f"(CPI {cycles / instructions:.2f}); untimed first runs incl. JIT/cache load and translation: "
        f"{warm_runs}, {warm:.2f} s"
    )
    console.print(
        f"{engine}: MIPS median {med:.1f}, min {min(mips):.1f}, max {max(mips):.1f}, "
        f"IQR {quartiles[0]:.1f}..{quartiles[2]:.1f}; simulated {statistics.median(mcps):.1f} M cycles/s"
    )
    return med


def _report_translation(console: Console) -> None:
    from robosoc.jit.compiler import shared_compiler
    from robosoc.jit.tables import translated_instructions

    stats = shared_compiler().stats
    n = translated_instructions()
    compiled = stats.modules - stats.cache_hits
    seconds = stats.seconds + stats.background_seconds
    per_k = f", {seconds / n * 1000:.3f} s per 1000 guest instructions" if n else ""
    thread = f", {stats.background_seconds:.2f} s of them in the compiling thread" if stats.background_seconds else ""
    console.print(
        f"translation: {n:,} guest instructions in {stats.modules} modules ({compiled} compiled, "
        f"{stats.cache_hits} from the disk cache), {seconds:.2f} s{thread}{per_k} (wall: parse "
        f"{stats.parse_seconds:.2f}, passes {stats.optimise_seconds:.2f}, code generation {stats.codegen_seconds:.2f}, "
        f"loading {stats.load_seconds:.2f}; CPU {stats.cpu_seconds:.2f} s)"
    )
