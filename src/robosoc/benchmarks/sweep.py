"""``robosoc bench sweep``: how a sweep scales with workers, and what the Dask path costs per point.

One sweep of ``points`` chip flights (the default scenario cut to ``seconds``, fixed point with
the multiplier, seeds 1..points: CPU-bound and all alike) runs three times into fresh folders:
on the local pool with 1 worker, with ``workers`` workers, and on a Dask ``LocalCluster`` of
``workers`` processes.  Each time includes starting the workers (each imports robosoc and loads
the compiled kernels once), as a user's sweep does; the firmware and the kernels are prepared
before the first, so no run pays for compiling.  Prints each wall time, the speed-up and the
Dask path's overhead per point; last the line ``sweep: <x>× speed-up with <n> workers``.
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

from rich.console import Console

from robosoc.config.sweep import SweepConfig, sweep_from_mapping
from robosoc.sweep.runner import LOCAL, run_sweep


def bench_sweep_config(points: int, seconds: float) -> SweepConfig:
    """The benchmark's sweep: ``points`` seeds of one ``seconds`` chip flight."""
    data = {"seeds": list(range(1, points + 1)), "base": {"duration_s": seconds, "controller": "chip"}}
    return sweep_from_mapping(data, "<bench sweep>", Path.cwd(), "bench")


def time_sweep(config: SweepConfig, folder: Path, workers: int, dask: str | None = None) -> float:
    """Wall seconds of one complete sweep into the fresh ``folder``."""
    start = time.perf_counter()
    outcome = run_sweep(config, folder, workers=workers, dask=dask)
    elapsed = time.perf_counter() - start
    if outcome.failures:
        raise RuntimeError(f"a benchmark point failed: {outcome.failures[0]['error']}")
    return elapsed


def run_sweep_benchmark(points: int, seconds: float, workers: int, console: Console | None = None) -> float:
    """Measure and print; the speed-up of ``workers`` workers over one."""
    console = console or Console()
    config = bench_sweep_config(points, seconds)
    console.print(f"{points} points of {seconds:g} s chip flights (fixed+mul); each time includes starting the workers")
    with tempfile.TemporaryDirectory(prefix="robosoc-bench-sweep-") as tmp:
        root = Path(tmp)
        one = time_sweep(config, root / "one", 1)
        console.print(f"local pool, 1 worker:   {one:7.1f} s ({one / points:.2f} s per point)")
        many = time_sweep(config, root / "many", workers)
        console.print(f"local pool, {workers} workers:  {many:7.1f} s ({many / points:.2f} s per point)")
        dask = time_sweep(config, root / "dask", workers, LOCAL)
        console.print(f"Dask LocalCluster, {workers}:   {dask:7.1f} s ({dask / points:.2f} s per point)")
    speedup = one / many
    console.print(f"speed-up {speedup:.2f}× with {workers} workers (ideal {min(workers, points)}×)")
    console.print(f"Dask path: {(dask - many) / points * 1000:+.0f} ms per point against the local pool")
    console.print(f"sweep: {speedup:.2f}× speed-up with {workers} workers")
    return speedup


__all__ = ["bench_sweep_config", "run_sweep_benchmark", "time_sweep"]
