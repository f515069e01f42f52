"""Building and running kernel test programs on the MPSoC (tests/firmware/kernel/programs)."""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from pathlib import Path

import pytest

from robosoc.chip.mpsoc import ChipResult, MPSoC
from robosoc.config.chip import ChipConfig
from robosoc.host import images
from robosoc.program.elf import load_elf

PROGRAMS = Path(__file__).parent / "programs"
#: every kernel test runs in both builds
BUILDS = [pytest.param(True, id="mul"), pytest.param(False, id="nomul")]

#: (x, y) of the one core of the 2x1 chip most tests use; the I/O tile is (0, 0)
CORE = (1, 0)
SMALL = ChipConfig(width=2, height=1)

#: NoC routing latency R of the default configuration: a packet of L flits over h hops has its
#: last flit in the receive memory (h + 1)(R + 1) + L - 1 cycles after its first flit entered the
#: source router on an idle network (docs/noc.md), and is visible one cycle later (docs/platform.md).
R = SMALL.noc.routing_latency


def build(program: str, mul: bool, **defines: str | int | None) -> Path:
    return images.build([PROGRAMS / program], mul=mul, defines=defines)


def run(
    elfs: Mapping[tuple[int, int], Path],
    config: ChipConfig = SMALL,
    injections: Iterable[tuple[tuple[int, int], list[int], int]] = (),
    max_cycles: int = 50_000_000,
) -> tuple[MPSoC, ChipResult]:
    """Load each ELF on its tile, queue the I/O tile's packets (dest, payload, cycle), run to the end."""
    chip = MPSoC(config)
    for xy, elf in elfs.items():
        chip.load(xy, load_elf(elf, chip.regions(xy)))
    for dest, payload, cycle in injections:
        chip.inject(dest, payload, cycle)
    result = chip.run(max_cycles=max_cycles)
    return chip, result


def packet_visible(inject_cycle: int, hops: int, flits: int) -> int:
    """Device cycle from which a packet injected by the I/O tile waits in the receive memory."""
    return inject_cycle + (hops + 1) * (R + 1) + flits - 1 + 1
