"""Every file a command reads or writes goes through here, so that a bad path is an error naming it.

Inputs (:func:`input_file`, :func:`read_text`, :func:`read_toml`, :func:`load_toml`, :func:`load_program`,
:func:`input_dir`): missing, a folder, unreadable, not UTF-8 and malformed contents each give a
:class:`~robosoc.cli.errors.CliError` such as ``--scenario: runs/: is a folder, expected a TOML file``.

Outputs (:func:`output_file`, :func:`output_dir`) are checked when the command starts, before any
long work: the parent folder exists or is created, a file is not a folder (and the other way
round), the place is writable (checked by writing, which also works for root and read-only file
systems), an existing file is a regular file (never a device such as ``/dev/null``, a FIFO or a
socket: outputs are renamed over their target, :mod:`robosoc.output_files`), and an output is not
one of the command's inputs.  A file that did not exist is not left
behind by the check.

``label`` is how the user gave the path: the option (``"--stats"``) or ``None`` for an argument,
whose path alone then names it.
"""

from __future__ import annotations

import tempfile
import tomllib
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypeVar

from robosoc.cli.errors import CliError
from robosoc.output_files import not_regular

if TYPE_CHECKING:
    from _typeshed import DataclassInstance

    from robosoc.program.elf import Program, Region

T = TypeVar("T", bound="DataclassInstance")

__all__ = [
    "input_dir",
    "input_file",
    "load_program",
    "load_toml",
    "output_dir",
    "output_file",
    "read_text",
    "read_toml",
]


def _error(label: str | None, path: Path | str, reason: str) -> CliError:
    where = f"{label}: {path}" if label else str(path)
    return CliError(f"{where}: {reason}")


def _reason(exc: OSError) -> str:
    return exc.strerror.lower() if exc.strerror else str(exc)


def input_file(path: Path | str, label: str | None = None, kind: str = "file") -> Path:
    """``path`` if it is an existing, readable regular file; ``kind`` names what is expected."""
    p = Path(path).expanduser()
    if not p.exists():
        raise _error(label, path, "file not found" if p.parent.is_dir() else "no such file or folder")
    if p.is_dir():
        raise _error(label, path, f"is a folder, expected {_article(kind)}")
    try:
        with p.open("rb") as stream:
            stream.read(1)
    except OSError as exc:
        raise _error(label, path, f"cannot read: {_reason(exc)}") from exc
    return p


def input_dir(path: Path | str, label: str | None = None) -> Path:
    """``path`` if it is an existing folder."""
    p = Path(path).expanduser()
    if not p.exists():
        raise _error(label, path, "folder not found")
    if not p.is_dir():
        raise _error(label, path, "is a file, expected a folder")
    return p


def read_text(path: Path | str, label: str | None = None, kind: str = "text file") -> str:
    """The UTF-8 text of an input file."""
    p = input_file(path, label, kind)
    try:
        data = p.read_bytes()
    except OSError as exc:
        raise _error(label, path, f"cannot read: {_reason(exc)}") from exc
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise _error(
            label,
            path,
            f"not UTF-8 text (byte 0x{data[exc.start]:02x} at offset {exc.start}): expected {_article(kind)}",
        ) from exc


def read_toml(path: Path | str, label: str | None = None) -> dict[str, Any]:
    """The parsed contents of a TOML file."""
    text = read_text(path, label, "TOML file")
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise _error(label, path, f"invalid TOML: {exc}") from exc


def load_toml(cls: type[T], path: Path | str, label: str | None = None) -> tuple[T, tuple[str, ...]]:
    """A configuration dataclass from a TOML file, and the dotted fields the file sets.

    Errors name the option, the file and the field: ``--chip: chip.toml: width: must be ...``.
    """
    from robosoc.config.validate import ConfigError, from_mapping, named_fields

    data = read_toml(path, label)
    try:
        return from_mapping(cls, data, str(path)), named_fields(data)
    except ConfigError as exc:
        raise CliError(f"{label}: {exc}" if label else str(exc)) from exc


def load_program(path: Path | str, label: str | None = None, regions: Sequence[Region] | None = None) -> Program:
    """An RV32 executable (:func:`robosoc.program.elf.load_elf`) whose segments fit ``regions``."""
    from robosoc.program.elf import ElfError, load_elf

    p = input_file(path, label, "ELF file")
    try:
        return load_elf(p, regions)
    except ElfError as exc:
        raise CliError(f"{label}: {exc}" if label else str(exc)) from exc
    except Exception as exc:  # a malformed file can trip the ELF parser anywhere: still the file's fault
        raise _error(label, path, f"malformed ELF file ({type(exc).__name__}: {exc})") from exc


def _same_file(a: Path, b: Path) -> bool:
    try:
        return a.exists() and b.exists() and a.samefile(b)
    except OSError:
        return False


def _make_dir(folder: Path, label: str | None, shown: Path | str) -> None:
    if folder.is_dir():
        return
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except (FileExistsError, NotADirectoryError) as exc:
        raise _error(label, shown, f"cannot create folder {folder}: a file is in the way") from exc
    except OSError as exc:
        raise _error(label, shown, f"cannot create folder {folder}: {_reason(exc)}") from exc


def output_file(
    path: Path | str,
    label: str | None = None,
    *,
    suffixes: Sequence[str] | None = None,
    inputs: Iterable[Path | str] = (),
) -> Path:
    """``path``, checked to be writable as a file (its parent folder is created if needed).

    Args:
        suffixes: the allowed suffixes (``(".png", ".pdf")``), case-insensitive; ``None``: any.
        inputs: the command's input files, which an output must not overwrite.
    """
    p = Path(path).expanduser()
    if str(path) == "" or p.is_dir():
        raise _error(label, path, "is a folder, expected a file name")
    kind = not_regular(p)
    if kind is not None:  # before the probe: opening a FIFO waits for a reader, a rename replaces a device
        raise _error(label, path, f"is {kind}, expected a regular file (robosoc writes only regular files)")
    if suffixes is not None and p.suffix.lower() not in suffixes:
        raise _error(label, path, f"must end in {' or '.join(suffixes)}")
    for source in inputs:
        if _same_file(p, Path(source)):
            raise _error(label, path, "is also an input of this command: it would be overwritten")
    _make_dir(p.parent, label, path)
    existed = p.exists()
    try:
        with p.open("ab"):
            pass
    except OSError as exc:
        raise _error(label, path, f"cannot write: {_reason(exc)}") from exc
    finally:
        if not existed:
            p.unlink(missing_ok=True)
    return p


def output_dir(
    path: Path | str, label: str | None = None, *, inputs: Iterable[Path | str] = (), names: Iterable[str] = ()
) -> Path:
    """``path``, created if needed and checked to be a folder one can write files in.

    Args:
        names: the files the command writes in the folder; none of them may exist as a device, a FIFO
            or a socket.
    """
    p = Path(path).expanduser()
    if p.exists() and not p.is_dir():
        raise _error(label, path, f"is {not_regular(p) or 'a file'}, expected a folder")
    for source in inputs:
        if _same_file(p, Path(source)):
            raise _error(label, path, "is also an input of this command")
    _make_dir(p, label, path)
    try:
        with tempfile.TemporaryFile(dir=p):
            pass
    except OSError as exc:
        raise _error(label, path, f"cannot write in this folder: {_reason(exc)}") from exc
    for name in names:
        kind = not_regular(p / name)
        if kind is not None:
            raise _error(label, path, f"{name} in it is {kind}, not a regular file (robosoc writes only regular files)")
    return p


def _article(kind: str) -> str:
    return f"an {kind}" if kind[:1].lower() in "aeiou" else f"a {kind}"
