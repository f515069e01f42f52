"""``robosoc bench ...``: each benchmark lives in :mod:`robosoc.benchmarks` and prints its figures."""

from typing import Annotated

import typer

from robosoc.cli.app import bench_app


@bench_app.command("core")
def bench_core(
    runs: Annotated[int, typer.Option(help="Timed runs after the JIT warm-up.")] = 7,
    mul: Annotated[bool, typer.Option("--mul/--no-mul", help="Build the workload with the multiplier.")] = True,
) -> None:
    """Simulated MIPS of one core on an EKF-like workload (7x7 matrix inverse and multiply)."""
    from robosoc.benchmarks.core import run_core_benchmark

    run_core_benchmark(runs=runs, mul=mul)


@bench_app.command("physics")
def bench_physics(
    seconds: Annotated[float, typer.Option(help="Simulated seconds per run.")] = 10.0,
    runs: Annotated[int, typer.Option(help="Timed runs.")] = 5,
) -> None:
    """Real-time factor of the quadrotor physics alone (no controller)."""
    from robosoc.benchmarks.physics import run_physics_benchmark

    run_physics_benchmark(seconds=seconds, runs=runs)


@bench_app.command("noc")
def bench_noc(
    size: Annotated[str, typer.Option(help="Mesh WxH.")] = "8x8",
    cycles: Annotated[int, typer.Option(help="Simulated cycles per injection rate.")] = 10_000,
    plot: Annotated[str | None, typer.Option(help="Write latency against injection rate to this PNG.")] = None,
    seed: Annotated[int, typer.Option(help="Seed of the random traffic.")] = 1,
) -> None:
    """NoC alone under uniform random traffic: flits per host second and latency against load."""
    from robosoc.benchmarks.noc import run_noc_benchmark

    try:
        width, height = (int(v) for v in size.lower().split("x"))
    except ValueError as exc:
        raise typer.BadParameter(f"expected WxH, got {size!r}", param_hint="--size") from exc
    run_noc_benchmark(width=width, height=height, cycles=cycles, seed=seed, plot_path=plot)


@bench_app.command("chip")
def bench_chip(
    runs: Annotated[int, typer.Option(help="Timed runs after the warm-up.")] = 5,
    cycles: Annotated[int, typer.Option(help="Simulated cycles of the busy meshes.")] = 2_000_000,
    ticks: Annotated[int, typer.Option(help="Timer ticks (1 ms each) of the sleeping mesh.")] = 40,
    noc: Annotated[bool, typer.Option("--noc/--no-noc", help="Also run the NoC-alone benchmark.")] = True,
) -> None:
    """Whole-MPSoC speed: busy 2x2 and 4x4 meshes, a mostly sleeping 2x2, and the NoC alone."""
    from robosoc.benchmarks.chip import run_chip_benchmark

    run_chip_benchmark(runs=runs, cycles=cycles, ticks=ticks, noc=noc)
