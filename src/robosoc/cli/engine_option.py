"""The ``--engine`` option of ``run``, ``fly`` and ``bench``: how the simulator executes the cores' code."""

from __future__ import annotations

from typing import Annotated

import typer

from robosoc.cli import options
from robosoc.config.chip import DEFAULT_CHIP_ENGINE, DEFAULT_ENGINE, engine_name

ENGINE_HELP = (
    "interp: the interpreter; jit: translate code to native code at first use; auto: translate the code that "
    "turns hot.  The same cycles, counters and outputs with each (docs/translation.md)."
)

ENGINE_DEFAULTS = f"Default: {DEFAULT_ENGINE} on one core; on a chip the chip file's, else {DEFAULT_CHIP_ENGINE}."

check_engine = options.checked(lambda name, value: engine_name(value, name, quote=False))
"""The callback of every ``--engine`` option: the one check of an engine's name, in the command line's words."""

Engine = Annotated[
    str | None,
    typer.Option("--engine", help=f"{ENGINE_HELP}  {ENGINE_DEFAULTS}", show_default=False, callback=check_engine),
]  # fmt: skip
"""``None``: not given (one core: :data:`DEFAULT_ENGINE`; a chip: its configuration's engine)."""

__all__ = ["ENGINE_HELP", "Engine", "check_engine"]
