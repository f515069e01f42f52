"""Command line: one module per command, each a thin typed function over the library."""

from robosoc.cli import bench, cc, fly, run  # noqa: F401  (modules register their commands)
from robosoc.cli.app import app


def main() -> None:
    """Entry point of the ``robosoc`` console script."""
    app()


__all__ = ["app", "main"]
