"""``robosoc fly [SCENARIO.toml]``: fly a scenario closed-loop (by default the firmware on the chip, in
lockstep), write the run folder and print a summary table (the run itself is
:func:`robosoc.outputs.flight_session.fly_scenario`)."""

from __future__ import annotations

import dataclasses
import json
import math
import time
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

from robosoc.cli import exit_codes, files, link_options, options
from robosoc.cli.console import make_console, note, plain
from robosoc.cli.errors import CliError
from robosoc.cli.project_check import check_project
from robosoc.cli.scenario_flags import FLY, ResolvedScenario, ScenarioFlags, resolve, takes_scenario
from robosoc.cli.typer_apps import app
from robosoc.config.scenario import ScenarioConfig

if TYPE_CHECKING:
    from rich.progress import Progress, TaskID

    from robosoc.physics.render import FrameSink, OffscreenRenderer

VIDEO_FPS = 25.0

Out = Annotated[
    Path | None,
    typer.Option(help="Run folder: scenario.toml, flight.csv, jobs.csv, summary.json, flight.png "
                 "(default: runs/fly-NAME-sSEED)."),
]  # fmt: skip
NoOut = Annotated[bool, typer.Option("--no-out", help="Write nothing (print the summary only).")]
Video = Annotated[Path | None, typer.Option(help="Render to FILE.mp4, or to a folder of PNG frames.")]
Foxglove = Annotated[
    int | None,
    typer.Option(
        help="Serve the flight live to Foxglove on ws://127.0.0.1:PORT (8765 is Foxglove's default; 0: any free "
        "port), at most at real-time pace.",
        callback=options.int_range(0, 65535),
    ),
]
FoxgloveKeep = Annotated[
    bool,
    typer.Option("--foxglove-keep", help="With --foxglove: keep serving after the flight ends, until Ctrl-C."),
]
Profile = Annotated[
    bool,
    typer.Option(
        "--profile",
        help="Count every instruction: cycles, instructions and energy per firmware function, tile and task "
        "(profile.json, profile.csv; docs/profile.md).",
    ),
]
Decoupled = Annotated[
    bool,
    typer.Option(
        "--decoupled",
        help="The physics and the chip as two processes over UDP on loopback (exit code 5 if a side goes silent).",
    ),
]


@app.command("fly", epilog=exit_codes.FLY_EPILOG)
@takes_scenario(FLY)
def fly_command(
    ctx: typer.Context,
    flags: ScenarioFlags,
    out: Out = None,
    no_out: NoOut = False,
    video: Video = None,
    foxglove: Foxglove = None,
    foxglove_keep: FoxgloveKeep = False,
    profile: Profile = False,
    # --- decoupled mode (robosoc.cli.fly_decoupled, docs/decoupled.md) ---
    decoupled: Decoupled = False,
    pace: link_options.Pace = "realtime",
    hold: link_options.Hold = "zoh",
    faults: link_options.Faults = None,
    resend: link_options.Resend = 2,
    peer_timeout: link_options.PeerTimeout = 5.0,
    bind: link_options.Bind = None,
) -> None:
    """Fly a scenario: by default the firmware (fixed point, multiplier) on the seed's 2x2 chip in
    lockstep with the physics: take off to 1 m, hover, 10° roll/pitch/yaw steps, a gust; 10 s."""
    console = make_console()
    link = link_options.link_of(ctx, decoupled, flags, video=video, foxglove=foxglove, profile=profile)
    if foxglove_keep and foxglove is None:
        raise options.fail("--foxglove-keep", "only with --foxglove PORT")
    resolved = resolve(flags)
    config = resolved.config if link is None else dataclasses.replace(resolved.config, controller="chip")
    _check_controller(resolved, config, profile)
    if link is not None:  # the decoupled mode's physics side sends the sensor packets only
        check_project(config, resolved.source_of("firmware.project"), sends=("sensor",), what="the decoupled mode")
    else:
        check_project(config, resolved.source_of("firmware.project"))
    check_power(resolved, config)
    options.exclusive(out=out is not None, no_out=no_out)
    if out is None and not no_out:
        out = Path("runs") / f"fly-{config.name}-s{config.seed}"
    if out is not None:
        from robosoc.outputs.run_folder import RUN_FILES

        out = files.output_dir(out, "--out", inputs=resolved.inputs, names=RUN_FILES)
    if link is not None:
        from robosoc.cli.fly_decoupled import fly_decoupled_run

        fly_decoupled_run(console, config, out, link, bind)
        return
    if video is not None:
        video = files.output_file(video, "--video", inputs=resolved.inputs) if video.suffix.lower() == ".mp4" else (
            files.output_dir(video, "--video"))  # fmt: skip
    _announce(console, resolved, config)
    flight = _fly(console, config, out, video, foxglove, profile, foxglove_keep)
    print_summary(console, flight.summary)
    if profile:
        from robosoc.cli.profile import print_profile

        for i, result in enumerate(flight.results):
            if result is not None and result.profile is not None:
                print_profile(console, result.profile, title=f"vehicle {i + 1}, " if len(flight.results) > 1 else "")
    if out is not None:
        plain(console, f"run folder: {out} (scenario.toml, flight.csv, summary.json, flight.png, flight.mcap, "
              + ("jobs.csv, chip-trace.json, " if config.controller == "chip" else "")
              + ("profile.json, profile.csv, " if profile else "") + "report.html)")  # fmt: skip


def check_power(resolved: ResolvedScenario, config: ScenarioConfig) -> None:
    """A battery that cannot fly the vehicle is refused before anything is built or flown.

    Raises:
        CliError: naming the field (the option or the scenario file that set it) and why.
    """
    from robosoc.physics.power import lift_problem

    problem = lift_problem(config.vehicle_config())
    if problem is not None:
        field, reason = problem
        raise CliError(f"{resolved.source_of(field)}: {reason}")


def _check_controller(resolved: ResolvedScenario, config: ScenarioConfig, profile: bool) -> None:
    """The host controller runs no firmware on no chip: the options for them are refused."""
    if config.controller != "host":
        return
    if profile:
        raise options.fail("--profile", "only with the chip controller (the host controller has no firmware)")
    for flag in resolved.given:
        if flag.section == "firmware":
            raise options.fail(flag.option, "only with the chip controller (the host controller has no firmware)")
        if flag.section == "chip":
            raise options.fail(flag.option, "only with the chip controller (the host controller runs no code)")


def _announce(console, resolved: ResolvedScenario, config: ScenarioConfig) -> None:
    """What is flown, and where each part of the scenario came from."""
    from rich.markup import escape

    flier = f"chip ({config.firmware.label}, lockstep)" if config.controller == "chip" else "host"
    fleet = f"{config.vehicles} vehicles ({config.vehicle})" if config.vehicles > 1 else f"vehicle {config.vehicle}"
    console.print(
        f"flying scenario [bold]{escape(config.name)}[/bold] for {config.duration_s:g} s, {fleet}, "
        f"controller {flier}, seed {config.seed}, sensors at {config.sensors.rate_hz:g} Hz"
    )
    for source, fields in resolved.sources:
        console.print(escape(f"from {source}: {', '.join(fields) if fields else '(no fields)'}"))
    console.print("every other field: built-in default" if resolved.sources else "all fields: built-in defaults")


def _fly(
    console,
    config: ScenarioConfig,
    out: Path | None,
    video: Path | None,
    foxglove: int | None,
    profile: bool,
    keep: bool = False,
):
    """The flight with its progress bar, video and live server (kept serving after the flight until
    Ctrl-C with ``keep``); an interrupt or a firmware fault ends the command with the flight so far
    in ``out``."""
    from robosoc.chip.mpsoc import ChipError
    from robosoc.chip.single import CoreError
    from robosoc.outputs.flight_session import fly_scenario
    from robosoc.toolchain import ToolchainError

    video_state = _VideoState(console, video) if video is not None else None
    live = _start_live(console, foxglove)  # --foxglove (docs/results-logs.md)
    progress = FlightProgress(console, config.duration_s, config.sensors.rate_hz)

    def on_sample(world, k: int) -> None:
        progress.sample(k)
        if video_state is not None:
            video_state.frame(world, k, config.sensors.rate_hz)

    try:
        flight = fly_scenario(
            config, out, on_sample=on_sample, on_status=progress.status, on_row=_live_rows(live), plot=True,
            profile=profile,
        )  # fmt: skip
        if keep and live is not None:
            progress.stop()
            plain(console, f"foxglove: the flight is over; still serving on {live.url} until Ctrl-C")
            live.hold()
    except KeyboardInterrupt as exc:
        progress.stop()
        note(console, interrupted_message(out, exc))
        raise typer.Exit(exit_codes.INTERRUPTED) from None
    except ToolchainError as exc:  # a compile error (file and line), or a program that cannot fit
        progress.stop()
        raise CliError(f"the firmware does not build: {exc}") from exc
    except (ChipError, CoreError) as exc:
        progress.stop()
        where = f" (the flight so far is in {out})" if out else ""
        raise CliError(f"the firmware failed on the chip: {exc}{where}", code=exit_codes.SIMULATOR_STOP) from exc
    finally:
        progress.stop()
        if video_state is not None:
            video_state.close()
        if live is not None:
            live.close()
    if video_state is not None and video_state.sink is not None and video_state.sink.frames:
        plain(console, f"video: {video_state.sink.path} ({video_state.sink.frames} frames at {VIDEO_FPS:g} fps)")
    return flight


def interrupted_message(out: Path | None, exc: KeyboardInterrupt) -> str:
    """What a Ctrl-C left, read from the run folder's ``summary.json`` itself, so that the message
    and the file agree whenever the interruption came (before, during or after the flight)."""
    from robosoc.cosim.interrupts import InterruptedAfterFlight

    if out is None:
        return "interrupted"
    path = out / "summary.json"
    try:
        complete = json.loads(path.read_text(encoding="utf-8")).get("complete")
    except (OSError, ValueError, AttributeError):
        complete = None
    if complete is True:
        missing = getattr(exc, "missing", []) if isinstance(exc, InterruptedAfterFlight) else []
        left = f"; not written: {', '.join(missing)}" if missing else ""
        return f"interrupted after the flight: it is complete in {out} (summary.json: complete true){left}"
    if complete is False:
        return f"interrupted; the flight so far is in {out} (summary.json: complete false)"
    return f"interrupted before the flight; nothing flown (no summary.json in {out})"


class FlightProgress:
    """A progress bar of simulated seconds and the real-time factor, started at the first sample
    (so that building and compiling are not counted)."""

    def __init__(self, console, duration_s: float, rate_hz: float) -> None:
        self.console = console
        self.duration_s = duration_s
        self.rate_hz = rate_hz
        self.samples = round(duration_s * rate_hz)
        self.progress: Progress | None = None
        self.spinner: Progress | None = None
        self.task: TaskID | None = None
        self.start = 0.0

    def status(self, text: str) -> None:
        """Say what is being done before the flight; a spinner with the elapsed time runs until the
        next status or the first sample (a first run compiles for a minute or more)."""
        from rich.progress import Progress, SpinnerColumn, TextColumn, TimeElapsedColumn

        self._stop_spinner()
        plain(self.console, text)
        self.spinner = Progress(
            SpinnerColumn(), TextColumn("{task.description}"), TimeElapsedColumn(), console=self.console, transient=True
        )
        self.spinner.start()
        self.spinner.add_task(text.rstrip(" .").split(" (")[0])

    def _stop_spinner(self) -> None:
        if self.spinner is not None:
            self.spinner.stop()
            self.spinner = None

    def sample(self, k: int) -> None:
        if self.progress is None:
            self._stop_spinner()
            from rich.progress import BarColumn, Progress, TextColumn, TimeRemainingColumn

            self.progress = Progress(
                TextColumn("flight"),
                BarColumn(),
                TextColumn("{task.fields[sim]}"),
                TextColumn("{task.fields[rtf]}"),
                TimeRemainingColumn(),
                console=self.console,
                transient=True,
            )
            self.progress.start()
            self.task = self.progress.add_task("fly", total=self.samples, sim="", rtf="")
            self.start = time.perf_counter()
        simulated = (k + 1) / self.rate_hz
        elapsed = time.perf_counter() - self.start
        rtf = f"{simulated / elapsed:.2f}x real time" if elapsed > 0.2 else ""
        assert self.task is not None  # added with the bar
        self.progress.update(self.task, completed=k + 1, sim=f"{simulated:.2f}/{self.duration_s:g} s", rtf=rtf)

    def stop(self) -> None:
        self._stop_spinner()
        if self.progress is not None:
            self.progress.stop()
            self.progress = None


class _VideoState:
    """The frame sink and the renderer (started at the first frame); without a GL backend: a note."""

    def __init__(self, console, video: Path) -> None:
        self.console = console
        self.renderer: OffscreenRenderer | None = None
        self.sink: FrameSink | None = None
        from robosoc.physics.render import FrameSink, RenderUnavailable, find_backend

        try:
            self.backend = find_backend()
            self.sink = FrameSink(video, VIDEO_FPS)
        except RenderUnavailable as exc:
            note(console, f"no video: {exc}")

    def frame(self, world, k: int, rate_hz: float) -> None:
        if self.sink is None or k % max(1, round(rate_hz / VIDEO_FPS)):
            return
        if self.renderer is None:
            from robosoc.physics.mjcf import RENDER_SIZE
            from robosoc.physics.render import OffscreenRenderer, RenderUnavailable

            try:
                width, height = RENDER_SIZE
                body = world.quadrotors[0].body_id
                self.renderer = OffscreenRenderer(world.model, body, width, height, self.backend)
            except RenderUnavailable as exc:
                note(self.console, f"no video: {exc}")
                self.sink.close()
                self.sink = None
                return
        self.sink.add(self.renderer.render(world.data))

    def close(self) -> None:
        if self.renderer is not None:
            self.renderer.close()
        if self.sink is not None:
            self.sink.close()


def _fmt(value: float | None, scale: float, digits: int, unit: str = "") -> str:
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "n/a"
    return f"{value * scale:.{digits}f}{(' ' + unit) if unit else ''}"


def _mission_rows(row) -> None:
    """The mission's lines of the flight summary: waypoints reached, their worst horizontal error,
    the landing."""

    def mission(v) -> dict:
        return v.get("mission") or {}

    row(
        "waypoints reached",
        lambda v: (
            f"{mission(v).get('reached')} of {len(mission(v).get('waypoints') or [])} "
            f"(within {_fmt(mission(v).get('acceptance_m'), 100, 0, 'cm')})"
        ),
    )
    row("horizontal error at waypoints max", lambda v: _fmt(mission(v).get("horizontal_error_max_m"), 100, 1, "cm"))

    def landed(v) -> str:
        m = mission(v)
        if "landed" not in m:
            return "n/a (no landing)"
        if not m["landed"]:
            return "no"
        return f"at {m['landed_s']:.2f} s, {_fmt(m.get('landing_error_m'), 100, 1, 'cm')} from the last waypoint"

    row("landed", landed)


def print_summary(console, summary: dict[str, Any]) -> None:
    """The short table printed at the end of a flight (from its ``summary.json`` content)."""
    from rich.table import Table

    vehicles = summary.get("vehicles") or [summary]
    many = len(vehicles) > 1
    table = Table(title="flight summary", show_edge=False, pad_edge=False)
    table.add_column("figure")
    for i in range(len(vehicles)):
        table.add_column(f"vehicle {i + 1}" if many else "value", justify="right")

    def row(name: str, pick) -> None:
        table.add_row(name, *(pick(v) for v in vehicles))

    def flight(v, key):
        return (v.get("flight") or {}).get(key)

    row("hover height error RMS", lambda v: _fmt(flight(v, "hover_rms_m"), 100, 2, "cm"))
    row("hover height error max", lambda v: _fmt(flight(v, "hover_max_m"), 100, 2, "cm"))
    row("overshoot", lambda v: _fmt(flight(v, "overshoot_m"), 100, 2, "cm"))
    for axis in ("roll", "pitch", "yaw"):
        row(f"{axis} tracking RMS", lambda v, a=axis: _fmt((flight(v, "tracking_rms_deg") or {}).get(a), 1, 2, "deg"))
    steps = (vehicles[0].get("flight") or {}).get("step_rise_s") or []
    for j, step in enumerate(steps):
        if step["time_s"] >= summary["simulated_s"]:
            continue
        row(
            f"{step['axis']} step at {step['time_s']:g} s: 90 % after",
            lambda v, j=j: _fmt(((v.get("flight") or {}).get("step_rise_s") or [{}] * (j + 1))[j].get("rise_s"),
                                1000, 0, "ms"),
        )  # fmt: skip
    row("attitude estimate RMS", lambda v: _fmt(flight(v, "attitude_estimate_rms_deg"), 1, 2, "deg"))
    row("height estimate RMS", lambda v: _fmt(flight(v, "height_estimate_rms_m"), 100, 2, "cm"))
    if vehicles[0].get("mission"):
        _mission_rows(row)
    if vehicles[0].get("tasks"):
        for task in vehicles[0]["tasks"]:

            def figures(v, task=task):
                return (v.get("tasks") or {}).get(task) or {}

            row(f"{task} jobs", lambda v, f=figures: str(f(v).get("jobs", "n/a")))
            row(
                f"{task} response mean / max",
                lambda v, f=figures: (
                    f"{_fmt(f(v).get('response_us_mean'), 1, 1)} / {_fmt(f(v).get('response_us_max'), 1, 1)} us"
                ),
            )
            row(f"{task} cycles per job (mean)", lambda v, f=figures: _fmt(f(v).get("exec_cycles_mean"), 1, 0))
            row(f"{task} energy per job (mean)", lambda v, f=figures: _fmt(f(v).get("energy_nj_mean"), 1, 1, "nJ"))
        row("deadline misses", lambda v: str(v.get("deadline_misses")))
        row("chip energy", lambda v: _fmt((v.get("energy") or {}).get("total_uj"), 1e-3, 2, "mJ"))
    if vehicles[0].get("power"):  # a battery flight (docs/power.md)

        def power(v) -> dict[str, Any]:
            return v.get("power") or {}

        row("energy from the pack", lambda v: _fmt((power(v).get("energy_j") or {}).get("total"), 1, 1, "J"))
        row("chip share of it", lambda v: _fmt(power(v).get("chip_share"), 100, 4, "%"))
        row("state of charge at the end", lambda v: _fmt((power(v).get("pack") or {}).get("final_soc"), 1, 4))
        row(
            "hover endurance to the reserve",
            lambda v: (
                f"{_fmt((power(v).get('endurance') or {}).get('hover_s'), 1 / 60, 1, 'min')} at "
                f"{_fmt(power(v).get('mean_power_w'), 1, 1, 'W')}"
            ),
        )
        if any(power(v).get("failsafe") for v in vehicles):
            row("low-battery failsafe", lambda v: str((power(v).get("failsafe") or {}).get("outcome") or "no"))
        if any(power(v).get("after_empty") for v in vehicles):
            row("pack empty", lambda v: str(power(v).get("after_empty") or "no"))
    console.print(table)
    for i, v in enumerate(vehicles):
        quiet = v.get("no_actuator_command")
        if quiet:
            who = f"vehicle {i + 1}: " if many else ""
            plain(
                console,
                f"{who}no actuator command for {quiet['seconds']:.2f} s from t = {quiet['from_s']:.2f} s "
                f"({quiet['periods']} sensor periods; the motors held the last command)",
            )
    status = "" if summary.get("complete", True) else f" (incomplete: {summary.get('stopped')})"
    extra = f"; closest approach {_fmt(summary.get('min_separation_m'), 1, 2, 'm')}" if many else ""
    plain(
        console,
        f"real-time factor {_fmt(summary['real_time_factor'], 1, 2)} ({summary['simulated_s']:g} s simulated in "
        f"{summary['host_s']:.1f} s){extra}{status}",
    )


# --- the live Foxglove server (docs/results-logs.md) ---


def _start_live(console, port: int | None):
    if port is None:
        return None
    from robosoc.outputs.foxglove_live import LiveFlight, LiveFlightError

    try:
        live = LiveFlight(port)
    except LiveFlightError as exc:
        raise options.fail("--foxglove", str(exc)) from exc
    plain(console, f"foxglove: {live.url} (Foxglove: Open connection, Foxglove WebSocket)")
    return live


def _live_rows(live):
    """The rows of vehicle 1 to the live server (None: no server)."""
    if live is None:
        return None

    def on_row(vehicle: int, row, telemetry) -> None:
        if vehicle == 0:
            live.publish(row, telemetry)

    return on_row
