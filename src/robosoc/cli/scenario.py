"""``robosoc scenario show``: the resolved scenario as TOML, to copy and edit; scenario files for ``fly``."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from robosoc.cli import exit_codes
from robosoc.cli.scenario_flags import Firmware
from robosoc.cli.typer_apps import RobosocGroup, app

if TYPE_CHECKING:
    from robosoc.config.scenario import ScenarioConfig

scenario_app = typer.Typer(
    cls=RobosocGroup,
    help="Scenarios: what robosoc fly flies (vehicles, wind, flight plan, controller, firmware, chip).",
    epilog=exit_codes.EPILOG,
    no_args_is_help=True,
)
app.add_typer(scenario_app, name="scenario")


def load_scenario(
    path: Path | None, label: str | None, firmware: str | None = None
) -> tuple[ScenarioConfig, tuple[str, ...]]:
    """The scenario of ``path`` merged into the built-in default (the default itself for None) and
    the defaults of the project it flies (``firmware``, as ``--firmware``, or the file's), and the
    dotted fields the file sets.  Errors name ``label`` (the option, or None for an argument), the
    file and the field."""
    from robosoc.cli.scenario_flags import ScenarioFlags, resolve

    resolved = resolve(ScenarioFlags(path, label, {"firmware": firmware} if firmware is not None else {}))
    named = next((fields for source, fields in resolved.sources if source == str(path)), ())
    return resolved.config, named


@scenario_app.command("show", epilog=exit_codes.EPILOG)
def scenario_show(
    file: Annotated[
        Path | None,
        typer.Argument(
            metavar="FILE", help="A scenario TOML file (it may name only the fields it changes); default: built-in."
        ),
    ] = None,
    firmware: Firmware = None,
) -> None:
    """Print the resolved scenario, every field, as TOML: save it, edit it, fly it with robosoc fly FILE."""
    from robosoc.config.scenario import scenario_toml

    config, _ = load_scenario(file, None, firmware)
    typer.echo(scenario_toml(config), nl=False)
