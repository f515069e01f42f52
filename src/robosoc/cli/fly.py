"""``robosoc fly``: fly a scenario closed-loop and print hover, tracking and estimation errors."""

from __future__ import annotations

import math
import time
from pathlib import Path
from typing import Annotated

import typer

from robosoc.cli import exit_codes, files, link_options, options
from robosoc.cli.app import app
from robosoc.cli.console import make_console, note, plain
from robosoc.cli.errors import CliError
from robosoc.config.firmware import ARITH_CHOICES, FirmwareConfig
from robosoc.config.vehicle import VEHICLE_PRESETS

VIDEO_FPS = 25.0


def _fmt(value: float, unit: str, digits: int = 2) -> str:
    return "n/a" if math.isnan(value) else f"{value:.{digits}f} {unit}"


CONTROLLERS = ("host", "chip")

Controller = Annotated[
    str,
    typer.Option(
        help="Who flies: host (float64 Python) or chip (the firmware on the seed's 2x2 chip, in lockstep).",
        callback=options.choice(*CONTROLLERS),
    ),
]
Arith = Annotated[
    str | None,
    typer.Option(
        help="With --controller chip: float (soft-float) or fixed (Q16.16) firmware (default: fixed).",
        callback=options.choice(*ARITH_CHOICES),
    ),
]
Mul = Annotated[
    bool | None,
    typer.Option(
        "--mul/--no-mul", help="With --controller chip: cores with the multiplier or without (default: with)."
    ),
]
Seconds = Annotated[
    float | None,
    typer.Option(
        help="Flight length in seconds, whole ms in 0.001..3600, at least one sensor period (default: the scenario's).",
        callback=options.float_range(0.001, 3600.0, unit="s"),
    ),
]
Seed = Annotated[
    int, typer.Option(help="Seeds every random number (noise, biases, gusts), 0..2**63-1.", callback=options.seed())
]
Scenario = Annotated[Path | None, typer.Option(help="Scenario TOML file (default: built-in).")]
Vehicle = Annotated[
    str | None,
    typer.Option(help="default or laser (default: the scenario's).", callback=options.choice(*VEHICLE_PRESETS)),
]
Out = Annotated[
    Path | None,
    typer.Option(help="Folder for flight.csv (written as it flies) and flight.png (default: runs/fly-NAME-sSEED)."),
]
NoOut = Annotated[bool, typer.Option("--no-out", help="Write no log and no plot.")]
Video = Annotated[Path | None, typer.Option(help="Render to FILE.mp4, or to a folder of PNG frames.")]


@app.command("fly", epilog=exit_codes.EPILOG)
def fly_command(
    ctx: typer.Context,
    controller: Controller = "host",
    seconds: Seconds = None,
    seed: Seed = 1,
    scenario: Scenario = None,
    vehicle: Vehicle = None,
    out: Out = None,
    no_out: NoOut = False,
    video: Video = None,
    arith: Arith = None,
    mul: Mul = None,
    # --- decoupled mode (robosoc.cli.fly_decoupled, docs/decoupled.md) ---
    decoupled: Annotated[
        bool,
        typer.Option(
            "--decoupled",
            help="The physics and the chip as two processes over UDP on loopback (exit code 5 if a side goes silent).",
        ),
    ] = False,
    pace: link_options.Pace = "realtime",
    hold: link_options.Hold = "zoh",
    faults: link_options.Faults = None,
    resend: link_options.Resend = 2,
    peer_timeout: link_options.PeerTimeout = 5.0,
    bind: link_options.Bind = None,
) -> None:
    """Fly the scenario (default: take off to 1 m, hover, 10° roll/pitch/yaw steps, a gust; 10 s)."""
    from rich.markup import escape
    from rich.progress import BarColumn, Progress, TextColumn, TimeRemainingColumn

    from robosoc.chip.mpsoc import ChipError
    from robosoc.chip.single import CoreError
    from robosoc.config.scenario import ScenarioConfig
    from robosoc.config.vehicle import vehicle_preset
    from robosoc.control.flight import flight_metrics, fly
    from robosoc.control.flight_log import CsvFlightLog
    from robosoc.control.flight_plot import plot_flight
    from robosoc.control.host import HostController
    from robosoc.cosim.lockstep import fly_lockstep

    console = make_console()
    # --- decoupled mode: its options, and the chip controller it implies ---
    from robosoc.cli.fly_decoupled import LINK_OPTIONS

    for option, name in LINK_OPTIONS.items():
        if options.given(ctx, name) and not decoupled:
            raise options.fail(option, "only with --decoupled")
    if decoupled:
        if options.given(ctx, "controller") and controller != "chip":
            raise options.fail(
                "--decoupled", "the decoupled mode flies the firmware on the chip (drop --controller host)"
            )
        if video is not None:
            raise options.fail("--video", "not with --decoupled (the physics runs in another process)")
        controller = "chip"
        link = link_options.link_config(pace, hold, faults, resend, peer_timeout)
    # --- end of the decoupled mode's checks ---
    fw = _firmware(ctx, controller, arith, mul)
    options.exclusive(out=out is not None, no_out=no_out)
    sources: list[tuple[str, tuple[str, ...]]] = []
    config = ScenarioConfig()
    if scenario is not None:
        config, named = files.load_toml(ScenarioConfig, scenario, "--scenario")
        sources.append((str(scenario), named))
    changes = {}
    if seconds is not None:
        changes["--seconds"] = ("duration_s", seconds)
    if vehicle is not None:
        changes["--vehicle"] = ("vehicle", vehicle)
    config = options.override(config, changes, [str(scenario)] if scenario is not None else ())
    sources.extend((option, (field,)) for option, (field, _) in changes.items())
    period = 1.0 / config.sensors.rate_hz
    if round(config.duration_s * config.sensors.rate_hz) < 1:
        where = "--seconds" if seconds is not None else f"--scenario: {scenario}: duration_s"
        raise options.fail(
            where,
            f"a flight lasts at least one sensor period ({period:g} s at {config.sensors.rate_hz:g} Hz), "
            f"got {config.duration_s:g}",
        )
    craft = vehicle_preset(config.vehicle)

    if out is None and not no_out:
        out = Path("runs") / f"fly-{config.name}-s{seed}"
    if out is not None:
        out = files.output_dir(out, "--out", inputs=[scenario] if scenario else ())
    if decoupled:  # --- decoupled mode ---
        from robosoc.cli.fly_decoupled import fly_decoupled_run

        assert fw is not None
        fly_decoupled_run(console, config, craft, fw, seed, out, link, bind)
        return
    if video is not None:
        if video.suffix.lower() == ".mp4":
            video = files.output_file(video, "--video", inputs=[scenario] if scenario else ())
        else:
            video = files.output_dir(video, "--video")
    if fw is None:
        pilot = HostController.for_scenario(config, craft)
        flier = "host"
    else:
        from robosoc.cosim.lockstep import ChipController

        note(console, f"building the firmware ({fw.label}) and loading the chip ...")
        pilot = ChipController(config, craft, fw)
        flier = f"chip ({fw.label}, lockstep)"
    log = CsvFlightLog(out / "flight.csv") if out else None
    renderer = sink = None
    if video is not None:
        renderer, sink = _open_video(console, video)
    samples = round(config.duration_s * config.sensors.rate_hz)
    frame_every = max(1, round(config.sensors.rate_hz / VIDEO_FPS))
    state = {"renderer": renderer}

    def on_sample(world, k: int) -> None:
        progress.update(task, completed=k + 1)
        if state["renderer"] is None or k % frame_every:
            return
        if not isinstance(state["renderer"], tuple):
            state["renderer"] = _start_renderer(console, world, state["renderer"])
            if state["renderer"] is None:
                return
        sink.add(state["renderer"][0].render(world.data))

    console.print(
        f"flying scenario [bold]{escape(config.name)}[/bold] for {config.duration_s:g} s, vehicle {config.vehicle}, "
        f"controller {flier}, seed {seed}, sensors at {config.sensors.rate_hz:g} Hz"
    )
    for source, named in sources:
        console.print(escape(f"from {source}: {', '.join(named) if named else '(no fields)'}"))
    console.print("every other field: built-in default" if sources else "all fields: built-in defaults")
    try:
        with Progress(
            TextColumn("flight"),
            BarColumn(),
            TextColumn("{task.percentage:>3.0f}%"),
            TimeRemainingColumn(),
            console=console,
            transient=True,
        ) as progress:
            task = progress.add_task("fly", total=samples)
            start = time.perf_counter()
            if isinstance(pilot, HostController):
                rows = fly(config, craft, pilot, seed, on_row=log.write if log else None, on_sample=on_sample)
            else:
                rows = fly_lockstep(config, craft, pilot, seed, on_row=log.write if log else None, on_sample=on_sample)
            host_s = time.perf_counter() - start
    except (ChipError, CoreError) as exc:
        raise CliError(f"the firmware failed on the chip: {exc}") from exc
    except KeyboardInterrupt:
        note(console, "interrupted" + (f"; the log so far is in {log.path}" if log else ""))
        raise typer.Exit(exit_codes.INTERRUPTED) from None
    finally:
        if log:
            log.close()
        if isinstance(state["renderer"], tuple):
            state["renderer"][0].close()
        if sink is not None:
            sink.close()

    m = flight_metrics(rows, config.flight, craft.rest_height)
    console.print(
        f"hover height error (RMS, after the climb): {_fmt(m.hover_rms * 100, 'cm')}"
        f"  (max {_fmt(m.hover_max * 100, 'cm')}); overshoot {_fmt(m.overshoot * 100, 'cm')}"
    )
    if m.min_pwm_armed >= 0:
        console.print(f"lowest motor PWM while armed: {m.min_pwm_armed} (idle {craft.idle_pwm})")
    console.print(
        "attitude tracking error (RMS, 0.5 s after steps excluded): "
        f"roll {_fmt(m.tracking_rms[0], 'deg')}, pitch {_fmt(m.tracking_rms[1], 'deg')}, "
        f"yaw {_fmt(m.tracking_rms[2], 'deg')}"
    )
    for axis, at, rise in m.step_rise:
        console.print(f"  {axis} step at {at:g} s: 90 % reached after {_fmt(rise * 1000, 'ms', 0)}")
    if fw is None:
        console.print(
            f"EKF attitude error vs truth (RMS while flying): {_fmt(m.ekf_rms, 'deg')} "
            f"(max {_fmt(m.ekf_max, 'deg')}; "
            f"roll {m.ekf_euler_rms[0]:.2f}, pitch {m.ekf_euler_rms[1]:.2f}, yaw {m.ekf_euler_rms[2]:.2f} deg)"
        )
        console.print(f"height estimate error (RMS while flying): {_fmt(m.height_estimate_rms * 100, 'cm')}")
    else:
        _chip_report(console, pilot, out, config.duration_s, host_s)
    if out:
        plot_flight(rows, out / "flight.png", title=f"{config.name}, seed {seed}")
        plain(console, f"log: {out / 'flight.csv'}  plot: {out / 'flight.png'}")
    if sink is not None and sink.frames:
        plain(console, f"video: {sink.path} ({sink.frames} frames at {VIDEO_FPS:g} fps)")


def _firmware(ctx: typer.Context, controller: str, arith: str | None, mul: bool | None) -> FirmwareConfig | None:
    """The firmware build the chip flies (None for the host controller, which takes no build options)."""
    arith_given = arith is not None
    mul_given = mul is not None and options.given(ctx, "mul")
    if controller == "host":
        for option, given in (("--arith", arith_given), ("--mul/--no-mul", mul_given)):
            if given:
                raise options.fail(option, "only with --controller chip (the host controller has no firmware)")
        return None
    changes = {}
    if arith_given:
        changes["--arith"] = ("arith", arith)
    if mul_given:
        changes["--mul/--no-mul"] = ("multiplier", mul)
    return options.override(FirmwareConfig(), changes)


def _chip_report(console, pilot, out: Path | None, simulated_s: float, host_s: float) -> None:
    """Per-task response times and deadline misses of the chip's flight; jobs.csv in ``out``."""
    from robosoc.cosim.replay import task_summary, write_jobs_csv

    result = pilot.result
    console.print("state estimate: on the chip (only PWM commands reach the I/O tile)")
    for name, s in task_summary(result.jobs, result.clock_ns).items():
        console.print(
            f"  {name:<9} {s['jobs']} jobs: response mean {s['response_us_mean']:.1f} us, "
            f"max {s['response_us_max']:.1f} us; exec mean {s['exec_cycles_mean']:.0f} cycles; "
            f"deadline misses {s['deadline_misses']}"
        )
    console.print(
        f"deadline misses: {result.deadline_misses}; {len(result.commands)} PWM commands; "
        f"real-time factor {simulated_s / host_s:.2f} ({simulated_s:g} s simulated in {host_s:.1f} s)"
    )
    if out:
        write_jobs_csv(result.jobs, out / "jobs.csv")
        plain(console, f"jobs: {out / 'jobs.csv'}")


def _open_video(console, video: Path):
    """Find a GL backend and open the frame sink; on failure say why and fly without video."""
    from robosoc.physics.render import FrameSink, RenderUnavailable, find_backend

    try:
        backend = find_backend()
        sink = FrameSink(video, VIDEO_FPS)
    except RenderUnavailable as exc:
        note(console, f"no video: {exc}")
        return None, None
    return backend, sink


def _start_renderer(console, world, backend: str):
    from robosoc.physics.mjcf import RENDER_SIZE
    from robosoc.physics.render import OffscreenRenderer, RenderUnavailable

    try:
        width, height = RENDER_SIZE
        return (OffscreenRenderer(world.model, world.quadrotors[0].body_id, width, height, backend),)
    except RenderUnavailable as exc:
        note(console, f"no video: {exc}")
        return None
