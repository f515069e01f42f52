"""Semaphores, delays, yields and best-effort round robin (programs/sync.c)."""

import pytest
from kernel_harness import BUILDS, CORE, build, run

from robosoc.host.images import read_stats

TICK = 262_144  # the default
DELAY = 3


@pytest.mark.parametrize("mul", BUILDS)
def test_semaphores_delays_yields_round_robin(mul):
    elf = build("sync.c", mul, DELAY=DELAY)
    chip, result = run({CORE: elf})
    assert result.exit_codes[CORE] == 0
    raw = chip.cores.read(chip.programs[1].address_of("results"), 64 * 4, tile=1)
    words = [int.from_bytes(raw[4 * i : 4 * i + 4], "little") for i in range(64)]
    # os_delay(DELAY) called after tick t returns after tick t + DELAY, which rises in cycle
    # (t + DELAY) * TICK + 2; the delayer has the highest priority but the checker (blocked)
    for k in range(3):
        t, woke = words[2 * k], words[2 * k + 1]
        assert (t + DELAY) * TICK + 2 < woke < (t + DELAY) * TICK + 2 + 3000
    # ping-pong: each handover goes through a voluntary switch, B runs after A blocked
    pairs = list(zip(words[8:24:2], words[9:24:2], strict=True))
    assert all(0 < b - a < 3000 for a, b in pairs)
    # two yielders of equal priority alternate (they run before the first tick, which would also
    # pass the turn on: the tick is long enough)
    entries = [(chr(w >> 24), w & 0xFFFFFF) for w in words[40:48]]
    assert entries == [(letter, 0) for letter in "ABABABAB"]
    # two spinners of equal priority that never yield both ran: round robin at ticks
    assert words[60] > 0 and words[61] > 0
    assert read_stats(chip, CORE).switches > 2 * 8
