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
ScenarioOpt = Annotated[
    Path | None, typer.Option(help="Scenario TOML file (default: built-in; robosoc scenario show prints every field).")
]
Vehicle = Annotated[
    str | None,
    typer.Option(help="default or laser (default: the scenario's).", callback=options.choice(*VEHICLE_PRESETS)),
]

__all__ = ["DURATION_HELP", "Arith", "Duration", "Mul", "ScenarioOpt", "SecondsAlias", "Seed", "Vehicle"]
