"""What translated code is specialised for: the part of a core's build its regions depend on."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Target:
    """What the translated code is specialised for (all of it is part of the cache key)."""

    base: int
    mem_size: int
    code_size: int
    rtl_errata: bool
