"""Ctrl-C held back while a run folder's summary is written, and what is left when it comes later.

A flight's files must agree with what the command prints: ``summary.json`` says whether the
flight is complete, and no half-written file (``*.partial``, ``*.tmp``) stays behind.  The short
step that writes the summary and the job records runs under :func:`deferred_interrupt`: a SIGINT
during it is kept and raised when the step is done.  The longer extras after it (plots, MCAP,
report) stay interruptible: :class:`InterruptedAfterFlight` then says the flight itself is
complete and which files were not written, and :func:`remove_partials` takes away what the
interruption left half-written.
"""

from __future__ import annotations

import signal
import threading
from collections.abc import Iterable, Iterator
from contextlib import contextmanager
from pathlib import Path

PARTIAL_SUFFIXES = (".partial", ".tmp")
"""Suffixes of the scratch files writers rename into place (``flight.mcap.partial``, ``summary.json.tmp``)."""


class InterruptedAfterFlight(KeyboardInterrupt):
    """Ctrl-C after the flight was complete and its ``summary.json`` written (``"complete": true``),
    while the extras were being written; ``missing`` names the files that were not."""

    def __init__(self, missing: list[str]) -> None:
        super().__init__(f"interrupted after the flight; not written: {', '.join(missing) or 'nothing'}")
        self.missing = missing


@contextmanager
def deferred_interrupt() -> Iterator[None]:
    """Run the block with SIGINT held back; one that came meanwhile is raised (KeyboardInterrupt)
    when the block ends.  Outside the main thread (a worker) it does nothing."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    came: list[int] = []
    try:
        before = signal.signal(signal.SIGINT, lambda signum, _frame: came.append(signum))
    except (ValueError, OSError):  # no signals here (an embedded interpreter)
        yield
        return
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, before)
    if came:
        raise KeyboardInterrupt


def remove_partials(folders: Iterable[Path], names: Iterable[str]) -> list[Path]:
    """Delete the scratch files of ``names`` (``flight.mcap`` → ``flight.mcap.partial``, with each of
    :data:`PARTIAL_SUFFIXES`) an interruption left in ``folders``; the paths removed."""
    removed = []
    names = list(names)
    for folder in folders:
        for name in names:
            for suffix in PARTIAL_SUFFIXES:
                path = folder / (name + suffix)
                if path.is_file():
                    path.unlink(missing_ok=True)
                    removed.append(path)
    return removed


__all__ = ["PARTIAL_SUFFIXES", "InterruptedAfterFlight", "deferred_interrupt", "remove_partials"]
