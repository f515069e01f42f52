"""The decoupled mode's command-line options, shared by ``robosoc serve physics|chip`` and
``robosoc fly --decoupled``, the :class:`~robosoc.config.link.LinkConfig` they make, and fly's
check of them (:func:`link_of`: a lockstep flight does not import the decoupled mode)."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

from robosoc.cli import options
from robosoc.cli.errors import CliError
from robosoc.config.link import (
    FAULT_NAMES,
    HOLD_CHOICES,
    MAX_RESEND,
    PACE_CHOICES,
    LinkConfig,
    LinkFaults,
    parse_faults,
)
from robosoc.cosim.link import Address, parse_address

if TYPE_CHECKING:
    from robosoc.cli.scenario_flags import ScenarioFlags

__all__ = [
    "DEFAULT_PORT",
    "Address",
    "Bind",
    "ConnectTimeout",
    "Faults",
    "Hold",
    "Pace",
    "PeerTimeout",
    "Resend",
    "address_option",
    "link_config",
    "link_of",
]

#: Where ``robosoc serve physics`` listens and ``robosoc serve chip`` sends by default.
DEFAULT_PORT = 47800
DEFAULT_BIND = f"127.0.0.1:{DEFAULT_PORT}"


def address_option(*, any_port: bool) -> Any:
    """Callback: ``HOST:PORT`` (port 0 allowed with ``any_port``) -> :class:`Address`."""

    def callback(ctx: typer.Context, param: typer.CallbackParam, value: str | None) -> Address | None:
        if value is None or getattr(ctx, "resilient_parsing", False):
            return None
        try:
            return parse_address(value, any_port=any_port)
        except ValueError as exc:
            raise CliError(f"{options.option_name(param)}: {exc}") from None

    return callback


def _faults(ctx: typer.Context, param: typer.CallbackParam, value: str | None) -> LinkFaults | None:
    if value is None or getattr(ctx, "resilient_parsing", False):
        return None
    try:
        return parse_faults(value)
    except ValueError as exc:
        raise CliError(f"{options.option_name(param)}: {exc}") from None


Pace = Annotated[
    str,
    typer.Option(
        help="realtime: the physics keeps to the wall clock; fast: as fast as the chip allows.",
        callback=options.choice(*PACE_CHOICES),
    ),
]
Hold = Annotated[
    str,
    typer.Option(
        help="Between actuator commands: zoh holds the newest, linear ramps to each over the command interval.",
        callback=options.choice(*HOLD_CHOICES),
    ),
]
Faults = Annotated[
    LinkFaults | None,
    typer.Option(
        parser=str,
        metavar="NAME=RATE,...",
        help=(
            "Inject faults on the datagrams sent (by this side; with fly --decoupled by both), "
            f"rates 0..1 ({', '.join(FAULT_NAMES)}); "
            "seeded by --seed. Example: loss=0.1,duplicate=0.05,reorder=0.05."
        ),
        callback=_faults,
    ),
]
Resend = Annotated[
    int,
    typer.Option(
        help=f"Each datagram repeats this many earlier readings or commands, 0..{MAX_RESEND} (against loss).",
        callback=options.int_range(0, MAX_RESEND),
    ),
]
PeerTimeout = Annotated[
    float,
    typer.Option(
        help="End (exit code 5) when the other side has been silent this long, 0.05..3600 s.",
        callback=options.float_range(0.05, 3600.0, unit="s"),
    ),
]
ConnectTimeout = Annotated[
    float,
    typer.Option(
        help="Wait this long for the other side's first datagram, 0.05..3600 s (a fresh chip side compiles first).",
        callback=options.float_range(0.05, 3600.0, unit="s"),
    ),
]
Bind = Annotated[
    Address | None,
    typer.Option(
        parser=str,
        metavar="HOST:PORT",
        help="The address to listen on (port 0: any free port).",
        callback=address_option(any_port=True),
    ),
]


def link_config(
    pace: str = LinkConfig.pace,
    hold: str = LinkConfig.hold,
    faults: LinkFaults | None = None,
    resend: int = LinkConfig.resend,
    peer_timeout: float = LinkConfig.peer_timeout_s,
    connect_timeout: float = LinkConfig.connect_timeout_s,
) -> LinkConfig:
    """The link configuration of the options (errors name the option; the defaults are LinkConfig's)."""
    try:
        return LinkConfig(
            pace=pace,
            hold=hold,
            faults=faults or LinkFaults(),
            resend=resend,
            peer_timeout_s=peer_timeout,
            connect_timeout_s=connect_timeout,
        )
    except ValueError as exc:
        field = str(exc).split(":", 1)[0]
        option = {"peer_timeout_s": "--peer-timeout", "connect_timeout_s": "--connect-timeout"}
        raise options.fail(option.get(field, f"--{field}"), str(exc).split(": ", 1)[-1]) from None


#: fly's options that only the decoupled mode takes (option -> parameter name).
LINK_OPTIONS = {
    "--pace": "pace",
    "--hold": "hold",
    "--faults": "faults",
    "--resend": "resend",
    "--peer-timeout": "peer_timeout",
    "--bind": "bind",
}


def link_of(
    ctx: typer.Context,
    decoupled: bool,
    flags: ScenarioFlags,
    *,
    video: Path | None,
    foxglove: int | None,
    profile: bool,
) -> LinkConfig | None:
    """The link of ``fly --decoupled`` from fly's link options (None without ``--decoupled``, when
    those options are refused), and the options the decoupled mode cannot take refused."""
    given = {name: options.given(ctx, name) for name in LINK_OPTIONS.values()}
    if not decoupled:
        for option, name in LINK_OPTIONS.items():
            if given[name]:
                raise options.fail(option, "only with --decoupled")
        return None
    controller = flags.values.get("controller")
    if controller is not None and controller != "chip":
        raise options.fail("--decoupled", "the decoupled mode flies the firmware on the chip (drop --controller host)")
    for option, on in (("--video", video is not None), ("--foxglove", foxglove is not None)):
        if on:
            raise options.fail(option, "not with --decoupled (the physics runs in another process)")
    if profile:
        raise options.fail("--profile", "not with --decoupled (profile its run folder with robosoc profile)")
    p = ctx.params
    return link_config(p["pace"], p["hold"], p["faults"], p["resend"], p["peer_timeout"])
