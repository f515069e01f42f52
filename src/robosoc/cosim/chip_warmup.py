"""The chip simulator's first run: numba compiles its kernels once, and says so while it does.

numba compiles the chip's kernels (:mod:`robosoc.kernels`) the first time they run and keeps them
in its on-disk cache (under ``$ROBOSOC_CACHE/numba/<digest of the kernel sources>``).  On a fresh
install that takes on the order of a minute, during which a flight would sit silently at 0 %.  A
flight therefore first checks the cache (:func:`kernels_cached`) and, when it is empty, tells the
user and compiles by booting a throwaway chip with the firmware (:func:`warm_up_chip`), so that
the flight's progress bar and its real-time factor measure flying only.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from robosoc.config.scenario import ScenarioConfig

#: The kernel whose compiled form marks the cache as filled (the MPSoC's main loop).
MARKER = "chip.run_chip-*.nbi"

COMPILING = "compiling the chip simulator with numba (first run only, cached afterwards; about a minute) ..."


def numba_cache_dir() -> Path:
    """The folder numba keeps robosoc's compiled kernels in (set by :mod:`robosoc.kernels`)."""
    import numba

    import robosoc.kernels  # noqa: F401  (sets numba's cache folder)

    return Path(numba.config.CACHE_DIR)


def kernels_cached() -> bool:
    """Whether numba's cache holds the compiled chip kernels."""
    return any(numba_cache_dir().rglob(MARKER))


def warm_up_chip(scenario: ScenarioConfig, on_status: Callable[[str], None]) -> bool:
    """Compile the chip kernels if the cache lacks them, telling ``on_status`` first; whether it compiled.

    The compilation boots the scenario's firmware on a throwaway chip (the firmware must be built).
    """
    if kernels_cached():
        return False
    from robosoc.config.vehicle import vehicle_preset
    from robosoc.cosim.replay import FirmwareRun

    on_status(COMPILING)
    run = FirmwareRun(
        scenario.firmware, vehicle=vehicle_preset(scenario.vehicle), scenario=scenario, chip=scenario.chip
    )
    run.run_to(run.first_cycle)
    return True
