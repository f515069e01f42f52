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
    arbiter: Annotated[
        str, typer.Option(help="Router model: hermes, per-output, or both (same traffic, same per-hop timing).")
    ] = "both",
    rates: Annotated[
        str | None, typer.Option(help="Offered loads in flits/cycle/tile, comma separated (default: a sweep).")
    ] = None,
    packet_flits: Annotated[int, typer.Option(help="Flits per packet, header and 3-flit tag included.")] = 16,
) -> None:
    """NoC alone under uniform random traffic: flits per host second and latency against load, per router model."""
    from robosoc.benchmarks.noc import DEFAULT_RATES, run_noc_benchmark
    from robosoc.config.chip import ARBITERS, ChipConfig

    try:
        width, height = (int(v) for v in size.lower().split("x"))
    except ValueError as exc:
        raise typer.BadParameter(f"expected WxH, got {size!r}", param_hint="--size") from exc
    try:
        ChipConfig(width=width, height=height)
    except ValueError as exc:
        raise typer.BadParameter(str(exc), param_hint="--size") from exc
    if arbiter != "both" and arbiter not in ARBITERS:
        raise typer.BadParameter(f"expected {', '.join(ARBITERS)} or both, got {arbiter!r}", param_hint="--arbiter")
    try:
        loads = DEFAULT_RATES if rates is None else tuple(float(v) for v in rates.split(","))
    except ValueError as exc:
        raise typer.BadParameter(f"expected numbers separated by commas, got {rates!r}", param_hint="--rates") from exc
    if not all(0.0 < r <= 1.0 for r in loads):
        raise typer.BadParameter(f"loads must be in (0, 1] flits/cycle/tile, got {rates!r}", param_hint="--rates")
    if not 5 <= packet_flits <= 64:
        raise typer.BadParameter(f"must be between 5 and 64, got {packet_flits}", param_hint="--packet-flits")
    run_noc_benchmark(
        width=width,
        height=height,
        rates=loads,
        cycles=cycles,
        packet_flits=packet_flits,
        seed=seed,
        plot_path=plot,
        arbiters=ARBITERS if arbiter == "both" else (arbiter,),
    )


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
