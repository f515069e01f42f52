"""TIMERCAUSE bits that only show late or at equality (platform.md memory map): bit 1 is TIMER0[18]
(not a neighbouring bit), bit 3 is TIMER1 < OCR (strictly).  Cycle frames as in test_timers.py: a
load starting in instruction cycle c reads device cycle c - 1."""

from __future__ import annotations

import pytest

import rv32_asm as A
from core_harness import exit_with, run_words

TIMER0 = 0xE1024000
TIMER1, TIMER1_PRE, TIMER1_OCR = 0xE1024400, 0xE1024410, 0xE1024430
TIMERCAUSE = 0xE1020400


@pytest.mark.parametrize(("until", "bits"), [(0x30000, 0b01), (0x40000, 0b10), (0x50000, 0b11)])
def test_timer0_bits_16_and_18_in_timercause(until: int, bits: int) -> None:
    """Spin until TIMER0 >= ``until``; the last TIMER0 load read a0 in [until, until + 5] (a loop
    iteration is lw 3 + taken branch 3), the next load of TIMERCAUSE starts 4 cycles later and reads
    device cycle a0 + 4: bit 0 = bit 16 and bit 1 = bit 18 of it."""
    words = [*A.li(5, TIMER0), *A.li(7, until), *A.li(28, TIMERCAUSE)]
    words += [A.load("lw", 10, 5, 0), A.branch("bltu", 10, 7, -4)]  # back to the load while a0 < until
    words += [A.load("lw", 11, 28, 0), A.i("andi", 11, 11, 3), *exit_with(11)]
    _, result = run_words(words, max_cycles=2_000_000)
    assert result.exit_code == bits


@pytest.mark.parametrize(("ocr", "below"), [(5, 0), (6, 1), (4, 0)])
def test_timer1_below_ocr_is_strict(ocr: int, below: int) -> None:
    """TIMER1 prescaled by 16384 does not move in the first 16384 cycles: set it to 5, OCR to ``ocr``,
    and read TIMERCAUSE bit 3 (TIMER1 < OCR)."""
    words = [*A.li(5, TIMER1), *A.li(6, 7), A.store("sw", 6, 5, 0x10)]  # TIMER1_PRE = 7: /16384
    words += [*A.li(6, 5), A.store("sw", 6, 5, 0), *A.li(6, ocr), A.store("sw", 6, 5, 0x30)]
    words += [*A.li(28, TIMERCAUSE), A.load("lw", 11, 28, 0), A.shift("srli", 11, 11, 3), A.i("andi", 11, 11, 1)]
    words += [A.load("lw", 12, 5, 0), A.shift("slli", 12, 12, 1), A.r("or", 11, 11, 12), *exit_with(11)]
    _, result = run_words(words)
    assert result.exit_code == below | (5 << 1)  # and TIMER1 still reads 5
