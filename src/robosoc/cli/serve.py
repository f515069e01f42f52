"""``robosoc serve physics`` and ``robosoc serve chip``: the two sides of the decoupled mode.

Thin over :func:`robosoc.outputs.decoupled_flight.run_physics_side` and
:func:`robosoc.outputs.decoupled_flight.run_chip_side` (docs/decoupled.md).  Start the physics side first;
both sides take the same scenario options (the physics side refuses a chip built for another).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from robosoc.cli import exit_codes, files, link_options, options
from robosoc.cli.console import make_console, note, plain
from robosoc.cli.errors import CliError
from robosoc.cli.link_options import DEFAULT_BIND, Bind, ConnectTimeout, Faults, Hold, Pace, PeerTimeout, Resend
from robosoc.cli.link_report import end_of_side, print_link_counts
from robosoc.cli.project_check import check_project
from robosoc.cli.scenario_flags import (
    SERVE_CHIP,
    SERVE_PHYSICS,
    ResolvedScenario,
    ScenarioFlags,
    resolve,
    takes_scenario,
)
from robosoc.cli.typer_apps import RobosocGroup, app

if TYPE_CHECKING:
    from robosoc.config.vehicle import VehicleConfig

serve_app = typer.Typer(
    cls=RobosocGroup,
    help="The decoupled mode's two sides as separate programs talking UDP (start the physics first).",
    epilog=exit_codes.SERVE_EPILOG,
    no_args_is_help=True,
)
app.add_typer(serve_app, name="serve")

NoOut = Annotated[bool, typer.Option("--no-out", help="Write no files.")]
Ros = Annotated[
    bool,
    typer.Option(
        "--ros",
        help="Be a ROS 1 node (hector_quadrotor's topics through the master at ROS_MASTER_URI) instead of "
        "a UDP peer (docs/ros.md).",
    ),
]


def _namespace(ctx: typer.Context, param: typer.CallbackParam, value: str) -> str:
    if getattr(ctx, "resilient_parsing", False):
        return value
    import re

    text = value.strip()
    if not text:
        raise CliError("--ns: empty: give a ROS namespace such as /uav1 (/ for none)")
    if not text.startswith("/"):
        text = "/" + text
    if not re.fullmatch(r"/|(/[A-Za-z][A-Za-z0-9_]*)+/?", text):
        raise CliError(f"--ns: not a ROS namespace such as /uav1, got {value!r}")
    return text.rstrip("/") or "/"


Namespace = Annotated[
    str,
    typer.Option(
        "--ns",
        metavar="NS",
        help="With --ros: the vehicle's namespace (/ for one vehicle, /uav1, /uav2 ... for a fleet).",
        callback=_namespace,
    ),
]


def _no_udp_options(ros: bool, **given: bool) -> None:
    """Refuse the UDP link's options with --ros (they would be silently ignored)."""
    if ros:
        for name, on in given.items():
            if on:
                raise options.fail(f"--{name.replace('_', '-')}", "is an option of the UDP link, not of --ros")


def _ros_failed(exc: Exception) -> CliError:
    return CliError(str(exc))


Peer = Annotated[
    link_options.Address | None,
    typer.Option(
        parser=str,
        metavar="HOST:PORT",
        help=f"The physics side's address (default {DEFAULT_BIND}).",
        callback=link_options.address_option(any_port=False),
    ),
]


def resolve_side(flags: ScenarioFlags) -> tuple[ResolvedScenario, VehicleConfig]:
    """The scenario of a side, resolved as ``robosoc fly`` resolves it, and its vehicle."""
    from robosoc.config.vehicle import vehicle_preset

    resolved = resolve(flags)
    return resolved, vehicle_preset(resolved.config.vehicle)


def _out(out: Path | None, no_out: bool, side: str, name: str, seed: int, scenario: Path | None) -> Path | None:
    options.exclusive(out=out is not None, no_out=no_out)
    if no_out:
        return None
    from robosoc.outputs import run_folder as rf

    written = (rf.FLIGHT_CSV, rf.PHYSICS_JSON, rf.LINK_PHYSICS_LOG, rf.JOBS_CSV, rf.CHIP_JSON, rf.LINK_CHIP_LOG)
    return files.output_dir(
        out or Path("runs") / f"serve-{side}-{name}-s{seed}",
        "--out",
        inputs=[scenario] if scenario else (),
        names=written,  # what either side writes in it (docs/decoupled.md): no device, FIFO or socket
    )


@serve_app.command("physics", epilog=exit_codes.SERVE_EPILOG)
@takes_scenario(SERVE_PHYSICS, scenario_option_hidden=True)
def serve_physics_command(
    flags: ScenarioFlags,
    out: Annotated[
        Path | None,
        typer.Option(
            help="Folder for flight.csv, physics.json, link-physics.log (default: runs/serve-physics-NAME-sSEED)."
        ),
    ] = None,
    no_out: NoOut = False,
    bind: Bind = None,
    pace: Pace = "realtime",
    hold: Hold = "zoh",
    faults: Faults = None,
    resend: Resend = 2,
    peer_timeout: PeerTimeout = 5.0,
    connect_timeout: ConnectTimeout = 300.0,
    ros: Ros = False,
    start_delay: Annotated[
        float,
        typer.Option(
            help="With --ros: seconds between the chips' arrival and the first sample, for recorders "
            "(rosbag record -a) to subscribe first, 0..600.",
            callback=options.float_range(0.0, 600.0, unit="s"),
        ),
    ] = 0.0,
) -> None:
    """The physics side: fly the scenario, sending sensor readings to a chip side and applying its commands."""
    from rich.markup import escape
    from rich.progress import BarColumn, Progress, TextColumn

    from robosoc.cosim.link import LinkError, parse_address
    from robosoc.outputs.decoupled_flight import run_physics_side

    console = make_console()
    resolved, craft = resolve_side(flags)
    config, seed = resolved.config, resolved.config.seed
    _no_udp_options(ros, bind=bind is not None, faults=faults is not None)
    what = "a ROS physics node" if ros else "the decoupled mode"  # it logs the project's telemetry
    check_project(config, resolved.source_of("firmware.project"), sends=("sensor",), what=what)
    link = link_options.link_config(pace, hold, faults, resend, peer_timeout, connect_timeout)
    folder = _out(out, no_out, "physics", config.name, seed, resolved.path)
    if not ros and start_delay:
        raise options.fail("--start-delay", "is an option of --ros")
    if ros:
        _serve_physics_ros(console, resolved, link, folder, start_delay)
        return
    if config.vehicles > 1:
        _serve_physics_fleet(console, resolved, link, bind or parse_address(DEFAULT_BIND, any_port=True), folder)
        return
    address = bind or parse_address(DEFAULT_BIND, any_port=True)
    samples = config.samples
    progress = Progress(
        TextColumn("{task.description}"), BarColumn(), TextColumn("{task.fields[t]}"), console=console, transient=True
    )
    task = progress.add_task("waiting for a chip", total=samples, t="")

    def on_listen(a) -> None:
        console.print(
            f"physics: scenario [bold]{escape(config.name)}[/bold], {config.duration_s:g} s, seed {seed}, "
            f"pace {pace}, hold {hold}; listening on {escape(str(a))}"
        )
        progress.start()

    def on_sample(done: int, total: int) -> None:
        progress.update(task, completed=done, description="flight", t=f"{done / config.sensors.rate_hz:.2f} s")

    try:
        try:
            outcome, record = run_physics_side(
                config, craft, link, address, folder, on_listen=on_listen, on_sample=on_sample
            )  # fmt: skip
        finally:
            progress.stop()
    except LinkError as exc:
        raise options.fail("--bind", str(exc)) from None
    f = record["flight"]
    if f and math.isfinite(f["hover_rms_m"]):
        console.print(
            f"hover height error (RMS, after the climb): {f['hover_rms_m'] * 100:.2f} cm "
            f"(max {f['hover_max_m'] * 100:.2f} cm)"
        )
    c = outcome.commands
    console.print(
        f"flown {outcome.simulated_s:g} of {config.duration_s:g} s in {outcome.host_s:.1f} s; "
        f"commands {c['received']}, late {c['late']}, missed {c['missed']}; "
        f"largest lag behind real time {outcome.max_lag_s * 1000:.0f} ms"
    )
    print_link_counts(console, {"to chip": record["link"]["to_chip"], "from chip": record["link"]["from_chip"]})
    if folder is not None:
        plain(console, f"files: {folder}")
    end_of_side(outcome.ended, outcome.message, str(folder) if folder else "")


@serve_app.command("chip", epilog=exit_codes.SERVE_EPILOG)
@takes_scenario(SERVE_CHIP, scenario_option_hidden=True)
def serve_chip_command(
    flags: ScenarioFlags,
    peer: Peer = None,
    bind: Annotated[
        link_options.Address | None,
        typer.Option(
            parser=str,
            metavar="HOST:PORT",
            help="The address to listen on (default: any free port).",
            callback=link_options.address_option(any_port=True),
        ),
    ] = None,
    out: Annotated[
        Path | None,
        typer.Option(help="Folder for jobs.csv, chip.json, link-chip.log (default: runs/serve-chip-NAME-sSEED)."),
    ] = None,
    no_out: NoOut = False,
    faults: Faults = None,
    resend: Resend = 2,
    peer_timeout: PeerTimeout = 5.0,
    connect_timeout: ConnectTimeout = 300.0,
    ros: Ros = False,
    ns: Namespace = "/",
) -> None:
    """The chip side: run the firmware on the chip for a physics side, over UDP (or as a ROS 1 node)."""
    from robosoc.cosim.link import LinkError, parse_address
    from robosoc.outputs.decoupled_flight import run_chip_side

    console = make_console()
    resolved, craft = resolve_side(flags)
    config, seed = resolved.config, resolved.config.seed
    _no_udp_options(ros, peer=peer is not None, bind=bind is not None, faults=faults is not None)
    if not ros and ns != "/":
        raise options.fail("--ns", "is an option of --ros")
    what = "a ROS chip node" if ros else "the decoupled mode"  # both are sent the sensor packets only
    check_project(config, resolved.source_of("firmware.project"), sends=("sensor",), what=what)
    link = link_options.link_config(
        faults=faults, resend=resend, peer_timeout=peer_timeout, connect_timeout=connect_timeout
    )
    folder = _out(out, no_out, "chip", config.name, seed, resolved.path)
    target = peer or parse_address(DEFAULT_BIND, any_port=False)
    say = lambda text: note(console, f"chip: {text}")  # noqa: E731
    try:
        if ros:
            from robosoc.cosim.ros1 import RosUnavailable
            from robosoc.outputs.ros_sides import run_ros_chip_side

            try:
                outcome, record = run_ros_chip_side(config, craft, link, ns, folder, on_status=say)
            except RosUnavailable as exc:
                raise _ros_failed(exc) from None
        else:
            outcome, record = run_chip_side(config, craft, link, target, bind, folder, on_status=say)
    except LinkError as exc:
        raise options.fail("--bind" if bind is not None and str(bind) in str(exc) else "--peer", str(exc)) from None
    except ValueError as exc:
        raise CliError(str(exc)) from None
    for name, t in record.get("tasks", {}).items():
        console.print(
            f"  {name:<9} {t['jobs']} jobs: response mean {t['response_us_mean']:.1f} us, "
            f"max {t['response_us_max']:.1f} us; "
            f"deadline misses {t['deadline_misses']}"
        )
    r = outcome.readings
    if r:
        console.print(
            f"readings {r['received']}, injected {r['injected']}, late {r['late']}, stale {r['stale']}; "
            f"commands sent {r['commands_sent']}; chip time {outcome.simulated_s:g} s in {outcome.host_s:.1f} s"
        )
    if ros:
        for topic, counts in record["link"]["from_physics"].items():
            console.print(f"  {topic}: " + ", ".join(f"{name} {value}" for name, value in counts.items()))
    else:
        print_link_counts(
            console, {"to physics": record["link"]["to_physics"], "from physics": record["link"]["from_physics"]}
        )
    if folder is not None:
        plain(console, f"files: {folder}")
    end_of_side(outcome.ended, outcome.message, str(folder) if folder else "")


def _serve_physics_ros(console, resolved: ResolvedScenario, link, folder: Path | None, start_delay: float) -> None:
    """``serve physics --ros``: the physics node, its figures per vehicle, its end."""
    from robosoc.cosim.ros1 import RosUnavailable
    from robosoc.outputs.ros_sides import run_ros_physics_side

    config = resolved.config
    console.print(
        f"physics (ROS 1): scenario {config.name}, {config.duration_s:g} s, seed {config.seed}, "
        f"{config.vehicles} vehicle(s), pace {link.pace}; waiting for the chip node(s) ..."
    )
    try:
        outcomes, records = run_ros_physics_side(config, link, folder, start_delay_s=start_delay)
    except RosUnavailable as exc:
        raise _ros_failed(exc) from None
    names = [str(record["namespace"]) for record in records]
    _print_fleet(console, config, outcomes, records, names, with_host_time=True, folder=folder)


def _print_fleet(console, config, outcomes, records, names, *, with_host_time: bool, folder: Path | None) -> None:
    """One line per vehicle of a fleet's physics side (flown time, hover, commands), its files, and
    the side's end (the first vehicle's)."""
    for name, outcome, record in zip(names, outcomes, records, strict=True):
        f = record["flight"]
        hover = (
            f"hover RMS {f['hover_rms_m'] * 100:.2f} cm (max {f['hover_max_m'] * 100:.2f} cm)"
            if f and math.isfinite(f["hover_rms_m"])
            else "no hover figures"
        )
        c = outcome.commands
        took = f" in {outcome.host_s:.1f} s" if with_host_time else ""
        console.print(
            f"  {name}: flown {outcome.simulated_s:g} of {config.duration_s:g} s{took}; {hover}; "
            f"commands {c['received']}, late {c['late']}, missed {c['missed']}"
        )
    if folder is not None:
        plain(console, f"files: {folder}")
    end_of_side(outcomes[0].ended, outcomes[0].message, str(folder) if folder else "")


def _serve_physics_fleet(console, resolved: ResolvedScenario, link, bind, folder: Path | None) -> None:
    """``serve physics --vehicles N`` over UDP: one link per vehicle on consecutive ports."""
    from robosoc.cosim.link import LinkError
    from robosoc.outputs.decoupled_flight import run_physics_fleet_side

    config = resolved.config

    def on_listen(addresses) -> None:
        console.print(
            f"physics: scenario {config.name}, {config.duration_s:g} s, seed {config.seed}, {config.vehicles} "
            f"vehicles, pace {link.pace}; listening on " + ", ".join(str(a) for a in addresses) + " (one chip each)"
        )

    try:
        outcomes, part = run_physics_fleet_side(config, link, bind, folder, on_listen=on_listen)
    except LinkError as exc:
        raise options.fail("--bind", str(exc)) from None
    names = [f"vehicle {i + 1}" for i in range(len(outcomes))]
    _print_fleet(console, config, outcomes, part["vehicles"], names, with_host_time=False, folder=folder)
