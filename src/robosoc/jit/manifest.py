"""The on-disk manifest of a program: the regions compiled for its code by earlier runs, as records.

``$ROBOSOC_CACHE/jit/manifests/<key>.txt`` holds one JSON line per region compiled for one program
(its code bytes, the core's build, the policy and its region caps, LLVM and the host:
:func:`manifest_key`): a :class:`RegionRecord`, everything a core needs to enter the region in its
tables (its translated words, block starts and indices, side exits) and the cache key
of its object.  A later run of the same program (another flight in the process, a new process)
enters these regions when it makes its tables, loading their objects from the object cache,
without finding or writing them again (``discover`` and ``emit_region`` cost a flight's first
use of each region 2-5 ms).  A :class:`Manifest` is what one core knows of its loaded code's list.
"""

from __future__ import annotations

import functools
import hashlib
import json
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import llvmlite.binding as llvm
import numpy as np

from robosoc.cache import cache_root
from robosoc.jit.compiler import PIPELINE
from robosoc.output_files import write_atomic

#: the arrays of a record, with their dtypes (as in :class:`robosoc.jit.tables.Translated`)
_ARRAYS = {
    "pcs": np.int64,
    "block_starts": np.int64,
    "block_indices": np.int64,
    "side_exits": np.int64,
    "rest": np.uint8,
}


def _manifest_path(key: str) -> Path:
    return cache_root() / "jit" / "manifests" / f"{key}.txt"


@functools.cache
def _manifest_host() -> str:
    """LLVM and the host, asked once: each LLVM call waits for llvmlite's process-wide lock, which
    the compiling thread holds while it generates code."""
    return f"llvm{llvm.llvm_version_info} {llvm.get_default_triple()} {llvm.get_host_cpu_name()} {PIPELINE}"


def manifest_key(code: bytes, options: str) -> str:
    """The key of a program's manifest: its code bytes, build options, LLVM and host (as object keys)."""
    return hashlib.sha256(_manifest_host().encode() + options.encode() + code).hexdigest()


@dataclass(frozen=True)
class RegionRecord:
    """A region compiled for a program, as a later run enters it: its start and size, its object's
    cache key (:meth:`robosoc.jit.compiler.Compiler.key`) and function name (with the placeholder
    stem), and the arrays of :class:`robosoc.jit.tables.Translated` (its words are the program's)."""

    start: int
    instructions: int
    object_key: str
    function: str
    arrays: dict[str, np.ndarray]

    def line(self) -> str:
        fields = {"start": self.start, "instructions": self.instructions, "key": self.object_key}
        fields["function"] = self.function
        fields.update({name: self.arrays[name].reshape(-1).tolist() for name in _ARRAYS})
        return json.dumps(fields, separators=(",", ":"))

    @staticmethod
    def of_line(line: str) -> RegionRecord:
        fields = json.loads(line)
        arrays = {name: np.array(fields[name], dtype=dtype) for name, dtype in _ARRAYS.items()}
        start, instructions = int(fields["start"]), int(fields["instructions"])
        return RegionRecord(start, instructions, fields["key"], fields["function"], arrays)


#: manifest file -> (its size and modification time when read, its records): read again only when
#: it changed (a chip's tiles making their tables one by one, each flight of a process, read it)
_READ: dict[Path, tuple[tuple[int, int], dict[int, RegionRecord]]] = {}


def read_manifest(key: str) -> dict[int, RegionRecord]:
    """The regions compiled before for this program, by start (their objects are likely in the
    cache); a line that cannot be read (a writer's, half written) is left out.  Do not change the
    dict returned (it is kept for the next reader)."""
    path = _manifest_path(key)
    try:
        stat = path.stat()
        seen = _READ.get(path)
        if seen is not None and seen[0] == (stat.st_size, stat.st_mtime_ns):
            return seen[1]
        lines = path.read_text().splitlines()
    except OSError:
        return {}
    records: dict[int, RegionRecord] = {}
    for line in lines:
        try:
            record = RegionRecord.of_line(line)
        except (ValueError, KeyError, TypeError):
            continue
        records.setdefault(record.start, record)
    _READ[path] = ((stat.st_size, stat.st_mtime_ns), records)
    return records


def whole_code_path(key: str) -> Path:
    """The mark that a program's whole code was translated (:meth:`robosoc.jit.engine.TranslatingCore.translate_code`:
    its manifest lists a region at every word the translator takes); it holds the records' count."""
    return _manifest_path(key).with_suffix(".whole")


def whole_code_translated(key: str) -> bool:
    """Whether the program with manifest key ``key`` had its whole code translated (and the
    manifest is still there)."""
    return whole_code_path(key).is_file() and _manifest_path(key).is_file()


def mark_whole_code(key: str, records: int) -> None:
    """Mark the program's whole code translated (written whole or not at all)."""
    path = whole_code_path(key)
    path.parent.mkdir(parents=True, exist_ok=True)
    write_atomic(path, f"{records}\n")


def add_to_manifest(key: str, record: RegionRecord) -> None:
    """Note a compiled region in the program's manifest (one line appended)."""
    path = _manifest_path(key)
    path.parent.mkdir(parents=True, exist_ok=True)
    with path.open("a") as f:
        f.write(record.line() + "\n")


class Manifest:
    """What one core knows of its loaded code's manifest: the starts listed or noted since, and
    the records an earlier run wrote (``cached``: their starts; the core keeps those it could not
    enter with its tables, their object gone from the cache)."""

    def __init__(self, key: str | None = None) -> None:
        """``key``: read the list of the code with that key now; None: start empty, the key made
        when a region is first noted (hashing the code cost each region 0.1 ms)."""
        self.key = key
        self.records: dict[int, RegionRecord] = read_manifest(key) if key is not None else {}
        self.known: set[int] = set(self.records)
        self.cached: frozenset[int] = frozenset(self.known)

    def note(self, start: int, make_key: Callable[[], str], record: Callable[[], RegionRecord]) -> None:
        """A region compiled at ``start`` (added to the file once); ``make_key``: the code's key,
        if not made yet; ``record``: the region's record."""
        if start not in self.known:
            self.known.add(start)
            if self.key is None:
                self.key = make_key()
            add_to_manifest(self.key, record())

    def copy(self) -> Manifest:
        """The same knowledge for another core holding the same code."""
        other = Manifest.__new__(Manifest)
        other.key = self.key
        other.records = self.records
        other.known = set(self.known)
        other.cached = self.cached
        return other
