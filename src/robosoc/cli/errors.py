"""How every command fails: one exception for errors the user can fix, one format, one exit code each.

A command (or a helper of :mod:`robosoc.cli.options` and :mod:`robosoc.cli.files`) raises
:class:`CliError`; :func:`run_guarded` (called by the application's group, :mod:`robosoc.cli.typer_apps`)
turns it and everything else into a message on stderr and an exit code (:mod:`robosoc.cli.exit_codes`):

* ``CliError("--seed: must be ...")``: ``robosoc fly: --seed: must be between 0 and 2**63-1, got -1``, 2;
* a click usage error (unknown option, not a number, missing argument): the same style
  (``robosoc run: --max-cycles: input should be a valid integer ...``) and a pointer to ``--help``, 2;
* ``typer.Exit(n)``: nothing more, ``n``;
* Ctrl-C: ``robosoc CMD: interrupted``, 130;
* a closed output pipe: nothing, 141;
* an output that is a device, a FIFO or a socket (:class:`robosoc.output_files.NotRegularFileError`,
  met inside an output folder; named options are checked first by :func:`robosoc.cli.files.output_file`): 2;
* any other exception: the traceback and a request to report the bug, 1.

Messages are plain text (never rich markup), so brackets and paths come out as written.
"""

from __future__ import annotations

import errno
import os
import sys
import traceback
from collections.abc import Callable
from typing import TYPE_CHECKING, TypeGuard

from robosoc.cli import exit_codes
from robosoc.output_files import NotRegularFileError

if TYPE_CHECKING:  # typer brings its own click (typer._click): exceptions are recognised by class name
    import click

__all__ = ["CliError", "command_path", "print_error", "run_guarded"]

PROGRAM = "robosoc"
REPORT = "this is a bug in robosoc, not in your input: please report it with the command line and the traceback above"


class CliError(Exception):
    """An error the user can fix: printed as ``robosoc CMD: <message>``, then exit with ``code``.

    ``message`` names what is wrong the way the user wrote it: the option (``--seed: ...``) or
    the file (``scenario.toml: sensors.rate_hz: ...``).
    """

    def __init__(self, message: str, code: int = exit_codes.USAGE) -> None:
        super().__init__(message)
        self.message = message
        self.code = code


def command_path(ctx: object | None) -> str:
    """``"robosoc bench noc"`` for a click context (whatever the program was called as)."""
    names: list[str] = []
    while ctx is not None:
        names.append(getattr(ctx, "info_name", None) or "")
        ctx = getattr(ctx, "parent", None)
    names.reverse()
    return " ".join([PROGRAM, *[n for n in names[1:] if n]])


def print_error(command: str, message: str) -> None:
    """``<command>: <message>`` on stderr, as plain text."""
    _stderr_write(f"{command}: {message}\n")


def _stderr_write(text: str) -> None:
    try:
        sys.stderr.write(text)
        sys.stderr.flush()
    except (OSError, ValueError):
        pass


def _lower_first(text: str) -> str:
    return text[:1].lower() + text[1:] if text[:2] != text[:2].upper() else text


def _click_message(exc: click.ClickException) -> str:
    """A click usage error in the ``--option: reason`` style."""
    param = getattr(exc, "param", None)  # BadParameter and MissingParameter name one; others do not
    if param is not None and type(exc).__name__ == "MissingParameter":  # typer's own class or click's
        kind = param.param_type_name
        shown = param.opts[0] if kind == "option" else (param.metavar or str(param.name).upper())
        return f"missing {kind} {shown}"
    if param is not None:
        opts = [o for o in param.opts if o.startswith("--")] or list(param.opts)
        name = opts[0] if opts and param.param_type_name == "option" else param.human_readable_name
        return f"{name}: {_lower_first(exc.message)}"
    return _lower_first(exc.message)


def _is_click_exception(exc: BaseException) -> TypeGuard[click.ClickException]:
    # click's class or its copy in typer (typer._click), with the same interface: known by name
    return any(cls.__name__ == "ClickException" for cls in type(exc).__mro__)


def _stdout_identity() -> tuple[int, int] | None:
    try:
        st = os.fstat(sys.stdout.fileno())
    except (OSError, ValueError, AttributeError):
        return None
    return st.st_dev, st.st_ino


def _rich_closed_pipe(before: tuple[int, int] | None) -> bool:
    """Whether rich met a closed pipe: it points stdout at /dev/null and exits with 1."""
    after = _stdout_identity()
    try:
        null = os.stat(os.devnull)
    except OSError:
        return False
    return before is not None and after != before and after == (null.st_dev, null.st_ino)


def run_guarded(main: Callable[[], object], default_command: str = PROGRAM) -> int:
    """Call ``main`` (a click ``main`` in non-standalone mode) and map what it raises to an exit code."""
    stdout_before = _stdout_identity()
    try:
        result = main()
    except CliError as exc:
        print_error(getattr(exc, "robosoc_command", default_command), exc.message)
        return exc.code
    except SystemExit as exc:
        if exc.code == 1 and _rich_closed_pipe(stdout_before):  # typer's help, printed by rich
            return exit_codes.BROKEN_PIPE
        return exc.code if isinstance(exc.code, int) else (exit_codes.OK if exc.code is None else exit_codes.USAGE)
    except KeyboardInterrupt:
        print_error(default_command, "interrupted")
        return exit_codes.INTERRUPTED
    except NotRegularFileError as exc:  # an output inside an output folder: the file is named
        print_error(getattr(exc, "robosoc_command", default_command), str(exc))
        return exit_codes.USAGE
    except BrokenPipeError:
        _silence_stdout()
        return exit_codes.BROKEN_PIPE
    except Exception as exc:
        if type(exc).__name__ == "NoArgsIsHelpError":
            help_text = getattr(exc, "message", "")
            if help_text:
                _stderr_write(help_text + "\n")
            return exit_codes.USAGE
        if type(exc).__name__ == "Abort":
            print_error(default_command, "interrupted")
            return exit_codes.INTERRUPTED
        if _is_click_exception(exc):
            command = command_path(getattr(exc, "ctx", None)) if getattr(exc, "ctx", None) else default_command
            print_error(command, _click_message(exc))
            _stderr_write(f"(see '{command} --help')\n")
            return int(getattr(exc, "exit_code", exit_codes.USAGE)) or exit_codes.USAGE
        if isinstance(exc, OSError) and exc.errno == errno.EPIPE:
            _silence_stdout()
            return exit_codes.BROKEN_PIPE
        _stderr_write("".join(traceback.format_exception(exc)))
        print_error(getattr(exc, "robosoc_command", default_command), f"internal error: {REPORT}")
        return exit_codes.INTERNAL_ERROR
    return result if isinstance(result, int) and not isinstance(result, bool) else exit_codes.OK


def _silence_stdout() -> None:
    """After a closed pipe: point stdout at /dev/null so that Python's final flush stays quiet."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError, AttributeError):
        pass
