"""``robosoc bench ...``: each benchmark lives in :mod:`robosoc.benchmarks` and prints its figures."""

from pathlib import Path
from typing import Annotated

import typer

from robosoc.cli import exit_codes, files, options
from robosoc.cli.console import make_console
from robosoc.cli.engine_option import check_engine
from robosoc.cli.typer_apps import bench_app
from robosoc.config.firmware import ARITH_CHOICES
from robosoc.config.scenario import MAX_VEHICLES

MAX_RUNS = 1000
#: Largest NoC benchmark: generated-cycles x tiles (the traffic draws one number per tile and cycle).
MAX_NOC_TILE_CYCLES = 50_000_000
PLOT_SUFFIXES = (".png", ".pdf", ".svg")

Runs = Annotated[int, typer.Option(help=f"Timed runs, 1..{MAX_RUNS}.", callback=options.int_range(1, MAX_RUNS))]


@bench_app.command("core", epilog=exit_codes.EPILOG)
def bench_core(
    runs: Annotated[
        int,
        typer.Option(
            help=f"Timed runs after the warm-up (JIT load, translation), 1..{MAX_RUNS}.",
            callback=options.int_range(1, MAX_RUNS),
        ),
    ] = 7,
    mul: Annotated[bool, typer.Option("--mul/--no-mul", help="Build the workload with the multiplier.")] = True,
    engine: Annotated[
        str,
        typer.Option(
            help="interp, jit or auto (docs/translation.md); the last line gives this engine's median.",
            callback=check_engine,
        ),
    ] = "interp",
    compare: Annotated[
        bool,
        typer.Option("--compare/--no-compare", help="Also time the interpreter in the same run (not with interp)."),
    ] = True,
) -> None:
    """Simulated MIPS of one core on an EKF-like workload (7x7 matrix inverse and multiply)."""
    from robosoc.benchmarks.core import run_core_benchmark

    run_core_benchmark(runs=runs, mul=mul, engine=engine, compare=compare, console=make_console())


@bench_app.command("physics", epilog=exit_codes.EPILOG)
def bench_physics(
    seconds: Annotated[
        float,
        typer.Option(
            help="Simulated seconds per run, 0.001..3600.", callback=options.float_range(0.001, 3600.0, unit="s")
        ),
    ] = 10.0,
    runs: Runs = 5,
) -> None:
    """Real-time factor of the quadrotor physics alone (no controller)."""
    from robosoc.benchmarks.physics import run_physics_benchmark

    run_physics_benchmark(seconds=seconds, runs=runs, console=make_console())


@bench_app.command("noc", epilog=exit_codes.EPILOG)
def bench_noc(
    size: Annotated[str, typer.Option(help="Mesh WxH, 2 to 256 tiles.")] = "8x8",
    cycles: Annotated[
        int,
        typer.Option(
            help="Simulated cycles per injection rate, 1..1000000 (cycles x tiles at most 50000000).",
            callback=options.int_range(1, 1_000_000, "cycles"),
        ),
    ] = 10_000,
    plot: Annotated[
        Path | None, typer.Option(help="Write latency against injection rate to this PNG (or .pdf, .svg).")
    ] = None,
    seed: Annotated[int, typer.Option(help="Seed of the random traffic, 0..2**63-1.", callback=options.seed())] = 1,
    arbiter: Annotated[
        str,
        typer.Option(
            help="Router model: hermes, per-output, or both (same traffic, same per-hop timing).",
            callback=options.choice("hermes", "per-output", "both"),
        ),
    ] = "both",
    rates: Annotated[
        str | None,
        typer.Option(help="Offered loads in (0, 1] flits/cycle/tile, comma separated (default: a sweep)."),
    ] = None,
    packet_flits: Annotated[
        str,
        typer.Option(
            help="Flits per packet, header and 3-flit tag included, 5..64, or a range such as 5-20 (each "
            "packet's length drawn uniformly)."
        ),
    ] = "16",
    depth: Annotated[
        int,
        typer.Option(
            help="Flits per router input buffer, 2..256 (the chip's default 16; ORCA's RTL has 4).",
            callback=options.int_range(2, 256),
        ),
    ] = 16,
    rx_hold: Annotated[
        int,
        typer.Option(
            help="Cycles every receive memory stays held after a packet, 0..10000 (0: freed the next cycle).",
            callback=options.int_range(0, 10_000),
        ),
    ] = 0,
    compare_read_pointer: Annotated[
        bool,
        typer.Option(
            "--compare-read-pointer",
            help="Also run the Hermes model without its buffer's read-pointer timing (hermes-before: the tail "
            "credit and the bubble off, the model before issue 38) on the same traffic.",
        ),
    ] = False,
    gating: Annotated[
        str,
        typer.Option(
            help="Router clock gating (chip.noc.clock_gating): off, on, or both (same traffic; the energy and "
            "latency change printed side by side).",
            callback=options.choice("off", "on", "both"),
        ),
    ] = "both",
) -> None:
    """NoC alone under uniform random traffic: flits per host second and latency against load, per router model
    (with and without clock-gated routers: their energy and latency change)."""
    from robosoc.benchmarks.noc import DEFAULT_RATES, run_noc_benchmark
    from robosoc.config.chip import ARBITERS

    width, height = options.parse_mesh("--size", size)
    if cycles * width * height > MAX_NOC_TILE_CYCLES:
        raise options.fail(
            "--cycles", f"at most {MAX_NOC_TILE_CYCLES // (width * height)} on a {width}x{height} mesh, got {cycles}"
        )
    loads = DEFAULT_RATES if rates is None else options.parse_floats("--rates", rates, 0.0, 1.0, lo_open=True)
    plot_path = files.output_file(plot, "--plot", suffixes=PLOT_SUFFIXES) if plot is not None else None
    run_noc_benchmark(
        width=width,
        height=height,
        rates=loads,
        cycles=cycles,
        packet_flits=_packet_flits(packet_flits),
        seed=seed,
        plot_path=plot_path,
        console=make_console(min_width=100),  # the table needs ~90 columns
        arbiters=ARBITERS if arbiter == "both" else (arbiter,),
        buffer_depth=depth,
        rx_hold=rx_hold,
        compare_read_pointer=compare_read_pointer,
        gating={"off": (False,), "on": (True,), "both": (False, True)}[gating],
    )


def _packet_flits(text: str) -> int | tuple[int, int]:
    """``--packet-flits``: ``"16"`` or ``"5-20"``, each 5..64."""
    try:
        values = [int(v) for v in text.split("-")]
    except ValueError:
        values = []
    if len(values) not in (1, 2) or any(not 5 <= v <= 64 for v in values) or values[0] > values[-1]:
        raise options.fail("--packet-flits", f"expected N or LO-HI with 5 <= LO <= HI <= 64, got {text!r}")
    return values[0] if len(values) == 1 else (values[0], values[1])


@bench_app.command("chip", epilog=exit_codes.EPILOG)
def bench_chip(
    runs: Annotated[
        int, typer.Option(help=f"Timed runs after the warm-up, 1..{MAX_RUNS}.", callback=options.int_range(1, MAX_RUNS))
    ] = 5,
    cycles: Annotated[
        int,
        typer.Option(
            help="Simulated cycles of the busy meshes, 1..10**10.", callback=options.int_range(1, 10**10, "cycles")
        ),
    ] = 2_000_000,
    ticks: Annotated[
        int,
        typer.Option(
            help="Timer ticks (1 ms each) of the sleeping mesh, 1..100000.", callback=options.int_range(1, 100_000)
        ),
    ] = 40,
    noc: Annotated[bool, typer.Option("--noc/--no-noc", help="Also run the NoC-alone benchmark.")] = True,
    engine: Annotated[
        str, typer.Option(help="interp, jit or auto (docs/translation.md).", callback=check_engine)
    ] = "interp",
) -> None:
    """Whole-MPSoC speed: busy 2x2, 4x4 and 8x8 meshes, mostly sleeping 2x2 and 16x16, and the NoC alone."""
    from robosoc.benchmarks.chip import run_chip_benchmark

    run_chip_benchmark(runs=runs, cycles=cycles, ticks=ticks, noc=noc, console=make_console(), engine=engine)


@bench_app.command("fly", epilog=exit_codes.EPILOG)
def bench_fly(
    ctx: typer.Context,
    arith: Annotated[
        str | None,
        typer.Option(
            help="Fly only this firmware arithmetic: float or fixed (default: all four builds).",
            callback=options.choice(*ARITH_CHOICES),
        ),
    ] = None,
    mul: Annotated[
        bool | None,
        typer.Option("--mul/--no-mul", help="Fly only the build with (or without) the multiplier."),
    ] = None,
    duration: Annotated[
        float,
        typer.Option(
            help="Simulated seconds per flight, whole ms in 0.01..3600.",
            callback=options.float_range(0.01, 3600.0, unit="s"),
        ),
    ] = 10.0,
    breakdown: Annotated[
        bool,
        typer.Option(
            "--breakdown",
            help="Instead: where each build's flight spends its host time, per cause (docs/translation.md).",
        ),
    ] = False,
    vehicles: Annotated[
        int,
        typer.Option(
            help=f"Vehicles per flight, 1..{MAX_VEHICLES} (their chips run on the host's cores at once); "
            "not with --breakdown.",
            callback=options.int_range(1, MAX_VEHICLES),
        ),
    ] = 1,
    engine: Annotated[
        str | None,
        typer.Option(
            help="The chip's engine for every build: interp, jit or auto (docs/translation.md; default: the "
            "chip's own, auto).",
            show_default=False,
            callback=check_engine,
        ),
    ] = None,
    runs: Annotated[
        int,
        typer.Option(
            help="Timed flights per build (and of the host controller) after the warm-up, 1..100; the figures "
            "are those of the median one.",
            callback=options.int_range(1, 100),
        ),
    ] = 3,
) -> None:
    """Real-time factor of the lockstep flight (physics + firmware on the chip), per firmware build,
    the host controller as reference, and each build's speed as a share of the host controller's
    flight in the same run (the median of --runs flights each); last line: fly: <x>× real time (fixed
    + multiplier by default)."""
    from robosoc.benchmarks.fly import ALL_BUILDS, run_fly_benchmark

    if round(duration * 1000) != round(duration * 1000, 6):
        raise options.fail("--duration", f"must be a whole number of ms, got {duration:g}")
    mul_given = mul is not None and options.given(ctx, "mul")
    builds = tuple(
        fw for fw in ALL_BUILDS if (arith is None or fw.arith == arith) and (not mul_given or fw.multiplier == mul)
    )
    chosen = arith is not None or mul_given
    if breakdown:
        if vehicles != 1:
            raise options.fail("--vehicles", "the breakdown flies one vehicle: leave --vehicles out with --breakdown")
        from robosoc.benchmarks.fly_breakdown import run_fly_breakdown

        run_fly_breakdown(builds, duration_s=duration, console=make_console(), engine=engine)
        return
    run_fly_benchmark(
        builds,
        duration_s=duration,
        host=not chosen,
        console=make_console(),
        vehicles=vehicles,
        engine=engine,
        runs=runs,
    )


@bench_app.command("sweep", epilog=exit_codes.EPILOG)
def bench_sweep(
    points: Annotated[
        int, typer.Option(help="Points (chip flights) per sweep, 1..256.", callback=options.int_range(1, 256))
    ] = 8,
    seconds: Annotated[
        float,
        typer.Option(
            help="Simulated seconds per flight, 0.01..60.", callback=options.float_range(0.01, 60.0, unit="s")
        ),
    ] = 2.0,
    workers: Annotated[
        int, typer.Option(help="Workers of the parallel runs, 1..256.", callback=options.int_range(1, 256))
    ] = 2,
) -> None:
    """Speed-up of a sweep on the local pool (1 worker against --workers) and the Dask path's overhead."""
    from robosoc.benchmarks.sweep import run_sweep_benchmark

    run_sweep_benchmark(points=points, seconds=seconds, workers=workers, console=make_console())
