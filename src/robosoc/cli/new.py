"""``robosoc new DIR [--template NAME]``: a firmware project to start from, ready to fly.

The templates are ordinary projects shipped in ``robosoc/firmware/templates/`` (docs/firmware-projects.md):
``blank`` (one task: estimator and PID in one job on one tile), ``quadrotor`` (the seed's two
tasks on two tiles, messages between them over the NoC) and ``position`` (three tasks on three
tiles flying a waypoint mission: its robosoc.toml's ``[scenario]`` defaults).
"""

from __future__ import annotations

import shutil
from pathlib import Path
from typing import Annotated

import typer

from robosoc.cli import exit_codes, options
from robosoc.cli.console import make_console, plain
from robosoc.cli.errors import CliError
from robosoc.cli.typer_apps import app
from robosoc.firmware import TEMPLATES_DIR

TEMPLATES = tuple(sorted(p.name for p in TEMPLATES_DIR.iterdir() if (p / "robosoc.toml").is_file()))


@app.command("new", epilog=exit_codes.EPILOG)
def new_command(
    folder: Annotated[
        Path, typer.Argument(metavar="DIR", help="The project's folder (created; must not exist or be empty).")
    ],
    template: Annotated[
        str,
        typer.Option(help=f"What to start from: {', '.join(TEMPLATES)}.", callback=options.choice(*TEMPLATES)),
    ] = "blank",
) -> None:
    """Make a firmware project in DIR from a template: its robosoc.toml (tasks, tiles, messages,
    builds) and C sources, ready to fly with robosoc fly --firmware DIR."""
    if folder.exists() and not folder.is_dir():
        raise options.fail("DIR", f"{folder} exists and is not a folder")
    if folder.is_dir() and any(folder.iterdir()):
        raise options.fail("DIR", f"{folder} is not empty: choose a new folder (nothing was written)")
    try:
        shutil.copytree(TEMPLATES_DIR / template, folder, dirs_exist_ok=True)
    except OSError as exc:
        raise CliError(f"DIR: cannot write {folder}: {exc.strerror or exc}") from exc
    console = make_console()
    plain(console, f"made project {folder} from the {template} template:")
    for path in sorted(p for p in folder.rglob("*") if p.is_file()):
        plain(console, f"  {path.relative_to(folder)}")
    plain(console, f"fly it: robosoc fly --firmware {folder}   (docs/firmware-projects.md)")
