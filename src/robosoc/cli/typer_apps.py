"""The typer applications that every command module registers itself on.

Both are built on :class:`RobosocGroup`, whose ``main`` runs every command through
:func:`robosoc.cli.errors.run_guarded`: one error format and one set of exit codes
(:mod:`robosoc.cli.exit_codes`) for every command, also under ``typer.testing.CliRunner``.
"""

from __future__ import annotations

import sys
from collections.abc import Sequence
from typing import Any

import typer
from typer.core import TyperGroup

from robosoc.cli import exit_codes
from robosoc.cli.errors import PROGRAM, command_path, run_guarded

# the attribute naming the command an exception left, read by run_guarded (exceptions do not declare it)
_COMMAND_TAG = "robosoc_command"


class RobosocGroup(TyperGroup):
    """A typer group whose commands fail the robosoc way (see :mod:`robosoc.cli.errors`)."""

    def main(
        self,
        args: Sequence[str] | None = None,
        prog_name: str | None = None,
        complete_var: str | None = None,
        standalone_mode: bool = True,
        windows_expand_args: bool = True,
        **extra: Any,
    ) -> Any:
        def call() -> object:
            return super(RobosocGroup, self).main(
                args=args,
                prog_name=PROGRAM,
                complete_var=complete_var,
                standalone_mode=False,
                windows_expand_args=windows_expand_args,
                **extra,
            )

        code = run_guarded(call)
        if standalone_mode:
            sys.exit(code)
        return code

    # typer calls it with a typer.Context and declares the base class, which typer keeps private
    def invoke(self, ctx: typer.Context) -> Any:  # type: ignore[override]  # given a typer.Context
        try:
            return super().invoke(ctx)
        except BrokenPipeError:
            raise typer.Exit(exit_codes.BROKEN_PIPE) from None
        except BaseException as exc:
            # the innermost group names the command: "robosoc bench noc"
            if not hasattr(exc, _COMMAND_TAG) and not isinstance(exc, typer.Exit | SystemExit):
                sub = ctx.invoked_subcommand
                command = command_path(ctx) + (f" {sub}" if sub else "")
                setattr(exc, _COMMAND_TAG, command)
                if isinstance(exc, KeyboardInterrupt):
                    from robosoc.cli.errors import print_error

                    print_error(command, "interrupted")
                    raise typer.Exit(exit_codes.INTERRUPTED) from None
            raise


app = typer.Typer(
    name=PROGRAM,
    cls=RobosocGroup,
    help="Robot control firmware on a cycle-accurate RISC-V MPSoC, closed-loop with physics.",
    epilog=exit_codes.EPILOG,
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)
bench_app = typer.Typer(
    cls=RobosocGroup,
    help="Benchmarks that print simulated speed figures.",
    epilog=exit_codes.EPILOG,
    no_args_is_help=True,
)
app.add_typer(bench_app, name="bench")
firmware_app = typer.Typer(
    cls=RobosocGroup,
    help="The control firmware: build its four variants, see their size, replay a flight into the chip.",
    epilog=exit_codes.EPILOG,
    no_args_is_help=True,
)
app.add_typer(firmware_app, name="firmware")
