"""Where robosoc keeps what it builds and compiles: ``$ROBOSOC_CACHE`` when set, else
``~/.cache/robosoc``.  Below it: ``zig/`` (zig's own caches), ``elf/`` (RISC-V builds), ``native/``
(host builds), ``numba/`` (the compiled kernels), ``dwarf/`` (what the host reads of a build's
debug information, :func:`robosoc.program.dwarf.debug_index`), the translator's objects and the
generated control headers."""

import os
from pathlib import Path


def cache_root() -> Path:
    """The project cache folder (``$ROBOSOC_CACHE`` or ``~/.cache/robosoc``)."""
    env = os.environ.get("ROBOSOC_CACHE")
    root = Path(env) if env else Path.home() / ".cache" / "robosoc"
    return root.expanduser().resolve()


def dwarf_dir() -> Path:
    """Where the debug information the host reads of each build is kept, under the build's digest."""
    return cache_root() / "dwarf"
