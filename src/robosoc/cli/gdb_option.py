"""``robosoc run --gdb PORT [--tile X,Y]``: the run, driven by a GDB stub (docs/debugging.md)."""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import TYPE_CHECKING

import typer

if TYPE_CHECKING:
    from robosoc.chip.mpsoc import MPSoC
    from robosoc.chip.single import SingleCoreSoC

GDB_HELP = "Debug with GDB: listen on 127.0.0.1:PORT (0: any free port); the core waits for GDB to continue."
TILE_HELP = "With --gdb on the MPSoC: the tile X,Y to debug (default: the first core tile)."


def check_gdb_options(gdb: int | None, tile: str | None, one_core: bool, trace: int, profile: int) -> None:
    """Reject option combinations the stub cannot serve (exit code 2)."""
    problem = None
    if tile is not None and gdb is None:
        problem = "--tile X,Y picks the tile to debug: it goes with --gdb PORT"
    elif tile is not None and one_core:
        problem = "--tile X,Y needs the MPSoC (--mesh WxH or --chip FILE)"
    elif gdb is not None and (trace or profile):
        problem = "--gdb cannot be combined with --trace or --profile"
    if problem:
        typer.echo(f"robosoc run: {problem}", err=True)
        raise typer.Exit(2)


@contextlib.contextmanager
def gdb_session(
    port: int | None, machine: SingleCoreSoC | MPSoC, program: Path, tile: str | None = None
) -> Iterator[Callable[[int], int] | None]:
    """The ``advance`` function a run loop uses with ``--gdb`` (None without it).

    Listens before the run starts (a port in use is exit code 2), and ends the GDB session when
    the run ends, however it ends.
    """
    if port is None:
        yield None
        return
    from robosoc.chip.mpsoc import MPSoC
    from robosoc.debug import ChipTarget, GdbServer, Listener, ListenError, SingleCoreTarget, Target

    target: Target
    if isinstance(machine, MPSoC):
        xy = _parse_tile(tile) if tile is not None else machine.core_tiles()[0]
        try:
            target = ChipTarget(machine, xy)
        except ValueError as exc:
            typer.echo(f"robosoc run: --tile: {exc}", err=True)
            raise typer.Exit(2) from exc
    else:
        target = SingleCoreTarget(machine)
    try:
        listener = Listener(port)
    except ListenError as exc:
        typer.echo(f"robosoc run: --gdb: {exc}", err=True)
        raise typer.Exit(2) from exc

    def log(message: str) -> None:
        typer.echo(f"robosoc: gdb: {message}", err=True)

    log(f"debugging the {target.description}: gdb-multiarch {program} -ex 'target remote :{listener.port}'")
    with GdbServer(target, listener, log=log) as server:
        yield server.advance


def _parse_tile(text: str) -> tuple[int, int]:
    from robosoc.cli.options import parse_tile

    return parse_tile("--tile", text)
