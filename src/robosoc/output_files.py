"""Every file robosoc writes goes through here: only regular files are written or replaced.

Outputs are written under a temporary name beside the target and renamed over it
(:func:`write_atomic`, :func:`atomic_open`), so that a reader never sees half a file.  Renaming over
a character device (``/dev/null``, ``/dev/full``), a FIFO or a socket would replace the node itself
(as root, ``/dev/null`` would become a regular file), and opening a FIFO for writing waits for a
reader that may never come.  So a target that exists and is anything but a regular file is refused
with :class:`NotRegularFileError` before anything is written; the same check is what the command
line's :func:`robosoc.cli.files.output_file` runs when a command starts.  Files written in place
as they grow (flight logs, link logs) are opened through :func:`open_in_place`, with the same check.
"""

from __future__ import annotations

import contextlib
import os
import stat
from collections.abc import Iterator
from pathlib import Path
from typing import IO, Any

__all__ = [
    "NotRegularFileError",
    "atomic_open",
    "check_regular",
    "not_regular",
    "open_in_place",
    "save_figure",
    "write_atomic",
]

_KINDS = (
    (stat.S_ISCHR, "a character device"),
    (stat.S_ISBLK, "a block device"),
    (stat.S_ISFIFO, "a FIFO (named pipe)"),
    (stat.S_ISSOCK, "a socket"),
)


class NotRegularFileError(OSError):
    """An output path names a device, a FIFO or a socket: robosoc neither replaces nor opens it."""

    def __init__(self, path: Path | str, kind: str) -> None:
        self.path = str(path)
        self.kind = kind
        super().__init__(f"{path}: is {kind}, not a regular file: robosoc writes only regular files")


def not_regular(path: Path | str) -> str | None:
    """What ``path`` is (``"a character device"``...) if it exists and is neither a regular file nor
    a folder (symbolic links followed); ``None`` otherwise, a missing path included."""
    try:
        mode = os.stat(path).st_mode
    except (OSError, ValueError):
        return None
    for test, kind in _KINDS:
        if test(mode):
            return kind
    return None


def check_regular(path: Path | str) -> None:
    """Raise :class:`NotRegularFileError` if ``path`` is a device, a FIFO or a socket."""
    kind = not_regular(path)
    if kind is not None:
        raise NotRegularFileError(path, kind)


def _scratch(path: Path) -> Path:
    return path.with_name(path.name + ".partial")


@contextlib.contextmanager
def atomic_open(path: Path | str, mode: str = "w", **kwargs: Any) -> Iterator[IO[Any]]:
    """A file object writing to a temporary name that replaces ``path`` when the block ends without
    an exception (and is removed when it raises).

    Raises:
        NotRegularFileError: ``path`` is a device, a FIFO or a socket (nothing is written).
    """
    if mode not in ("w", "wb"):
        raise ValueError(f"atomic_open writes a whole file: mode 'w' or 'wb', got {mode!r}")
    target = Path(path)
    check_regular(target)
    scratch = _scratch(target)
    scratch.unlink(missing_ok=True)  # our own name: whatever a crash left there goes
    try:
        with scratch.open(mode, **kwargs) as handle:
            yield handle
        check_regular(target)  # still nothing else there when the work is done
        os.replace(scratch, target)
    finally:
        scratch.unlink(missing_ok=True)


def write_atomic(path: Path | str, data: bytes | str, *, encoding: str = "utf-8", fsync: bool = False) -> None:
    """Write ``data`` to ``path`` so that it is either the old file or the whole new one.

    Raises:
        NotRegularFileError: ``path`` is a device, a FIFO or a socket (nothing is written).
    """
    if isinstance(data, str):
        data = data.encode(encoding)
    with atomic_open(path, "wb") as handle:
        handle.write(data)
        if fsync:
            handle.flush()
            os.fsync(handle.fileno())


def open_in_place(path: Path | str, mode: str = "w", **kwargs: Any) -> IO[Any]:
    """``open(path, mode)`` for a file written as it grows (a log), refusing what is not a regular file.

    Raises:
        NotRegularFileError: ``path`` is a device, a FIFO or a socket.
    """
    check_regular(path)
    return Path(path).open(mode, **kwargs)


def save_figure(fig: Any, path: Path | str, **kwargs: Any) -> bytes:
    """Save a matplotlib figure to ``path`` (format from its suffix) through :func:`write_atomic`;
    returns the bytes written."""
    import io

    target = Path(path)
    check_regular(target)
    buffer = io.BytesIO()
    fig.savefig(buffer, format=target.suffix.lstrip(".").lower() or "png", **kwargs)
    data = buffer.getvalue()
    write_atomic(target, data)
    return data
