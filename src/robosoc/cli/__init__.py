"""Command line: one module per command, each a thin typed function over the library.

The rules every command follows (option checks, files, exit codes, errors) and the helpers that
implement them are described in docs/cli.md.

The command ``robosoc X`` (or the group ``robosoc X ...``) is registered by the module
``robosoc.cli.X``, named in :data:`COMMANDS`.  The console script imports only the module of the
command it was given (``robosoc new`` loads no simulator, ``robosoc fly`` no sweep, report or
server code); ``robosoc --help``, an unknown command, and ``from robosoc.cli import app`` (tests,
notebooks) import them all, in the order of :data:`COMMANDS`.

Ctrl-C while the commands are being imported (a second or two) ends with ``robosoc: interrupted``
and 130, as it does later, and not with a traceback from whatever module was loading; once a
command has ended (its message printed), a late Ctrl-C no longer changes the exit code.
"""

from __future__ import annotations

import importlib
import signal
import sys
from collections.abc import Sequence
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    import typer

#: every top-level command and group, each registered by the module of its name, in help order
COMMANDS = ("bench", "cc", "firmware", "fly", "new", "profile", "report", "run", "scenario", "serve", "sweep", "table")


def commands_for(args: Sequence[str]) -> tuple[str, ...]:
    """The command modules a command line needs: its command's alone, or all of them when the line
    names none of them (help, an unknown or misspelt command, no argument)."""
    if args and args[0] in COMMANDS:
        return (args[0],)
    return COMMANDS


def application(commands: Sequence[str] = COMMANDS) -> typer.Typer:
    """The robosoc application with ``commands`` registered (importing a module twice does nothing)."""
    for name in commands:
        importlib.import_module(f"robosoc.cli.{name}")
    from robosoc.cli.typer_apps import app

    return app


def __getattr__(name: str) -> typer.Typer:
    if name == "app":
        return application()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def main() -> None:
    """Entry point of the ``robosoc`` console script."""
    try:
        app = application(commands_for(sys.argv[1:]))
    except KeyboardInterrupt:
        sys.stderr.write("robosoc: interrupted\n")
        raise SystemExit(130) from None
    try:
        app()
    finally:  # the command is over and has said so: a Ctrl-C now would only turn its exit code into -2
        signal.signal(signal.SIGINT, signal.SIG_IGN)


__all__ = ["COMMANDS", "application", "commands_for", "main"]
