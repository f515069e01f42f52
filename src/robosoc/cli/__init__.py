"""Command line: one module per command, each a thin typed function over the library.

The rules every command follows (option checks, files, exit codes, errors) and the helpers that
implement them are described in docs/cli.md.
"""

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


def main() -> None:
    """Entry point of the ``robosoc`` console script."""
    app()


__all__ = ["app", "exit_codes", "main"]
