"""The options that override a scenario's fields, shared by ``robosoc fly`` and ``robosoc serve``."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from robosoc.cli import options
from robosoc.config.firmware import ARITH_CHOICES
from robosoc.config.vehicle import VEHICLE_PRESETS

Arith = Annotated[
    str | None,
    typer.Option(
        help="Firmware arithmetic: float (soft-float) or fixed (Q16.16) (default: the scenario's, fixed).",
        callback=options.choice(*ARITH_CHOICES),
    ),
]
Mul = Annotated[
    bool | None,
    typer.Option(
        "--mul/--no-mul",
        help="Firmware built for cores with the multiplier or without (default: the scenario's, with).",
    ),
]
DURATION_HELP = (
    "Flight length in seconds, whole ms in 0.001..3600, at least one sensor period (default: the scenario's)."
)
Duration = Annotated[
    float | None,
    typer.Option(help=DURATION_HELP, callback=options.float_range(0.001, 3600.0, unit="s")),
]
SecondsAlias = Annotated[
    float | None,
    typer.Option(help=DURATION_HELP, callback=options.float_range(0.001, 3600.0, unit="s"), hidden=True),
]
Seed = Annotated[
    int | None,
    typer.Option(
        help="Seeds every random number (noise, biases, gusts), 0..2**63-1 (default: the scenario's, 1).",
        callback=options.seed(),
    ),
]
SCENARIO_HELP = "Scenario TOML file (default: built-in; robosoc scenario show prints every field)."
ScenarioArg = Annotated[Path | None, typer.Argument(metavar="SCENARIO", help=SCENARIO_HELP, show_default=False)]
ScenarioOpt = Annotated[Path | None, typer.Option(help=SCENARIO_HELP)]
ScenarioAlias = Annotated[Path | None, typer.Option("--scenario", help=SCENARIO_HELP, hidden=True)]
Vehicle = Annotated[
    str | None,
    typer.Option(help="default or laser (default: the scenario's).", callback=options.choice(*VEHICLE_PRESETS)),
]


def scenario_source(option: Path | None, argument: Path | None) -> tuple[Path | None, str | None]:
    """The scenario file given as SCENARIO or as ``--scenario`` (not both), and the label its errors
    carry (None: the file name alone)."""
    options.exclusive(scenario=option is not None, SCENARIO=argument is not None)
    return (option, "--scenario") if option is not None else (argument, None)


def duration_change(duration: float | None, seconds: float | None) -> tuple[str, float] | None:
    """(the option as typed, its value) of ``--duration`` or its alias ``--seconds`` (not both)."""
    options.exclusive(duration=duration is not None, seconds=seconds is not None)
    if duration is not None:
        return "--duration", duration
    return ("--seconds", seconds) if seconds is not None else None


__all__ = [
    "DURATION_HELP", "SCENARIO_HELP", "Arith", "Duration", "Mul", "ScenarioAlias", "ScenarioArg", "ScenarioOpt",
    "SecondsAlias", "Seed", "Vehicle", "duration_change", "scenario_source",
]  # fmt: skip
