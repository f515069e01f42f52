"""Rich consoles for command output that stays intact when it is piped or captured.

On a terminal rich wraps to the window.  Anywhere else (a pipe, a file, a test's capture) rich
would assume 80 columns and break long lines, words and paths included; :func:`make_console`
then turns wrapping off and leaves tables room to lay out on one line each.  Text from outside
(file names, messages of exceptions, hints such as ``pip install 'robosoc[video]'``) goes through
:func:`plain` or :func:`note`, which never interpret brackets as markup.
"""

from __future__ import annotations

import os
import sys

from rich.console import Console
from rich.markup import escape

__all__ = ["PIPE_WIDTH", "make_console", "note", "plain"]

#: Width given to tables when the output is not a terminal (text is not wrapped at all).
PIPE_WIDTH = 200


class _Console(Console):
    """A rich console that reports a closed pipe as :class:`BrokenPipeError` (exit code 141), where
    rich would exit with 1, the code robosoc keeps for its own bugs."""

    def on_broken_pipe(self) -> None:
        self.quiet = True
        try:
            devnull = os.open(os.devnull, os.O_WRONLY)
            os.dup2(devnull, sys.stdout.fileno())
        except (OSError, ValueError, AttributeError):
            pass
        raise BrokenPipeError


def make_console(stderr: bool = False, min_width: int = 0) -> Console:
    """A console on stdout (or stderr) that wraps only on a terminal.

    ``COLUMNS`` in the environment still sets the width, as with plain rich; on a terminal the
    console is at least ``min_width`` wide (for tables that need it).
    """
    probe = _Console(stderr=stderr)
    if probe.is_terminal:
        return _Console(stderr=stderr, width=max(probe.width, min_width)) if probe.width < min_width else probe
    columns = os.environ.get("COLUMNS", "")
    width = int(columns) if columns.isdigit() and int(columns) > 0 else PIPE_WIDTH
    return _Console(stderr=stderr, soft_wrap=True, width=max(width, min_width), highlight=False)


def plain(console: Console, text: str, style: str | None = None) -> None:
    """Print ``text`` exactly as written (brackets included), optionally in one style."""
    console.print(escape(text), style=style)


def note(console: Console, text: str) -> None:
    """A warning the command carries on after, in yellow, brackets printed literally."""
    plain(console, text, style="yellow")
