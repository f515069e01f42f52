"""Printing the decoupled mode's datagram counts, and the exit of a side that did not finish."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from rich.console import Console
from rich.table import Table

from robosoc.cli import exit_codes
from robosoc.cli.errors import CliError
from robosoc.cosim.decoupled_physics import Ended
from robosoc.cosim.link_counters import COUNTER_NAMES
from robosoc.cosim.link_faults import INJECTED_NAMES

__all__ = ["end_of_side", "print_link_counts"]


def print_link_counts(console: Console, directions: Mapping[str, Mapping[str, Any]]) -> None:
    """A table: one row per direction (``"to chip"`` ...), the counters of :data:`COUNTER_NAMES`
    (``-`` where this side cannot know them), then the faults injected by the sender."""
    table = Table(title="datagrams", title_justify="left", box=None, pad_edge=False)
    table.add_column("direction")
    for name in COUNTER_NAMES:
        table.add_column(name, justify="right")
    table.add_column("injected (" + "/".join(n[:4] for n in INJECTED_NAMES) + ")", justify="right")
    for direction, counts in directions.items():
        injected = counts.get("injected")
        table.add_row(
            direction,
            *(str(counts[name]) if name in counts else "-" for name in COUNTER_NAMES),
            "/".join(str(injected.get(n, 0)) for n in INJECTED_NAMES) if injected else "-",
        )
    console.print(table)


def end_of_side(ended: str, message: str, where: str) -> None:
    """Raise what ends the command for a side that did not finish (``where``: its files, or "")."""
    tail = f"; what was done is in {where}" if where else ""
    if ended == Ended.DONE:
        return
    if ended == Ended.INTERRUPTED:
        raise CliError("interrupted" + tail, code=exit_codes.INTERRUPTED)
    if ended in (Ended.PEER_LOST, Ended.PEER_ENDED):
        raise CliError(message + tail, code=exit_codes.PEER_LOST)
    raise CliError(message + tail)
