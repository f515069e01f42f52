"""The interrupt rules of platform.md §3, one hand-derived case at a time.

Frames (§3): instruction cycle n counts as in §1 (the first instruction executes in cycle 3, each
instruction adds its §1 cost); device cycle x is the value TIMER0 holds, and device cycle x is the
same clock as instruction cycle x + 1.  So a TIMER0 load starting in instruction cycle c returns
c - 1, and a device store starting in instruction cycle s holds its new value from device cycle s.

Rules used below (all §3):
  R1  a line rising in device cycle t (t = s for a mask/INV/status store starting in s) gives the
      request in instruction cycle t + 4 when the controller is idle;
  R2  entry at the first instruction boundary b >= t + 5, whatever instruction ended there; the
      instruction that would start at b is squashed, IRQ_EPC <- its address + 4, IRQ_STATUS.0 <- 0;
      the first vector instruction executes in b + 2 and b + 3, the second starts in b + 4 (so a
      TIMER0 load there returns b + 3);
  R3  after an entry the controller is idle again at device cycle s + 2 after the store (starting
      in s) that sets IRQ_STATUS.0: a line still high gives its request at s + 6; the first enable
      after reset (controller idle) gives it at s + 4;
  R4  a request, once the controller left idle, is held even if the line drops or IRQ_STATUS is
      cleared; a line high for one device cycle is still taken;
  R5  a MUL in [m, m + L) with the request r = t + 4 inside it: r <= m + L - 3 shadow case,
      r = m + L - 2 the MUL re-executes, r = m + L - 1 a normal entry (rtl mode); spec mode enters
      at m + L and reports the erratum.

TIMER1 with the reset prescaler (/1) pulses in every device cycle from 2 on, so it holds x - 2 in
device cycle x until it reaches TIMER1_CTC = C in device cycle C + 2: it reads 0 (and the
compare flag, TIMERCAUSE bit 2, toggles) in device cycle t = C + 3 and then counts 0, 1, 2...
(so a TIMER1 load starting in instruction cycle c then returns c - 1 - t).
"""

from __future__ import annotations

import importlib
import warnings

import pytest

import rv32_asm as A
from core_harness import exit_with, make_soc

single = importlib.import_module("robosoc.chip.single")

SRAM = 0x40000000
VEC = SRAM + 0x800  # the handler
FLAG = SRAM + 0x1000  # a data word
TIMER0 = 0xE1024000
IRQ = 0xF0000000
TCAUSE_INV = 0xE1020800  # TIMERCAUSE = -0x400, TIMERMASK = +0x400

T0, T3, T4, ONE, TMP, S11 = 5, 28, 29, 4, 6, 27  # TIMER0 base, IRQ base, TIMERCAUSE_INV base, 1
A1, A2, A3, A4, A5, A6, A7 = 11, 12, 13, 14, 15, 16, 17
S2, S3, S4 = 18, 19, 20
FLAGREG = 9  # holds FLAG


def cost(word: int) -> int:
    """§1 cost of a straight-line instruction (branches not taken; no MUL here)."""
    op = word & 0x7F
    assert not (op == 0x33 and word >> 25 == 1), "MUL costs depend on rs2: count them by hand"
    return 3 if op in (0x03, 0x23, 0x6F, 0x67) else 1


def start_of(words: list[int], index: int) -> int:
    """Start cycle of words[index] when words[0..index) run straight from reset (cycle 3)."""
    return 3 + sum(cost(w) for w in words[:index])


def addr(index: int) -> int:
    return SRAM + 4 * index


def sw_const(base: int, off: int, value: int) -> list[int]:
    return [*A.li(TMP, value), A.store("sw", TMP, base, off)]


def setup(line: str, ctc: int | None = None, ocr: int | None = None) -> list[int]:
    """Bases, IRQ_VECTOR, IRQ_MASK = 1 and the timer line; IRQ_STATUS stays 0 (the test enables).

    line "high": INV = MASK = 8: TIMERCAUSE bit 3 (TIMER1 < OCR = 0) is 0, inverted: the line is
    high from the mask store on.  "flag": MASK = 4, the CTC flag: rises in device cycle C + 3.
    "t1zero": MASK = 8 with OCR = 1: high only while TIMER1 = 0, i.e. in device cycle C + 3 only.
    """
    words = [*A.li(T0, TIMER0), *A.li(T3, IRQ), *A.li(T4, TCAUSE_INV), A.i("addi", ONE, 0, 1)]
    if ctc is not None:  # TIMER1 holds about 10 here: well below any C used
        words += sw_const(T0, 0x420, ctc)
    if ocr is not None:
        words += sw_const(T0, 0x430, ocr)
    words += sw_const(T3, 0x00, VEC) + A.li(FLAGREG, FLAG)
    if line == "high":
        words += sw_const(T4, 0, 8) + sw_const(T4, 0x400, 8)
    elif line == "flag":
        words += sw_const(T4, 0x400, 4)
    else:
        assert line == "t1zero" and ocr == 1
        words += sw_const(T4, 0x400, 8)
    return [*words, A.store("sw", ONE, T3, 0x20)]  # IRQ_MASK = 1


ENABLE = A.store("sw", ONE, T3, 0x30)  # IRQ_STATUS = 1
DISABLE = A.store("sw", 0, T3, 0x30)

# vector: a1 += 1 (the first vector instruction: twice), a2 = TIMER0 (second vector instruction,
# in b + 4: returns b + 3), a7 = TIMER1 (in b + 7: returns b + 6 - t), a3 = IRQ_EPC,
# a6 = IRQ_STATUS, then exit
H_EXIT = [
    A.i("addi", A1, A1, 1),
    A.load("lw", A2, T0, 0),
    A.load("lw", A7, T0, 0x400),
    A.load("lw", A3, T3, 0x40),
    A.load("lw", A6, T3, 0x30),
    *exit_with(0),
]

# vector that acknowledges (TIMERMASK = 0) and returns; with v2 = the second vector instruction's
# start: lw a2 [v2], lw a3 [v2+3], sw TIMERMASK [v2+6], lw s11 [v2+9], addi [v2+12],
# sw IRQ_STATUS [v2+13], jalr [v2+16]: the interrupted code resumes in v2 + 19.
H_RETURN = [
    A.i("addi", A1, A1, 1),
    A.load("lw", A2, T0, 0),
    A.load("lw", A3, T3, 0x40),
    A.store("sw", 0, T4, 0x400),
    A.load("lw", S11, T3, 0x40),
    A.i("addi", S11, S11, -4),
    ENABLE,
    A.jalr(0, S11, 0),
]
RESUME = 19  # v2 + 19


def layout(main: list[int], handler: list[int]) -> list[int]:
    assert 4 * len(main) <= VEC - SRAM
    return main + [A.NOP] * ((VEC - SRAM) // 4 - len(main)) + handler


def hits(result, erratum: str) -> int:
    """How many times the run hit ``erratum`` (RunResult.errata; the exact dict is checked in
    test_no_errata_no_warnings)."""
    return result.errata.get(erratum, 0)


def run(words: list[int], mul: bool = True, errata: str = "spec", max_cycles: int = 2_000_000):
    soc = make_soc(words, mul=mul, errata=errata)
    result = soc.run(max_cycles=max_cycles)
    return result, [int(v) & 0xFFFFFFFF for v in soc.regs]


# ------------------------------------------------------------------ entry point, EPC, first enable


def test_first_enable_with_the_line_already_high():
    # The line is high before IRQ_STATUS is set; the enable store starts in s: t = s (R1, the
    # controller is idle since reset), request in s + 4.  After the store (s..s+2) the nops run in
    # s+3, s+4, s+5: the boundaries are s+3, s+4, s+5 -> b = s + 5 >= t + 5, the third nop is
    # squashed: EPC = its address + 4.  a2 = b + 3 = s + 8.
    main = [*setup("high"), A.load("lw", A5, T0, 0), ENABLE]
    k = len(main) - 1
    main += [A.NOP] * 20 + exit_with(0)
    result, regs = run(layout(main, H_EXIT))
    s = start_of(main, k)
    assert regs[A5] == s - 4, "the TIMER0 load just before the store starts in s - 3"
    assert result.counters["interrupts"] == 1
    assert regs[A1] == 2, "the first vector instruction executes twice"
    assert regs[A2] == s + 8
    assert regs[A3] == addr(k + 3) + 4
    assert regs[A6] & 1 == 0, "the entry cleared IRQ_STATUS bit 0"


@pytest.mark.parametrize(
    "kind,nops,b_minus_s,squashed",
    [
        # enable in s (t = s); after it: `nops` nops, then 3-cycle instructions X1, X2, ...
        # 0 nops: X1 in s+3..s+5: cycles s+3, s+4 blocked, s+5 (X1's bubble) is >= t + 4: b = s + 6,
        #         X2 squashed (index 2 after the store)
        ("lw", 0, 6, 2), ("sw", 0, 6, 2), ("beq", 0, 6, 2), ("jal", 0, 6, 2),
        # 1 nop (s+3), X1 in s+4..s+6: b = s + 7 (X1's bubble s+6), X2 squashed (index 3)
        ("lw", 1, 7, 3), ("sw", 1, 7, 3), ("beq", 1, 7, 3), ("jal", 1, 7, 3),
        # 2 nops (s+3, s+4): b = s + 5 falls before X1, X1 itself is squashed (index 3)
        ("lw", 2, 5, 3), ("beq", 2, 5, 3),
        # auipc (s+3) + jalr (s+4..s+6) pairs: boundaries s+3, s+4, s+7: b = s + 7 (the jalr's
        # bubble s+6 is the acknowledge cycle), the second auipc squashed (index 3)
        ("jalr", 0, 7, 3),
        # not-taken branches cost 1: boundaries s+4, s+5 -> b = s + 5, the third one squashed
        ("bne", 0, 5, 3),
    ],
)  # fmt: skip
def test_acknowledge_at_the_first_boundary_after_t_plus_4(kind, nops, b_minus_s, squashed):
    unit = {
        "lw": [A.load("lw", A4, FLAGREG, 0)],
        "sw": [A.store("sw", A4, FLAGREG, 0)],
        "beq": [A.branch("beq", 0, 0, 4)],  # taken to pc + 4: still 3 cycles
        "jal": [A.jal(0, 4)],
        "jalr": [A.auipc(1, 0), A.jalr(0, 1, 8)],  # 1 + 3 cycles, to the next pair
        "bne": [A.branch("bne", 0, 0, 8)],  # never taken: 1 cycle, falls through
    }[kind]
    main = [*setup("high"), ENABLE]
    k = len(main) - 1
    main += [A.NOP] * nops + unit * 12 + exit_with(0)
    result, regs = run(layout(main, H_EXIT))
    s = start_of(main, k)
    b = s + b_minus_s
    assert result.counters["interrupts"] == 1
    assert regs[A1] == 2
    assert regs[A2] == b + 3, f"entry at b = s + {b_minus_s}"
    assert regs[A3] == addr(k + squashed) + 4


def test_a_line_high_for_a_single_cycle_is_taken():
    # OCR = 1, MASK = bit 3 (TIMER1 < OCR): the line is high only while TIMER1 = 0, i.e. in device
    # cycle t = C + 3 alone (TIMER1 = 1 from C + 4 on).  R4: the controller leaves idle on that
    # single cycle: request t + 4, entry at the first boundary >= t + 5 of a nop sled: b = t + 5.
    # a2 = b + 3; a7 (TIMER1 loaded in b + 7) = b + 6 - t = 11.
    main = [*setup("t1zero", ctc=200, ocr=1), ENABLE]
    sled = len(main)
    main += [A.NOP] * 300 + exit_with(0)
    t = 200 + 3
    assert start_of(main, sled) < t
    result, regs = run(layout(main, H_EXIT))
    b = t + 5
    assert result.counters["interrupts"] == 1
    assert regs[A2] == b + 3
    assert regs[A7] == 11
    assert regs[A3] == addr(sled + (b - start_of(main, sled))) + 4


@pytest.mark.parametrize("late", [0, 1])
def test_a_request_survives_clearing_irq_status(late):
    # The CTC flag line rises in t = C + 3.  A store clearing IRQ_STATUS starts in s_c.
    # late = 1: s_c = t + 1: in device cycle t IRQ_STATUS.0 is still 1, so the controller leaves
    #   idle in t; the request (t + 4) is held (R4) although IRQ_STATUS is 0 from t + 1 on.  The
    #   store runs t+1..t+3, the nops t+4, t+5: b = t + 5, the second nop after the store squashed.
    # late = 0: s_c = t: IRQ_STATUS is 0 in device cycle t already: nothing is ever latched.
    def program(c: int) -> tuple[list[int], int]:
        main = [*setup("flag", ctc=c), ENABLE] + [A.NOP] * 30
        k = len(main)
        return main + [DISABLE] + [A.NOP] * 20 + exit_with(0), k

    main, k = program(0)
    s_c = start_of(main, k)  # the same for every C (li is always two instructions)
    t = s_c - late
    main, k = program(t - 3)
    result, regs = run(layout(main, H_EXIT))
    if late:
        assert result.counters["interrupts"] == 1
        assert regs[A2] == t + 5 + 3
        assert regs[A3] == addr(k + 2) + 4
    else:
        assert result.counters["interrupts"] == 0 and regs[A1] == 0


def test_re_enable_while_the_line_is_high_requests_at_s_plus_6():
    # First entry as in test_first_enable_with_the_line_already_high: b1 = s + 5.  The handler
    # does not acknowledge; on its first pass (a1 = 2 after the double first instruction) it keeps
    # a2/a3 in s2/s3 and returns.  Timeline from v2 = b1 + 4: lw a2 [v2], lw a3 [v2+3],
    # addi [v2+6], bne not taken [v2+7], addi [v2+8], addi [v2+9], lw s11 [v2+10], addi [v2+13],
    # sw IRQ_STATUS [v2+14] = s', jalr [s'+3], back in the sled in s' + 6.
    # R3: idle at device s' + 2, the line is high: request s' + 6, entry at the first boundary
    # >= s' + 7: the resumed nop (EPC1 - 4) runs in s' + 6, b2 = s' + 7, the next nop squashed.
    handler = [
        A.i("addi", A1, A1, 1),
        A.load("lw", A2, T0, 0),
        A.load("lw", A3, T3, 0x40),
        A.i("addi", TMP, 0, 2),
        A.branch("bne", A1, TMP, 4 * 7),  # second entry (a1 = 4): to the exit
        A.i("addi", S2, A2, 0),
        A.i("addi", S3, A3, 0),
        A.load("lw", S11, T3, 0x40),
        A.i("addi", S11, S11, -4),
        ENABLE,
        A.jalr(0, S11, 0),
        *exit_with(0),
    ]
    main = [*setup("high"), ENABLE]
    k = len(main) - 1
    main += [A.NOP] * 60 + exit_with(0)
    result, regs = run(layout(main, handler))
    s = start_of(main, k)
    b1 = s + 5
    assert regs[S2] == b1 + 3 and regs[S3] == addr(k + 3) + 4
    s2 = b1 + 4 + 14
    b2 = s2 + 7
    assert result.counters["interrupts"] == 2 and regs[A1] == 4
    assert regs[A2] == b2 + 3
    assert regs[A3] == addr(k + 4) + 4, "the nop after the resumed one is squashed"


# ------------------------------------------------------------------ firmware wait loops


def _wait_loop(loop: list[int], c: int, handler: list[int], tail: list[int] | None = None):
    main = [*setup("flag", ctc=c), ENABLE]
    k = len(main)
    main += loop + (tail or [])
    return main, k


@pytest.mark.parametrize("c", [400, 401, 402, 30000])
def test_jump_to_self_is_interrupted(c):
    # `j .` from cycle j0 on: boundaries j0 + 3n.  t = C + 3, b = the first j0 + 3n >= C + 8; the
    # jump itself is squashed there: EPC = J + 4.  a2 = b + 3, a7 = b + 6 - t.
    main, k = _wait_loop([A.jal(0, 0)], c, H_EXIT)
    j0 = start_of(main, k)
    t = c + 3
    b = j0 + 3 * -(-(t + 5 - j0) // 3)
    result, regs = run(layout(main, H_EXIT))
    assert result.counters["interrupts"] == 1
    assert regs[A2] == b + 3
    assert regs[A7] == b + 6 - t
    assert regs[A3] == addr(k) + 4


@pytest.mark.parametrize("c", [400, 401, 402, 403, 30001])
def test_nop_jump_loop_is_interrupted(c):
    # `L: nop; j L` from cycle w0 on: the nop in w0 + 4n, the jump in w0 + 4n + 1 .. + 3.
    # Boundaries w0 + 4n (nop next: EPC = L + 4) and w0 + 4n + 1 (jump next: EPC = L + 8).
    main, k = _wait_loop([A.NOP, A.jal(0, -4)], c, H_EXIT)
    w0 = start_of(main, k)
    t = c + 3
    b = min(x for x in range(t + 5, t + 9) if (x - w0) % 4 in (0, 1))
    epc = addr(k) + (4 if (b - w0) % 4 == 0 else 8)
    result, regs = run(layout(main, H_EXIT))
    assert result.counters["interrupts"] == 1
    assert regs[A2] == b + 3
    assert regs[A3] == epc


@pytest.mark.parametrize("c", [400, 401, 402, 403, 404, 405, 20000])
def test_polling_loop_is_interrupted(c):
    # `P: lw a0, FLAG; beqz a0, P` from cycle p0 on, FLAG = 0: the lw in p0 + 6n, the (taken)
    # beqz in p0 + 6n + 3.  Boundaries p0 + 6n (lw next: EPC = P + 4) and p0 + 6n + 3 (beqz next:
    # EPC = P + 8).  The handler sets FLAG = 1, masks the line and returns; it resumes in
    # R = b + 4 + 19 (H_RETURN with one more store: see below).
    #   lw next:   lw [R..R+2] reads 1, beqz not taken [R+3], lw a5 = TIMER0 in R + 4: R + 3
    #   beqz next: beqz (a0 = 0) taken [R..R+2], lw [R+3..], beqz not taken [R+6], a5 = R + 6
    handler = [H_RETURN[0], H_RETURN[1], H_RETURN[2], A.store("sw", ONE, FLAGREG, 0), *H_RETURN[3:]]
    loop = [A.load("lw", 10, FLAGREG, 0), A.branch("beq", 10, 0, -4)]
    main, k = _wait_loop(loop, c, handler, tail=[A.load("lw", A5, T0, 0), *exit_with(0)])
    p0 = start_of(main, k)
    t = c + 3
    b = min(x for x in range(t + 5, t + 11) if (x - p0) % 6 in (0, 3))
    lw_next = (b - p0) % 6 == 0
    resume = b + 4 + RESUME + 3  # the extra store in the handler
    result, regs = run(layout(main, handler))
    assert result.counters["interrupts"] == 1
    assert regs[A2] == b + 3
    assert regs[A3] == addr(k) + (4 if lw_next else 8)
    assert regs[A5] == resume + (3 if lw_next else 6)
    assert result.exit_code == 0


# ------------------------------------------------------------------ entry latency seen by a handler


def test_entry_latency_spread_on_rv32i_code():
    # TIMER1 compare interrupts (CTC = 96: a match every 97 cycles, t = C + 3 + 97 n); the handler
    # reads TIMER1 first (its second instruction, in b + 4: returns b + 3 - t).  On RV32I code every
    # instruction lasts 1 or 3 cycles and its last cycle is an acknowledge point, so b is in
    # t+5 .. t+7 and the observed latency in 8 .. 10: a spread of exactly 2 over varied code.
    rec = 26  # s10: record pointer
    handler = [
        A.NOP,
        A.load("lw", A2, T0, 0x400),  # TIMER1
        A.store("sw", A2, rec, 0),
        A.i("addi", rec, rec, 4),
        A.load("lw", TMP, T4, 0),
        A.i("xori", TMP, TMP, 4),  # acknowledge: flip the CTC flag's INV bit
        A.store("sw", TMP, T4, 0),
        A.load("lw", S11, T3, 0x40),
        A.i("addi", S11, S11, -4),
        ENABLE,
        A.jalr(0, S11, 0),
    ]
    main = setup("flag", ctc=96) + A.li(rec, SRAM + 0x2000) + [ENABLE, A.i("addi", 7, 0, 300)]
    body = [
        A.load("lw", 10, FLAGREG, 0),
        A.i("addi", 10, 10, 1),
        A.branch("beq", 0, 0, 8),  # taken, skips the next
        A.NOP,
        A.store("sw", 10, FLAGREG, 4),
        A.r("xor", 12, 12, 10),
        A.jal(0, 4),
        A.i("addi", 7, 7, -1),
    ]
    main += [*body, A.branch("bne", 7, 0, -4 * len(body)), *exit_with(0)]
    soc = make_soc(layout(main, handler), mul=False)
    result = soc.run(max_cycles=1_000_000)
    n = result.counters["interrupts"]
    assert n > 50
    seen = [int.from_bytes(soc.state.read(SRAM + 0x2000 + 4 * i, 4), "little") for i in range(n)]
    assert set(seen) == {8, 9, 10}


# ------------------------------------------------------------------ interrupts and the multiplier

MUL_L = 37  # rs2 = 0xffffffff (§1)


def _mul_program(c: int, shadow: str):
    """setup, then `mul s4, s2, s3` (37 cycles) at M, then the shadow, then a5 = TIMER0, exit.

    shadow "addi": M+4 `addi a4, a4, 1`.  shadow "jal": M+4 `jal x0, M+12`, M+8 `addi a4, a4, 1`,
    M+12: a5 = TIMER0, a6 = IRQ_STATUS, a7 = IRQ_EPC, exit.
    """
    main = setup("flag", ctc=c) + A.li(S3, 0xFFFFFFFF) + A.li(S2, 3) + [ENABLE] + [A.NOP] * 40
    k = len(main)
    main += [A.r("mul", S4, S2, S3)]
    if shadow == "addi":
        main += [A.i("addi", A4, A4, 1), A.load("lw", A5, T0, 0), *exit_with(0)]
    else:
        main += [A.jal(0, 8), A.i("addi", A4, A4, 1)]
        main += [A.load("lw", A5, T0, 0), A.load("lw", A6, T3, 0x30), A.load("lw", A7, T3, 0x40), *exit_with(0)]
    m = start_of(main, k)
    return main, k, m


def _run_mul(c: int, shadow: str, errata: str):
    main, k, m = _mul_program(c, shadow)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result, regs = run(layout(main, H_RETURN), errata=errata)
    return result, regs, caught, addr(k), m


def _c_for(r: int) -> int:
    return r - 4 - 3  # r = t + 4, t = C + 3


def _irq_mul_warnings(caught) -> list:
    return [w for w in caught if issubclass(w.category, single.IrqDuringMulErratum)]


@pytest.mark.parametrize("r_off", [0, 1, MUL_L - 3])  # r = m + r_off <= m + L - 3
def test_rtl_mul_case_shadow_runs_then_vector_once(r_off):
    # rtl, r <= m + L - 3: the shadow (a4 += 1) runs in m + L; the first vector instruction once in
    # m + L + 1 (a1 = 1), the second (TIMER0) in v2 = m + L + 2: a2 = m + L + 1; EPC = M + 8;
    # IRQ_STATUS.0 = 0.  H_RETURN resumes at EPC - 4 = M + 4 in v2 + 19 = m + L + 21: the shadow
    # runs again (a4 = 2), a5 = TIMER0 loaded in m + L + 22 -> m + L + 21.
    m0 = _mul_program(100, "addi")[2]
    result, regs, _, mul_at, m = _run_mul(_c_for(m0 + r_off), "addi", "rtl")
    assert m == m0
    L = MUL_L
    assert regs[S4] == (3 * 0xFFFFFFFF) & 0xFFFFFFFF
    assert regs[A4] == 2, "the shadow executes twice"
    assert regs[A1] == 1, "the first vector instruction executes once"
    assert regs[A2] == m + L + 1
    assert regs[A3] == mul_at + 8
    assert regs[A5] == m + L + 21
    assert result.counters["interrupts"] == 1
    assert hits(result, "irq_during_mul") == 1


def test_rtl_mul_then_taken_jump_loses_the_vector():
    # rtl, r <= m + L - 3, the shadow is `jal x0, M+12`: it runs m+L..m+L+2 and its redirect drops
    # the vector: the handler never runs (a1 = 0), IRQ_STATUS.0 stays 0, EPC = M + 8; M+12 starts
    # in m + L + 3: a5 = m + L + 2.  The skipped addi at M+8 never runs.
    m0 = _mul_program(100, "jal")[2]
    result, regs, _, mul_at, m = _run_mul(_c_for(m0 + 2), "jal", "rtl")
    L = MUL_L
    assert regs[A1] == 0, "the handler never ran"
    assert result.counters["interrupts"] == 0
    assert regs[A5] == m + L + 2
    assert regs[A6] & 1 == 0, "interrupts remain off"
    assert regs[A7] == mul_at + 8
    assert regs[A4] == 0
    assert hits(result, "irq_during_mul") == 1


def test_rtl_mul_case_mul_executes_again():
    # rtl, r = m + L - 2: EPC = M + 4; the first vector instruction in m+L+1 and m+L+2 (a1 = 2),
    # the second in v2 = m + L + 3: a2 = m + L + 2.  Resume at M in v2 + 19 = m + L + 22: the MUL
    # runs again (L cycles), the shadow in m + 2L + 22 (a4 = 1), a5 = TIMER0 in m + 2L + 23.
    m0 = _mul_program(100, "addi")[2]
    L = MUL_L
    result, regs, _, mul_at, m = _run_mul(_c_for(m0 + L - 2), "addi", "rtl")
    assert regs[A1] == 2
    assert regs[A2] == m + L + 2
    assert regs[A3] == mul_at + 4
    assert regs[A4] == 1
    assert regs[A5] == m + 2 * L + 22
    assert regs[S4] == (3 * 0xFFFFFFFF) & 0xFFFFFFFF
    assert result.counters["interrupts"] == 1
    assert hits(result, "irq_during_mul") == 1


@pytest.mark.parametrize("errata", ["rtl", "spec"])
def test_mul_request_in_its_last_cycle_is_a_normal_entry(errata):
    # r = m + L - 1: the MUL's last cycle is an acknowledge point: entry at b = m + L (the shadow
    # squashed), EPC = M + 8, a1 = 2, a2 = b + 3; resume at M + 4 in b + 4 + 19: the shadow runs
    # once (a4 = 1), a5 = TIMER0 in b + 24 -> m + L + 23.  Nothing went wrong on the RTL: no
    # erratum (counted 0, no warning).
    m0 = _mul_program(100, "addi")[2]
    L = MUL_L
    result, regs, caught, mul_at, m = _run_mul(_c_for(m0 + L - 1), "addi", errata)
    b = m + L
    assert regs[A1] == 2 and regs[A2] == b + 3 and regs[A3] == mul_at + 8
    assert regs[A4] == 1 and regs[A5] == b + 23
    assert hits(result, "irq_during_mul") == 0
    assert not _irq_mul_warnings(caught)


@pytest.mark.parametrize("errata", ["rtl", "spec"])
def test_request_just_before_a_mul_squashes_it(errata):
    # r = m - 1: the boundary m itself is >= r + 1: entry before the MUL, which is squashed
    # (EPC = M + 4), a2 = m + 3; resume at M in m + 4 + 19: the MUL runs once in full
    # (m+23 .. m+L+22), the shadow in m + L + 23, a5 = m + L + 23.  No erratum.
    m0 = _mul_program(100, "addi")[2]
    L = MUL_L
    result, regs, caught, mul_at, m = _run_mul(_c_for(m0 - 1), "addi", errata)
    assert regs[A1] == 2 and regs[A2] == m + 3 and regs[A3] == mul_at + 4
    assert regs[A4] == 1 and regs[A5] == m + L + 23
    assert hits(result, "irq_during_mul") == 0
    assert not _irq_mul_warnings(caught)


@pytest.mark.parametrize("r_off", [0, 1, MUL_L - 3, MUL_L - 2])
def test_spec_mul_interrupt_enters_where_the_mul_ends(r_off):
    # spec, r in m .. m + L - 2 (an erratum on the RTL): entry at b = m + L like any other
    # instruction boundary: the shadow squashed, EPC = M + 8, a1 = 2, a2 = b + 3, the shadow
    # once after the return (a4 = 1), a5 = b + 23.  Counted and warned once, naming the MUL's pc.
    m0 = _mul_program(100, "addi")[2]
    L = MUL_L
    result, regs, caught, mul_at, m = _run_mul(_c_for(m0 + r_off), "addi", "spec")
    b = m + L
    assert regs[A1] == 2 and regs[A2] == b + 3 and regs[A3] == mul_at + 8
    assert regs[A4] == 1 and regs[A5] == b + 23
    assert regs[S4] == (3 * 0xFFFFFFFF) & 0xFFFFFFFF
    assert result.counters["interrupts"] == 1
    assert hits(result, "irq_during_mul") == 1
    found = _irq_mul_warnings(caught)
    assert len(found) == 1 and issubclass(found[0].category, single.RtlErratum)
    assert f"{mul_at:08x}" in str(found[0].message).lower()


def test_spec_mul_then_jump_is_a_normal_entry():
    # spec, same program as the rtl `mul; j` case: entry at b = m + L, the jal squashed,
    # EPC = M + 8, a1 = 2; resume at the jal in b + 4 + 19; M+12 starts in b + 26: a5 = b + 25;
    # IRQ_STATUS = 1 again (the handler's return), IRQ_EPC = M + 8.
    m0 = _mul_program(100, "jal")[2]
    L = MUL_L
    result, regs, caught, mul_at, m = _run_mul(_c_for(m0 + 2), "jal", "spec")
    b = m + L
    assert regs[A1] == 2 and regs[A2] == b + 3 and regs[A3] == mul_at + 8
    assert regs[A5] == b + 25 and regs[A6] & 1 == 1 and regs[A7] == mul_at + 8
    assert regs[A4] == 0
    assert result.counters["interrupts"] == 1
    assert hits(result, "irq_during_mul") == 1
    assert len(_irq_mul_warnings(caught)) == 1


# ------------------------------------------------------------------ MULHSU


@pytest.mark.parametrize("errata", ["spec", "rtl"])
def test_mulhsu_result_and_report(errata):
    # rs1 = -2 (signed), rs2 = 3 (unsigned): RISC-V MULHSU = high word of -6 = 0xffffffff; the
    # RTL returns MULHU = high word of 0xfffffffe * 3 = 0x2_fffffffa -> 2.  Executed twice.
    main = [*A.li(S2, -2), *A.li(S3, 3), A.r("mulhsu", A1, S2, S3)]
    k = len(main) - 1
    main += [A.r("mulhsu", A2, S2, S3), *exit_with(0)]
    soc = make_soc(main, errata=errata)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = soc.run(max_cycles=10_000)
    regs = [int(v) & 0xFFFFFFFF for v in soc.regs]
    want = 0xFFFFFFFF if errata == "spec" else 2
    assert regs[A1] == regs[A2] == want
    assert hits(result, "mulhsu") == 2
    assert hits(result, "irq_during_mul") == 0
    if errata == "spec":
        found = [w for w in caught if issubclass(w.category, single.MulhsuErratum)]
        assert len(found) == 1, "one warning per run"
        assert issubclass(single.MulhsuErratum, single.RtlErratum)
        assert issubclass(single.RtlErratum, UserWarning)
        assert f"{addr(k):08x}" in str(found[0].message).lower()


def test_no_errata_no_warnings():
    main = [*A.li(S2, -2), *A.li(S3, 3), A.r("mulhu", A1, S2, S3), A.r("mul", A2, S2, S3), *exit_with(0)]
    soc = make_soc(main)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = soc.run(max_cycles=10_000)
    assert result.errata == {"mulhsu": 0, "irq_during_mul": 0}
    assert not [w for w in caught if issubclass(w.category, single.RtlErratum)]
