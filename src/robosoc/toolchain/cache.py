"""Where builds are cached, and the content hash that keys them.

The root is :func:`robosoc.cache.cache_root`.  Below it:
``zig/`` holds zig's own caches, ``elf/`` the RISC-V builds, ``native/`` the host builds.
A key is the SHA-256 of a JSON description of everything that decides the output:
the toolchain version, the options, and the contents of every source and of every header
in the include directories and in the sources' own directories.
"""

import hashlib
import json
from collections.abc import Iterable
from pathlib import Path

from robosoc.cache import cache_root

#: Bumped whenever the way robosoc drives the compiler changes, to invalidate old entries.
CACHE_SCHEMA = 1

HEADER_SUFFIXES = (".h", ".inc")


def zig_cache_dir() -> Path:
    """zig's global and local cache folder inside the project cache."""
    return cache_root() / "zig"


def file_digest(path: Path) -> str:
    """SHA-256 of a file's bytes."""
    return hashlib.sha256(path.read_bytes()).hexdigest()


def header_digests(directories: Iterable[Path]) -> dict[str, str]:
    """Digests of every header (recursively) below the given directories, keyed by path."""
    digests: dict[str, str] = {}
    for directory in directories:
        if not directory.is_dir():
            continue
        for header in sorted(directory.rglob("*")):
            if header.suffix in HEADER_SUFFIXES and header.is_file():
                digests[str(header)] = file_digest(header)
    return digests


def build_key(description: dict[str, object]) -> str:
    """Stable hex key of a JSON-serialisable build description."""
    blob = json.dumps({"schema": CACHE_SCHEMA, **description}, sort_keys=True, default=str)
    return hashlib.sha256(blob.encode()).hexdigest()


def entry_dir(kind: str, key: str) -> Path:
    """Folder of one cache entry (``kind`` is ``elf`` or ``native``)."""
    return cache_root() / kind / key[:2] / key
