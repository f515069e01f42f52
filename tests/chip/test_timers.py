"""TIMER0/TIMER1 reads against an independent cycle-by-cycle model of the timer block.

The reference below steps the timer block one cycle at a time exactly as platform.md §2 words it
(registers reset to 0, the prescaler bit sampled through two registers, a pulse when it differs,
clear-on-compare with a toggling flag, a TIMER1 write lost in a pulse cycle); robosoc computes the
same values in closed form.  Programs of configuration writes and reads run on the core, and
every value read must equal the reference's value in the cycle before the load started.
"""

import random

import pytest

import rv32_asm as A
from core_harness import exit_with, make_soc

T0 = 5
TIMER0 = 0xE1024000
REGS = {"t1": 0x400, "pre": 0x410, "ctc": 0x420, "ocr": 0x430}
CAUSE = 0xE1020400


class TimerReference:
    """The timer block, one cycle per step."""

    def __init__(self) -> None:
        self.t1, self.pre, self.ctc, self.ocr, self.flag = 0, 0, 0xFFFF, 0, 0
        self.sample = [0, 0]  # the selected TIMER0 bit in cycles c-1 and c-2
        self.history: list[tuple[int, int]] = []  # (t1, cause) during each cycle

    def cause(self, cycle: int) -> int:
        return (
            ((cycle >> 16) & 1) | (((cycle >> 18) & 1) << 1) | (self.flag << 2)
            | ((1 if self.t1 < self.ocr else 0) << 3) | (((self.t1 >> 15) & 1) << 4)
        )  # fmt: skip

    def run(self, cycles: int, writes: dict[int, tuple[str, int]]) -> None:
        for c in range(cycles):
            self.history.append((self.t1, self.cause(c)))
            pulse = self.sample[0] != self.sample[1]
            bit = 2 * self.pre
            self.sample = [(c >> bit) & 1, self.sample[0]]
            if pulse:
                if self.t1 != self.ctc:
                    self.t1 = (self.t1 + 1) & 0xFFFF
                else:
                    self.t1 = 0
                    self.flag ^= 1
            if c in writes:  # a store's write happens at the end of its last cycle
                reg, value = writes[c]
                if reg == "t1":
                    if not pulse:
                        self.t1 = value & 0xFFFF
                else:
                    setattr(self, reg, value & (7 if reg == "pre" else 0xFFFF))


def build(rng: random.Random) -> tuple[list[int], list[tuple[str, int, int]], dict[int, tuple[str, int]]]:
    """A straight-line program; returns words, reads (kind, register, start cycle), writes by cycle."""
    words = [*A.li(T0, TIMER0), *A.li(6, CAUSE)]
    cycle = 3 + 4
    reads: list[tuple[str, int, int]] = []
    writes: dict[int, tuple[str, int]] = {}
    dest = 10
    for _ in range(24):
        kind = rng.random()
        if kind < 0.35:
            reg = rng.choice(["pre", "ctc", "ocr", "t1"])
            value = {"pre": rng.randint(0, 3), "ctc": rng.randint(1, 60), "ocr": rng.randint(0, 60)}.get(
                reg, rng.randint(0, 40)
            )
            words += [*A.li(7, value), A.store("sw", 7, T0, REGS[reg])]
            writes[cycle + 2 + 2] = (reg, value)
            cycle += 2 + 3
        elif kind < 0.75 and dest < 28:
            which = rng.choice(["t1", "cause"])
            base, off = (T0, REGS["t1"]) if which == "t1" else (6, 0)
            words.append(A.load("lw", dest, base, off))
            reads.append((which, dest, cycle))
            dest += 1
            cycle += 3
        else:
            n = rng.randint(1, 90)
            words += [A.NOP] * n
            cycle += n
    return [*words, *exit_with(0)], reads, writes


@pytest.mark.parametrize("seed", range(16))
def test_timer_reads_match_the_cycle_by_cycle_reference(seed: int):
    rng = random.Random(seed)
    words, reads, writes = build(rng)
    soc = make_soc(words)
    soc.run(max_cycles=100_000)
    ref = TimerReference()
    ref.run(max(c for _, _, c in reads) + 2 if reads else 10, writes)
    for which, reg, start in reads:
        t1, cause = ref.history[start - 1]
        want = t1 if which == "t1" else cause
        got = int(soc.regs[reg]) & 0xFFFFFFFF
        assert got == want, f"{which} read starting in cycle {start}: core {got}, reference {want}"


def test_timer0_read_returns_previous_cycle():
    # lui (3) addi (4) lw (5..7) -> reads 4; nop x 10; lw starts at 18 -> reads 17
    words = [*A.li(T0, TIMER0), A.load("lw", 10, T0, 0), *[A.NOP] * 10, A.load("lw", 11, T0, 0), *exit_with(0)]
    soc = make_soc(words)
    soc.run()
    assert int(soc.regs[10]) == 4 and int(soc.regs[11]) == 17


def test_timer1_write_is_lost_with_the_undivided_prescaler():
    words = [*A.li(T0, TIMER0), *A.li(7, 1000), A.store("sw", 7, T0, REGS["t1"]), A.load("lw", 10, T0, REGS["t1"])]
    soc = make_soc([*words, *exit_with(0)])
    soc.run()
    # the load starts in cycle 10 and reads TIMER1 of cycle 9: 7 pulses (cycles 2..8), not 1000
    assert int(soc.regs[10]) == 7
