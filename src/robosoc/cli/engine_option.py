"""The ``--engine`` option of ``run``, ``fly`` and ``bench``: how the simulator executes the cores' code."""

from __future__ import annotations

from typing import Annotated

import typer

from robosoc.cli import options
from robosoc.jit import DEFAULT_ENGINE, ENGINES

ENGINE_HELP = (
    "interp: the interpreter; jit: translate code to native code at first use; auto: translate the code that "
    "turns hot.  The same cycles, counters and outputs with each (docs/translation.md)."
)

Engine = Annotated[
    str | None,
    typer.Option("--engine", help=f"{ENGINE_HELP}  [default: {DEFAULT_ENGINE}, or the chip file's]",
                 show_default=False, callback=options.choice(*ENGINES)),
]  # fmt: skip
"""``None``: not given (the chip configuration's engine, :data:`DEFAULT_ENGINE` by default)."""

__all__ = ["ENGINE_HELP", "Engine"]
