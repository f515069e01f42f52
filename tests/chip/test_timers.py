"""TIMER0/TIMER1 reads against an independent cycle-by-cycle model of the timer block.

The reference below steps the timer block one cycle at a time exactly as platform.md §2 words it
(registers reset to 0, the prescaler bit sampled through two registers, a pulse when it differs,
clear-on-compare with a toggling flag, a TIMER1 write lost in a pulse cycle); robosoc computes the
same values in closed form.  Programs of configuration writes and reads run on the core, and
every value read must equal the reference's value in the cycle before the load started.

Frames (§3): device cycle x (TIMER0 = x) is the clock of instruction cycle x + 1.  A load starting
in instruction cycle c reads device cycle c - 1; a device store starting in instruction cycle s
writes at the end of its *first* cycle, i.e. at the end of device cycle s - 1: the new value
holds from device cycle s (so a load right after the store, starting in s + 3, sees it).
"""

import random

import pytest

import rv32_asm as A
from core_harness import exit_with, make_soc

T0 = 5
TIMER0 = 0xE1024000
REGS = {"t1": 0x400, "pre": 0x410, "ctc": 0x420, "ocr": 0x430}
CAUSE_INV = 0xE1020800  # TIMERCAUSE_INV; -0x400 TIMERCAUSE, +0x400 TIMERMASK
S0CAUSE = 0xE1000400
IRQ = 0xF0000000


class TimerReference:
    """The timer block, one cycle per step."""

    def __init__(self) -> None:
        self.t1, self.pre, self.ctc, self.ocr, self.flag = 0, 0, 0xFFFF, 0, 0
        self.inv = self.mask = 0
        self.sample = [0, 0]  # the selected TIMER0 bit in cycles c-1 and c-2
        self.history: list[dict[str, int]] = []  # the readable values during each cycle

    def cause(self, cycle: int) -> int:
        return (
            ((cycle >> 16) & 1) | (((cycle >> 18) & 1) << 1) | (self.flag << 2)
            | ((1 if self.t1 < self.ocr else 0) << 3) | (((self.t1 >> 15) & 1) << 4)
        )  # fmt: skip

    def run(self, cycles: int, writes: dict[int, tuple[str, int]]) -> None:
        for c in range(cycles):
            cause = self.cause(c)
            line = 1 if (cause ^ self.inv) & self.mask else 0
            self.history.append(
                {"t1": self.t1, "cause": cause, "inv": self.inv, "mask": self.mask, "s0cause": line << 2}
            )
            pulse = self.sample[0] != self.sample[1]
            bit = 2 * self.pre
            self.sample = [(c >> bit) & 1, self.sample[0]]
            if pulse:
                if self.t1 != self.ctc:
                    self.t1 = (self.t1 + 1) & 0xFFFF
                else:
                    self.t1 = 0
                    self.flag ^= 1
            if c in writes:  # a store starting in instruction cycle c + 1: end of device cycle c
                reg, value = writes[c]
                if reg == "t1":
                    if not pulse:
                        self.t1 = value & 0xFFFF
                else:
                    setattr(self, reg, value & {"pre": 7, "inv": 0x1F, "mask": 0x1F}.get(reg, 0xFFFF))


def build(rng: random.Random) -> tuple[list[int], list[tuple[str, int, int]], dict[int, tuple[str, int]]]:
    """A straight-line program; returns words, reads (kind, register, start cycle), writes by cycle."""
    words = [*A.li(T0, TIMER0), *A.li(6, CAUSE_INV), *A.li(9, S0CAUSE)]
    cycle = 3 + 6  # cycle the next instruction starts in
    reads: list[tuple[str, int, int]] = []
    writes: dict[int, tuple[str, int]] = {}
    dest = 10
    where = {"t1": (T0, REGS["t1"]), "cause": (6, -0x400), "inv": (6, 0), "mask": (6, 0x400), "s0cause": (9, 0)}
    for _ in range(24):
        kind = rng.random()
        if kind < 0.35:
            reg = rng.choice(["pre", "ctc", "ocr", "t1", "inv", "mask"])
            value = {
                "pre": rng.randint(0, 3), "ctc": rng.randint(1, 60), "ocr": rng.randint(0, 60),
                "inv": rng.randint(0, 31), "mask": rng.randint(0, 31),
            }.get(reg, rng.randint(0, 40))  # fmt: skip
            base, off = (6, where[reg][1]) if reg in ("inv", "mask") else (T0, REGS[reg])
            words += [*A.li(7, value), A.store("sw", 7, base, off)]
            writes[cycle + 2 - 1] = (reg, value)  # the store starts in cycle + 2
            cycle += 2 + 3
        elif kind < 0.75 and dest < 28:
            which = rng.choice(["t1", "cause", "inv", "mask", "s0cause"])
            base, off = where[which]
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
        want = ref.history[start - 1][which]
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


def _after_store(value: int, store: list[int], load: list[int]) -> int:
    words = [*A.li(T0, TIMER0), *A.li(6, CAUSE_INV), *A.li(9, S0CAUSE), *A.li(8, IRQ)]
    words += [*A.li(7, value), *store, *load, *exit_with(0)]
    soc = make_soc(words)
    soc.run(max_cycles=10_000)
    return int(soc.regs[10]) & 0xFFFFFFFF


def test_a_device_store_is_seen_by_the_very_next_load():
    # The store starts in s and writes at the end of its first cycle (value from device cycle s);
    # the load right after it starts in s + 3 and reads device cycle s + 2: the new value.
    # OCR = 0xffff: TIMERCAUSE bit 3 (TIMER1 < OCR) reads 1 at once (with OCR = 0 it would be 0).
    assert _after_store(0xFFFF, [A.store("sw", 7, T0, REGS["ocr"])], [A.load("lw", 10, 6, -0x400)]) & 8 == 8
    # TIMERMASK = INV = 8 ... the line: S0CAUSE bit 2 set by the load right after the mask store
    store = [A.store("sw", 7, 6, 0), A.store("sw", 7, 6, 0x400)]
    assert _after_store(8, store, [A.load("lw", 10, 9, 0)]) == 4
    # IRQ_MASK / IRQ_STATUS read back right after the store
    assert _after_store(0x81, [A.store("sw", 7, 8, 0x20)], [A.load("lw", 10, 8, 0x20)]) == 0x81
    assert _after_store(1, [A.store("sw", 7, 8, 0x30)], [A.load("lw", 10, 8, 0x30)]) == 1


def test_timer1_write_lands_with_a_slow_prescaler():
    # PRE = 2 (/16: pulses when TIMER0 bit 4, sampled through two registers, changes: in device
    # cycles y with y - 1 a multiple of 16).  li t0 (3, 4); li t2 (5, 6); sw PRE (7..9: PRE = 2
    # from device 7); li t2 = 1000 (10, 11); sw TIMER1 (12..14): written at the end of device 11,
    # no pulse there (11 - 1 is not a multiple of 16), so TIMER1 = 1000 from device 12; the load
    # in 15 reads device 14: still 1000 (the next pulse is in device 17).
    words = [*A.li(T0, TIMER0), *A.li(7, 2), A.store("sw", 7, T0, REGS["pre"]), *A.li(7, 1000)]
    words += [A.store("sw", 7, T0, REGS["t1"]), A.load("lw", 10, T0, REGS["t1"])]
    words += [*[A.NOP] * 4, A.load("lw", 11, T0, REGS["t1"]), *exit_with(0)]
    soc = make_soc(words)
    soc.run()
    assert int(soc.regs[10]) == 1000
    # the second load starts in 15 + 3 + 4 = 22 and reads device 21: one pulse (device 17) later
    assert int(soc.regs[11]) == 1001
