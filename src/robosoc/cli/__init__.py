"""Command line: one module per command, each a thin typed function over the library.

The rules every command follows (option checks, files, exit codes, errors) and the helpers that
implement them are described in docs/cli.md.

Ctrl-C while the commands are being imported (a second or two) ends with ``robosoc: interrupted``
and 130, as it does later, and not with a traceback from whatever module was loading; once a
command has ended (its message printed), a late Ctrl-C no longer changes the exit code.
"""

import signal
import sys

try:
    from robosoc.cli import (  # noqa: F401  (modules register their commands)
        bench,
        cc,
        exit_codes,
        firmware,
        fly,
        new,
        profile,
        report,
        run,
        scenario,
        serve,
        sweep,
        table,
    )  # fmt: skip
    from robosoc.cli.app import app
except KeyboardInterrupt:
    sys.stderr.write("robosoc: interrupted\n")
    raise SystemExit(130) from None


def main() -> None:
    """Entry point of the ``robosoc`` console script."""
    try:
        app()
    finally:  # the command is over and has said so: a Ctrl-C now would only turn its exit code into -2
        signal.signal(signal.SIGINT, signal.SIG_IGN)


__all__ = ["app", "exit_codes", "main"]
