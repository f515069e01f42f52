"""The ``--engine`` option of ``run``, ``fly`` and ``bench``: how the simulator executes the cores' code."""

from __future__ import annotations

from typing import Annotated

import typer

from robosoc.cli import options
from robosoc.config.chip import DEFAULT_CHIP_ENGINE
from robosoc.jit import DEFAULT_ENGINE, ENGINES

ENGINE_HELP = (
    "interp: the interpreter; jit: translate code to native code at first use; auto: translate the code that "
    "turns hot.  The same cycles, counters and outputs with each (docs/translation.md)."
)

ENGINE_DEFAULTS = f"Default: {DEFAULT_ENGINE} on one core; on a chip the chip file's, else {DEFAULT_CHIP_ENGINE}."

Engine = Annotated[
    str | None,
    typer.Option("--engine", help=f"{ENGINE_HELP}  {ENGINE_DEFAULTS}", show_default=False,
                 callback=options.choice(*ENGINES)),
]  # fmt: skip
"""``None``: not given (one core: :data:`DEFAULT_ENGINE`; a chip: its configuration's engine)."""

__all__ = ["ENGINE_HELP", "Engine"]
