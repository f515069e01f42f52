"""The on-disk manifest of a program: the regions compiled for its code by earlier runs.

``$ROBOSOC_CACHE/jit/manifests/<key>.txt`` lists, one hex start per line, the regions compiled for
one program (its code bytes, the core's build, the policy, LLVM and the host: :func:`manifest_key`).
Their objects are likely in the object cache, so ``auto`` translates them at their first arrival
instead of waiting for them to turn hot and for its budget (docs/translation.md).  A
:class:`Manifest` is what one core knows of its loaded code's list.
"""

from __future__ import annotations

import functools
import hashlib
from collections.abc import Callable
from pathlib import Path

import llvmlite.binding as llvm

from robosoc.cache import cache_root
from robosoc.jit.compiler import PIPELINE_VERSION


def _manifest_path(key: str) -> Path:
    return cache_root() / "jit" / "manifests" / f"{key}.txt"


@functools.cache
def _manifest_host() -> str:
    """LLVM and the host, asked once: each LLVM call waits for llvmlite's process-wide lock, which
    the compiling thread holds while it generates code."""
    return f"llvm{llvm.llvm_version_info} {llvm.get_default_triple()} {llvm.get_host_cpu_name()} {PIPELINE_VERSION}"


def manifest_key(code: bytes, options: str) -> str:
    """The key of a program's manifest: its code bytes, build options, LLVM and host (as object keys)."""
    return hashlib.sha256(_manifest_host().encode() + options.encode() + code).hexdigest()


def read_manifest(key: str) -> set[int]:
    """The region starts compiled before for this program (their objects are likely in the cache)."""
    try:
        return {int(line, 16) for line in _manifest_path(key).read_text().split()}
    except (OSError, ValueError):
        return set()


def add_to_manifest(key: str, start: int) -> None:
    """Note a compiled region's start in the program's manifest (one line appended: readers see whole lines)."""
    path = _manifest_path(key)
    path.parent.mkdir(parents=True, exist_ok=True)
    with path.open("a") as f:
        f.write(f"{start:08x}\n")


class Manifest:
    """What one core knows of its loaded code's manifest: the starts listed or noted since, and
    those an earlier run compiled (``cached``: installed at once when they turn hot)."""

    def __init__(self, key: str | None = None) -> None:
        """``key``: read the list of the code with that key now (``auto``); None: start empty, the
        key made when a region is first noted (hashing the code cost each region 0.1 ms)."""
        self.key = key
        self.known: set[int] = read_manifest(key) if key is not None else set()
        self.cached: frozenset[int] = frozenset(self.known)

    def note(self, start: int, make_key: Callable[[], str]) -> None:
        """A region compiled at ``start`` (added to the file once); ``make_key``: the code's key,
        if not made yet."""
        if start not in self.known:
            self.known.add(start)
            if self.key is None:
                self.key = make_key()
            add_to_manifest(self.key, start)

    def copy(self) -> Manifest:
        """The same knowledge for another core holding the same code."""
        other = Manifest.__new__(Manifest)
        other.key = self.key
        other.known = set(self.known)
        other.cached = self.cached
        return other
