"""The only numba code in robosoc: the core step and the NoC cycle, arrays in, arrays out.

numba's on-disk cache is keyed on the source file of each compiled function only, so a change in
a function it calls from another file (or in the instruction table whose numbers are baked in as
constants) would leave a stale compiled kernel behind.  Importing this package therefore points
numba's cache at a folder named after a digest of every kernel source and the instruction table:
any change there compiles afresh, and unchanged sources start in about a second.  Setting
``NUMBA_CACHE_DIR`` yourself overrides this.
"""

import hashlib
import os
from collections.abc import Iterable
from pathlib import Path

import numba

from robosoc.cache import cache_root

_SOURCES = [*sorted(Path(__file__).parent.glob("*.py")), Path(__file__).parent.parent / "isa" / "table.py"]


def sources_digest(seed: str, sources: Iterable[Path]) -> str:
    """Digest of ``seed`` and the names and bytes of ``sources`` (what a compiled form depends on)."""
    h = hashlib.sha256(seed.encode())
    for path in sources:
        h.update(path.name.encode())
        h.update(path.read_bytes())
    return h.hexdigest()[:16]


def kernel_digest() -> str:
    """Digest of the sources whose compiled form numba caches."""
    return sources_digest(numba.__version__, _SOURCES)


def _numba_cache_dir() -> Path:
    return cache_root() / "numba" / kernel_digest()


# numba.config makes its settings at run time (globals().update()), unseen by numba's stubs
if not os.environ.get("NUMBA_CACHE_DIR"):
    numba.config.CACHE_DIR = str(_numba_cache_dir())  # type: ignore[attr-defined]  # numba.config: made at run time


def compiled_or_cached(kernel: numba.core.dispatcher.Dispatcher) -> bool:
    """Whether the ``@njit(cache=True)`` ``kernel`` is compiled in this process or in numba's cache
    (its first call then takes about a second, instead of compiling for tens of seconds)."""
    if kernel.signatures:
        return True
    # numba keeps a kernel's index in a folder named after its source folder's path: another checkout
    # of the same sources shares the digest folder but not that one (nor, if lines moved, the name)
    index = getattr(getattr(getattr(kernel, "_cache", None), "_cache_file", None), "_index_path", None)
    if isinstance(index, str):
        return Path(index).is_file()
    func = kernel.py_func
    index = f"{func.__module__.rsplit('.', 1)[-1]}.{func.__qualname__}-*.nbi"  # numba's index file of it
    cache = Path(numba.config.CACHE_DIR)  # type: ignore[attr-defined]  # numba.config: made at run time
    return any(cache.rglob(index))
