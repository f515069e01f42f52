"""The translating engines against the interpreter on hand-made and random programs: interrupts,
self-modifying code, every error, and the translator's cache (docs/translation.md).

Each comparison runs the same words on a fresh core with the interpreter and with the engine and
requires the same outcome: exit code or error message, cycles, counters, state, registers and
memory.  The random programs are the interrupt-heavy ones of ``test_irq_differential`` (timer
interrupts at random periods, polling loops, critical sections, device reads, multiplies).
"""

from __future__ import annotations

import threading
import warnings
from pathlib import Path

import numpy as np
import pytest
import test_irq_differential as irq

import robosoc.jit.policy as jit_policy
import robosoc.jit.tables as jit_tables
import rv32_asm as A
from core_harness import exit_with, make_soc
from robosoc.chip.core_state import SRAM_BASE
from robosoc.chip.single import CoreError, CycleBudgetExceeded, SingleCoreSoC
from robosoc.jit.compiler import Compiler
from robosoc.jit.emit_ir import (
    MUL_WORST_CYCLES,
    MemoryCheck,
    emit_region,
    memory_checks,
    multiplier_tail_table,
)
from robosoc.jit.regions import CodeView, discover
from robosoc.jit.target import Target
from robosoc.kernels.core import _MUL_CHUNK, mul_latency
from robosoc.kernels.core_layout import S_CYCLE, S_RUN
from robosoc.kernels.jit_dispatch import CTX_FLUSHES, CTX_STEPS, JitArrays

ENGINES = ["jit", "auto"]
#: random programs per flavour: each is new code, compiled afresh (the comparison costs compile time)
SEEDS = {"jit": 3, "auto": 2}


def outcome(soc: SingleCoreSoC, max_cycles: int) -> tuple[object, dict[str, np.ndarray]]:
    """(exit code or error text, the core's arrays) after running ``soc``."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            result: object = (soc.run(max_cycles=max_cycles).exit_code, soc.counters())
        except (CoreError, CycleBudgetExceeded) as exc:
            result = (type(exc).__name__, str(exc), soc.counters())
    arrays = {n: getattr(soc.state, n).copy() for n in ("st", "ctr", "opc", "regs", "m8")}
    return result, arrays


def assert_same(words: list[int], engine: str, max_cycles: int = 200_000, code_words: int | None = None, **kw):
    """Run ``words`` with the interpreter and with ``engine``; everything must be equal.  Returns the engine's SoC."""
    runs = []
    for name in ("interp", engine):
        soc = make_soc(words, engine=name, **kw)
        if code_words is not None:  # only the program is code: stores beyond it run translated
            soc.state.set_code_size(4 * code_words)
            soc.forget_translations()
        runs.append((soc, *outcome(soc, max_cycles)))
    (_, want, want_arrays), (soc, got, got_arrays) = runs
    assert got == want
    for name, arr in want_arrays.items():
        assert np.array_equal(got_arrays[name], arr), f"{name} differs"
    return soc


# ---------------------------------------------------------------- random programs with interrupts


@pytest.mark.parametrize("engine", ENGINES)
@pytest.mark.parametrize("mul,errata", irq.FLAVOURS, ids=["rv32i", "rv32im-spec", "rv32im-rtl"])
def test_random_interrupt_programs_run_as_on_the_interpreter(mul: bool, errata: str, engine: str, monkeypatch) -> None:
    if engine == "auto":
        # these runs are short: auto's budget would leave them to the interpreter, and its compiling
        # thread deliver after they end, unless the jit variant ran first in this process and left
        # its regions (the test must not rely on that)
        monkeypatch.setattr(jit_policy, "AUTO_BACKGROUND", False)
        monkeypatch.setattr(jit_policy, "AUTO_COMPILE_SHARE", 1e9)
        monkeypatch.setattr(jit_policy, "STRETCHES", {"auto": 50})  # samples often enough to find hot words
    translated = 0
    for k in range(SEEDS[engine]):
        words, _ = irq.build(7000 + 100 * irq.FLAVOURS.index((mul, errata)) + k, mul, errata)
        # alternately with the whole SRAM as code (every store is the interpreter's) and with only
        # the program as code (stores to the records run translated)
        code = None if k % 2 == 0 else len(words)
        soc = assert_same(words, engine, irq.MAX_CYCLES, code, mul=mul, sram_size=irq.SRAM_SIZE, errata=errata)
        translated += soc.translator.stats.instructions + soc.translator.stats.reused
    assert translated > 0


def test_random_interrupt_programs_are_mostly_translated() -> None:
    """The comparison above is only worth something if the engine runs most instructions itself."""
    words, _ = irq.build(7001, True, "spec")
    soc = assert_same(words, "jit", irq.MAX_CYCLES, len(words), mul=True, sram_size=irq.SRAM_SIZE)
    steps = int(soc.translator.tables().ctx[CTX_STEPS])
    assert soc.counters()["interrupts"] >= 5
    assert steps < soc.counters()["instructions"] // 2


# ---------------------------------------------------------------- self-modifying code


@pytest.mark.parametrize("engine", ENGINES)
@pytest.mark.parametrize("width", ["sw", "sh", "sb"])
def test_a_store_into_translated_code_is_seen(width: str, engine: str) -> None:
    # a loop runs `addi x10, x10, 1` (translated), then rewrites it to `addi x10, x10, 100` and runs again
    target = SRAM_BASE + 4 * 6
    new = A.i("addi", 10, 10, 100)
    value = {"sw": new, "sh": new >> 16, "sb": new >> 24}[width]
    offset = {"sw": 0, "sh": 2, "sb": 3}[width]
    words = [
        *A.li(5, target + offset),  # 2 words
        *A.li(6, value),  # 2 words
        A.i("addi", 7, 0, 50),  # loop count
        A.i("addi", 8, 0, 2),  # passes
        A.i("addi", 10, 10, 1),  # target (word 6)
        A.i("addi", 7, 7, -1),
        A.branch("bne", 7, 0, -8),
        A.store(width, 6, 5, 0),  # rewrite the target
        A.i("addi", 7, 0, 50),
        A.i("addi", 8, 8, -1),
        A.branch("bne", 8, 0, -24),
        *exit_with(10),
    ]
    soc = assert_same(words, engine, 100_000, len(words))
    # the stale translation would add 1 in both passes: 100; the rewritten word adds more
    assert int(soc.regs[10]) > 100
    if engine == "jit":
        assert soc.translator.tables().ctx[CTX_FLUSHES] >= 1  # the translation was forgotten


# ---------------------------------------------------------------- the edges of memory

EDGE_SRAM = 64 * 1024


@pytest.mark.parametrize("width", ["w", "h", "b"])
@pytest.mark.parametrize("where", ["code start", "data start", "memory end"])
def test_accesses_at_the_edges_of_code_and_memory_are_the_interpreters(width: str, where: str) -> None:
    """A translated load or store one check decides (inside the data part, aligned) against the
    interpreter at every offset around the end of the code and the end of SRAM: stores into the
    code, misaligned accesses and accesses past the end leave to the interpreter (or its error)."""
    body = [A.i("addi", 11, 0, 3)] * 5
    tail = 10  # words after the body: li (2), store, load, exit_with
    code_words = len(body) + tail
    edge = {"code start": 0, "data start": 4 * code_words, "memory end": EDGE_SRAM}[where]
    for delta in (-4, -3, -2, -1, 0, 1, 2, 3, 4):
        off = edge + delta
        words = [
            *body,
            *A.li(6, SRAM_BASE + off),
            A.i("addi", 10, 0, 0x5A5),
            A.store("s" + width, 10, 6, 0),
            A.load("l" + width if width == "w" else "l" + width + "u", 12, 6, 0),
            *exit_with(12),
        ]
        words += [A.NOP] * (code_words - len(words))
        assert len(words) == code_words, (len(words), code_words)
        assert_same(words, "jit", 5_000, code_words, sram_size=EDGE_SRAM)


#: accesses through one base register (name, offset), checked as groups: stores, then loads
GROUPS = {
    "words": [("sw", 0), ("sw", 4), ("sw", 8), ("sw", 12), ("lw", 12), ("lw", 0), ("lw", 8)],
    # the span ends a byte past a word: with the word at SRAM's last word, the byte is past the end
    "word and byte": [("sw", 0), ("sb", 4), ("lw", 0), ("lbu", 4)],
    "mixed widths": [("sw", 4), ("sh", 2), ("sb", 1), ("sh", 10), ("lhu", 6), ("lw", 8), ("lb", -1), ("lbu", 3)],
    # a wider access after a narrower one aligns the group: the halfword at 1 is never aligned
    # when the word at 0 is (two groups), the one at 6 always is
    "wider later": [("lh", 1), ("lw", 0), ("lhu", 6)],
    # the halfword at 1 is never aligned when the word at 0 is: two groups, one of them always leaves
    "no common alignment": [("sb", 7), ("sw", 0), ("sh", 1), ("lh", -3), ("lw", 4), ("lbu", 2)],
}


@pytest.mark.parametrize("group", sorted(GROUPS))
@pytest.mark.parametrize("where", ["code start", "data start", "memory end"])
def test_grouped_accesses_at_the_edges_are_the_interpreters(group: str, where: str, monkeypatch) -> None:
    """Accesses through one base register are checked once, before the first of them: at every
    base around the ends of the code and of SRAM, aligned or not, the translated block does what
    the interpreter does (the block leaves before the group, and the interpreter makes each access
    or raises its error at the one that fails)."""
    accesses = GROUPS[group]
    body = [A.i("addi", 11, 0, 3)] * 5
    code_words = len(body) + 2 + 1 + len(accesses) + 2 * (len(accesses) - 1) + 8
    edge = {"code start": 0, "data start": 4 * code_words, "memory end": EDGE_SRAM}[where]
    for delta in range(-6, 7):
        words = [*body, *A.li(6, SRAM_BASE + edge + delta), A.i("addi", 10, 0, 0x5A5)]
        loaded = []
        for k, (name, imm) in enumerate(accesses):
            if name.startswith("s"):
                words.append(A.store(name, 10, 6, imm))
            else:
                loaded.append(12 + k)
                words.append(A.load(name, 12 + k, 6, imm))
        for r in loaded[1:]:
            words.append(A.r("xor", loaded[0], loaded[0], r))
        words += exit_with(loaded[0])
        words += [A.NOP] * (code_words - len(words))
        assert len(words) == code_words, (len(words), code_words)
        # translated afresh: a region left by an earlier base (which started inside the group, after
        # a way out) would split the group
        monkeypatch.setattr(jit_tables, "_TRANSLATED", {})
        assert_same(words, "jit", 5_000, code_words, sram_size=EDGE_SRAM)


def test_accesses_through_one_base_are_checked_once() -> None:
    """A register save and restore is one check each; a write to the base, the other kind of
    access or an alignment no one test covers starts another check."""
    sp, a0 = 2, 10
    words = [
        *(A.store("sw", r, sp, 4 * r) for r in range(8, 12)),  # one check
        *(A.load("lw", r, sp, 4 * r) for r in range(12, 16)),  # one check (loads)
        A.store("sb", 8, sp, 1),  # with the stores above? no: the loads did not write sp, so yes
        A.i("addi", sp, sp, -16),  # writes the base: what follows is checked again
        A.load("lw", a0, sp, 0),
        A.load("lw", 11, a0, 0),  # another base
        A.load("lh", 12, a0, 1),  # never aligned with the word at 0: its own check
        A.jal(0, 0),
    ]
    view = CodeView(lambda a: words[(a - SRAM_BASE) >> 2], SRAM_BASE, 4 * len(words), EDGE_SRAM, True)
    (block,) = discover(view, SRAM_BASE).blocks.values()
    checks = memory_checks(block.insns, Target(SRAM_BASE, EDGE_SRAM, 4 * len(words), False))
    assert sorted(checks) == [0, 4, 10, 11, 12]
    assert checks[0] == MemoryCheck(start=4 * len(words), low=1, span=47, align=3, anchor=32)
    assert checks[4] == MemoryCheck(start=0, low=48, span=16, align=3, anchor=48)
    assert checks[12] == MemoryCheck(start=0, low=1, span=2, align=1, anchor=1)
    # with 8 bytes of data after the code, no group of stores may span more: pairs of words
    data = 4 * len(words)
    stores = {j: c for j, c in memory_checks(block.insns, Target(SRAM_BASE, data + 8, data, False)).items() if c.start}
    assert stores == {
        0: MemoryCheck(start=data, low=32, span=8, align=3, anchor=32),
        2: MemoryCheck(start=data, low=40, span=8, align=3, anchor=40),
        8: MemoryCheck(start=data, low=1, span=1, align=0, anchor=1),
    }


# ---------------------------------------------------------------- errors


ERROR_PROGRAMS = {
    "illegal": [A.NOP, 0xFFFFFFFF],
    "div": [A.r("div", 10, 11, 12)],
    "misaligned load": [*A.li(6, SRAM_BASE + 0x100), A.load("lw", 10, 6, 2)],
    "misaligned store": [*A.li(6, SRAM_BASE + 0x100), A.store("sh", 10, 6, 3)],
    "unmapped load": [*A.li(6, 0x20000000), A.load("lw", 10, 6, 0)],
    "unmapped store": [*A.li(6, 0xE2000000), A.store("sb", 10, 6, 0)],
    "read-only store": [*A.li(6, 0xE1024000), A.store("sw", 10, 6, 0)],
    "jump outside": [A.jal(0, 0x10000)],
    "misaligned jalr": [*A.li(6, SRAM_BASE + 0x102), A.jalr(1, 6, 0)],
    "fall off the code": [A.NOP, A.NOP],
    "budget": [A.i("addi", 10, 10, 1), A.jal(0, -4)],
}


@pytest.mark.parametrize("engine", ENGINES)
@pytest.mark.parametrize("name", sorted(ERROR_PROGRAMS))
def test_errors_are_the_interpreters(name: str, engine: str) -> None:
    words = [A.i("addi", 11, 0, 3)] * 5 + ERROR_PROGRAMS[name]  # some translated work first
    assert_same(words, engine, 5_000, len(words))


def test_multiply_without_multiplier_is_the_interpreters() -> None:
    assert_same([A.i("addi", 12, 0, 3), A.r("mul", 10, 11, 12)], "jit", 5_000, 2, mul=False)


# ---------------------------------------------------------------- multiplier timing


def test_translated_multiplier_latency_is_the_interpreters() -> None:
    # the emitter's tail table continues kernels.core.mul_latency's byte table: same latency for all
    tail = multiplier_tail_table()
    rng = np.random.default_rng(5)
    values = [0, 1, 0xF, 0xFF, 0xFFFF, 0x80000000, 0xFFFFFFFF, *rng.integers(0, 2**32, 3000).tolist()]
    values += [1 << k for k in range(32)] + [0xF << k for k in range(29)]
    for b in values:
        off, steps = 0, 0
        for k in range(3):
            e = int(_MUL_CHUNK[off, (b >> (8 * k)) & 2047])
            steps += e >> 4
            off = e & 15
        assert 5 + steps + int(tail[off, b >> 24]) == mul_latency(b), hex(b)
        assert mul_latency(b) <= MUL_WORST_CYCLES


@pytest.mark.parametrize("engine", ENGINES)
def test_multiplies_with_random_operands(engine: str) -> None:
    rng = np.random.default_rng(9)
    words = []
    for _ in range(200):
        a, b = (int(v) for v in rng.integers(0, 2**32, 2))
        op = ["mul", "mulh", "mulhu", "mulhsu"][int(rng.integers(0, 4))]
        words += [*A.li(11, a), *A.li(12, b), A.r(op, 13, 11, 12), A.r("xor", 10, 10, 13)]
    for errata in ("spec", "rtl"):
        assert_same([*words, *exit_with(10)], engine, 1_000_000, len(words) + 3, errata=errata)


# ---------------------------------------------------------------- the compile cache


def _region_ir(words: list[int], mem_size: int = 64 * 1024) -> str:
    view = CodeView(lambda a: words[(a - SRAM_BASE) >> 2], SRAM_BASE, 4 * len(words), mem_size, True)
    region = discover(view, SRAM_BASE)
    return emit_region(Target(SRAM_BASE, mem_size, 4 * len(words), False), region).ir


def test_compiled_objects_are_cached_by_code_and_options(tmp_path, monkeypatch) -> None:
    monkeypatch.setenv("ROBOSOC_CACHE", str(tmp_path))
    words = [A.i("addi", 10, 10, 1), A.i("addi", 11, 11, 2), A.branch("bne", 10, 11, -8), *exit_with(10)]
    ir = _region_ir(words)
    first = Compiler()
    _, hit = first.object_code(ir)
    assert not hit and len(list((tmp_path / "jit").rglob("*.o"))) == 1
    second = Compiler()  # a new process would start like this
    obj, hit = second.object_code(ir)
    assert hit and obj == first.object_code(ir)[0]
    # changed code, changed options: other objects
    assert not second.object_code(_region_ir([A.i("addi", 10, 10, 2), *words[1:]]))[1]
    assert not second.object_code(_region_ir(words, mem_size=128 * 1024))[1]
    assert len(list((tmp_path / "jit").rglob("*.o"))) == 3


@pytest.mark.usefixtures("no_records")
def test_a_region_translated_once_is_reused_by_the_next_core() -> None:
    words = [A.i("addi", 10, 0, 0), A.i("addi", 10, 10, 1), A.i("addi", 11, 0, 40), A.branch("bne", 10, 11, -8)]
    words += exit_with(10)
    a = make_soc(words, engine="jit")
    a.run(max_cycles=10_000)
    b = make_soc(words, engine="jit")
    b.run(max_cycles=10_000)
    assert b.translator.stats.reused >= 1 and b.translator.stats.regions == 0
    # a changed word is translated afresh
    c = make_soc([*words[:2], A.i("addi", 11, 0, 41), *words[3:]], engine="jit")
    c.run(max_cycles=10_000)
    assert c.translator.stats.regions >= 1


@pytest.mark.usefixtures("no_records")
def test_the_core_benchmark_warms_up_until_a_run_translates_nothing_new(monkeypatch) -> None:
    """``bench core`` times runs only once translation has settled: a run that entered a region,
    handed one to the compiling thread or put one off, or whose engine may not translate yet (auto
    before its warm-up) is followed by another untimed run."""
    from robosoc.benchmarks.core import _settled

    monkeypatch.setattr(jit_tables, "_TRANSLATED", {})
    monkeypatch.setattr(jit_tables, "_FRESH_TABLES", {})
    words = [A.i("addi", 10, 0, 0), A.i("addi", 10, 10, 1), A.i("addi", 11, 0, 40), A.branch("bne", 10, 11, -8)]
    words += exit_with(10)

    def ran(engine_name: str) -> SingleCoreSoC:
        soc = make_soc(words, engine=engine_name)
        soc.run(max_cycles=10_000)
        return soc

    assert _settled(ran("interp"))
    assert not _settled(ran("jit"))  # translated its regions
    assert _settled(ran("jit"))  # entered them from the process
    monkeypatch.setattr(jit_policy, "_BUILD_SECONDS", {})
    assert not _settled(ran("auto"))  # its warm-up is not over: it may translate later
    monkeypatch.setattr(jit_policy, "AUTO_WARMUP_SECONDS", 0.0)
    assert _settled(ran("auto"))  # may translate, and every region it wants is there


def _fresh_tables(soc: SingleCoreSoC) -> tuple[list[np.ndarray], np.ndarray]:
    """The core's tables made afresh (as at a run's start) and its predecode rows then."""
    tr = soc.translator
    tr.forget()
    tables = [a.copy() for a in tr.tables()]
    return tables, soc.state.dec[0].copy()


@pytest.mark.usefixtures("no_records")
@pytest.mark.parametrize("later", [False, True], ids=["", "a-region-translated-since"])
@pytest.mark.parametrize("changed", [None, 0, 1, 30], ids=["same", "first-word", "loop-word", "outside-the-region"])
def test_a_core_copying_the_tables_of_the_last_gets_those_made_afresh(
    changed: int | None, later: bool, monkeypatch
) -> None:
    """The cores of a chip share one program: a core makes its fresh tables by copying those the
    last core of the build made, which must equal entering every known region itself; a core whose
    code differs anywhere (a region's word or not) makes its own."""
    monkeypatch.setattr(jit_tables, "_TRANSLATED", {})
    monkeypatch.setattr(jit_tables, "_FRESH_TABLES", {})
    words = [A.i("addi", 10, 0, 0), A.i("addi", 10, 10, 1), A.i("addi", 11, 0, 40), A.branch("bne", 10, 11, -8)]
    words += exit_with(10)
    words += [0] * (32 - len(words))  # an illegal word ends the region: word 30 is in no region
    make_soc(words, engine="jit").run(max_cycles=10_000)
    mine = list(words)
    if changed is not None:
        mine[changed] = A.i("addi", 12, 0, 7)
    make_soc(words, engine="jit").translator.tables()  # made afresh, kept for the next core
    if later:  # a region starting inside the loop (as after an interrupt there)
        make_soc(words, engine="jit").translator.translate(SRAM_BASE + 8)
    copied = make_soc(mine, engine="jit")
    got = _fresh_tables(copied)
    monkeypatch.setattr(jit_tables, "_FRESH_TABLES", {})
    made = make_soc(mine, engine="jit")
    want = _fresh_tables(made)
    assert len(got[0]) == len(want[0])
    for name, a, b in zip(JitArrays._fields, got[0], want[0], strict=True):
        assert np.array_equal(a, b), name
    assert np.array_equal(got[1], want[1])  # the interpreter stops before the same blocks
    mine_tr, made_tr = copied.translator, made.translator
    assert (mine_tr.stats.reused, mine_tr._known_starts_in) == (made_tr.stats.reused, made_tr._known_starts_in)
    # a region is entered unless one of its words changed (word 2 starts no block of the first)
    entry_fn = want[0][0]
    assert (entry_fn[0] != 0) == (changed in (None, 30))
    if changed in (None, 30):
        assert (entry_fn[2] != 0) == later
    (got_result, got_arrays), (want_result, want_arrays) = (
        outcome(soc, 10_000) for soc in (copied, make_soc(mine, engine="interp"))
    )
    assert got_result == want_result
    assert all(np.array_equal(got_arrays[n], want_arrays[n]) for n in want_arrays)


# ---------------------------------------------------------------- region structure and tiers


@pytest.mark.usefixtures("no_records")
def test_many_small_chained_regions_run_as_on_the_interpreter(monkeypatch) -> None:
    """Regions of at most 8 instructions: control crosses regions all the time (tail calls through
    the entry table, returns into other regions, arrivals inside translated blocks after interrupts)."""
    import robosoc.jit.regions as regions

    monkeypatch.setattr(regions, "MAX_REGION_INSTRUCTIONS", 8)  # the cap of jit's regions
    monkeypatch.setattr(jit_tables, "_TRANSLATED", {})  # nothing reused from the larger regions of other tests
    words, _ = irq.build(7003, True, "spec")
    soc = assert_same(words, "jit", irq.MAX_CYCLES, len(words), mul=True, sram_size=irq.SRAM_SIZE)
    assert soc.translator.stats.regions >= 5
    assert all(
        len(b.insns) <= 8 for t in jit_tables._TRANSLATED[soc.translator._key()] for b in t.region.blocks.values()
    )


def indirect_calls(count: int) -> list[int]:
    """main calls one of two functions through a register (jalr ra, 0(t0)) ``count`` times; each returns with ret."""
    f1, f2 = 12, 15  # word indices of the functions
    return [
        A.i("addi", 10, 0, 0),  # 0: acc
        A.i("addi", 7, 0, count),  # 1: count
        A.i("andi", 6, 7, 1),  # 2: loop: pick by parity
        *A.li(5, SRAM_BASE + 4 * f1),  # 3, 4
        A.branch("beq", 6, 0, 12),  # 5: even -> f1 (to word 8)
        *A.li(5, SRAM_BASE + 4 * f2),  # 6, 7
        A.jalr(1, 5, 0),  # 8: call
        A.i("addi", 7, 7, -1),  # 9
        A.branch("bne", 7, 0, -32),  # 10: back to word 2
        A.jal(0, 4 * (18 - 11)),  # 11: to the exit at word 18
        A.i("addi", 10, 10, 3),  # 12: f1
        A.i("xori", 10, 10, 5),  # 13
        A.jalr(0, 1, 0),  # 14: ret
        A.i("addi", 10, 10, 7),  # 15: f2
        A.r("add", 10, 10, 10),  # 16
        A.jalr(0, 1, 0),  # 17: ret
        *exit_with(10),  # 18
    ]


def test_indirect_calls_through_a_register_run_as_on_the_interpreter() -> None:
    words = indirect_calls(60)
    for engine in ENGINES:
        assert_same(words, engine, 100_000, len(words))


def test_auto_compiles_nothing_when_compiling_is_not_worth_it(monkeypatch) -> None:

    monkeypatch.setattr(jit_policy, "AUTO_COMPILE_SHARE", 0.0)
    monkeypatch.setattr(jit_tables, "_TRANSLATED", {})
    words, _ = irq.build(7004, True, "spec")
    soc = assert_same(words, "auto", irq.MAX_CYCLES, len(words), mul=True, sram_size=irq.SRAM_SIZE)
    assert soc.translator.stats.regions == 0


def test_auto_asks_for_no_region_before_its_warm_up(monkeypatch) -> None:
    """A run shorter than AUTO_WARMUP_SECONDS is interpreted as by interp (nothing found, written
    or handed to the compiling thread); once the core, or the cores of its build in the process,
    have run that long, hot words are asked for."""
    monkeypatch.setattr(jit_tables, "_TRANSLATED", {})
    monkeypatch.setattr(jit_policy, "_BUILD_SECONDS", {})
    monkeypatch.setattr(jit_policy, "AUTO_WARMUP_SECONDS", 3600.0)  # longer than any run here
    words, _ = irq.build(7005, True, "spec")
    soc = assert_same(words, "auto", irq.MAX_CYCLES, len(words), mul=True, sram_size=irq.SRAM_SIZE)
    stats = soc.translator.stats
    assert stats.run_seconds > 0 and (stats.regions, stats.background, stats.deferred) == (0, 0, 0)
    assert soc.translator.ask_threshold(cached=False) == jit_policy.NEVER_ASK
    stats.run_seconds = 3600.5  # warmed up (and the budget is large)
    assert soc.translator.ask_threshold(cached=False) == jit_policy.AUTO_THRESHOLD
    stats.run_seconds = 0.0  # regions compiled by an earlier run are installed from the start
    assert soc.translator.ask_threshold(cached=True) == jit_policy.AUTO_THRESHOLD
    ran = jit_policy._BUILD_SECONDS[soc.translator._key()]
    assert 0 < ran < 3600  # the run counted for its build
    jit_policy._BUILD_SECONDS[soc.translator._key()] = 3600.5  # earlier runs of the build warmed it up
    monkeypatch.setattr(jit_policy.AutoPolicy, "budget", lambda self: 1.0)  # (a new core's is 0 before it runs)
    fresh = make_soc(words, engine="auto", mul=True, sram_size=irq.SRAM_SIZE)
    fresh.state.set_code_size(4 * len(words))
    assert fresh.translator.stats.run_seconds == 0
    assert fresh.translator.ask_threshold(cached=False) == jit_policy.AUTO_THRESHOLD
    other = make_soc(words, engine="auto", mul=False, sram_size=irq.SRAM_SIZE)  # another build: not warm
    other.state.set_code_size(4 * len(words))
    assert other.translator.ask_threshold(cached=False) == jit_policy.NEVER_ASK


def test_auto_installs_regions_compiled_by_an_earlier_run_at_once(tmp_path, monkeypatch) -> None:
    monkeypatch.setattr("robosoc.jit.policy.AUTO_WARMUP_SECONDS", 0.0)  # short runs translate too
    import robosoc.jit.compiler as compiler

    monkeypatch.setenv("ROBOSOC_CACHE", str(tmp_path))
    monkeypatch.setattr(jit_tables, "_TRANSLATED", {})
    monkeypatch.setattr(compiler, "_SHARED", None)
    words = indirect_calls(2000)
    # the first run may compile whatever turns hot (as a long run would; short stretches sample
    # often), in line: a run this short ends before the compiling thread delivers
    monkeypatch.setattr(jit_policy, "AUTO_BACKGROUND", False)
    monkeypatch.setattr(jit_policy.AutoPolicy, "budget", lambda self: float("inf"))  # always worth compiling
    monkeypatch.setattr(jit_policy, "STRETCHES", {"auto": 50})
    first = assert_same(words, "auto", 1_000_000, len(words))
    assert first.translator.stats.regions >= 1
    # a new process (no regions in memory) that may not compile anything: the cached regions still come in
    monkeypatch.setattr(jit_policy.AutoPolicy, "budget", lambda self: 0.0)
    monkeypatch.setattr(jit_tables, "_TRANSLATED", {})
    monkeypatch.setattr(compiler, "_SHARED", None)
    second = assert_same(words, "auto", 1_000_000, len(words))
    # entered from the first run's records: neither found nor written again, objects from the cache
    assert second.translator.stats.recorded == first.translator.stats.regions
    assert second.translator.stats.regions == 0
    stats = second.translator.compiler.stats
    assert stats.cache_hits == stats.modules >= 1


@pytest.mark.parametrize("engine", ["jit", "auto"])
def test_a_later_process_enters_the_recorded_regions_without_finding_or_writing_them(
    engine: str, tmp_path, monkeypatch
) -> None:
    """A run records every region it compiled in its program's manifest; a new process (nothing
    in memory) running the same program enters them all when it makes its tables: no call of
    ``discover`` or ``emit_region``, nothing compiled, the same results as the interpreter.  A
    program differing in one word has another manifest."""
    import robosoc.jit.compiler as compiler
    import robosoc.jit.emit_ir as emit_ir
    import robosoc.jit.regions as regions

    monkeypatch.setenv("ROBOSOC_CACHE", str(tmp_path))
    monkeypatch.setattr(jit_policy, "AUTO_WARMUP_SECONDS", 0.0)
    monkeypatch.setattr(jit_policy, "AUTO_BACKGROUND", False)
    monkeypatch.setattr(jit_policy.AutoPolicy, "budget", lambda self: float("inf"))
    monkeypatch.setattr(jit_policy, "STRETCHES", {"jit": 0, "auto": 50})
    calls = {"discover": 0, "emit_region": 0}

    def counted(module, name):
        real = getattr(module, name)

        def call(*args, **kwargs):
            calls[name] += 1
            return real(*args, **kwargs)

        monkeypatch.setattr(module, name, call)

    counted(regions, "discover")
    counted(emit_ir, "emit_region")

    def new_process() -> None:
        monkeypatch.setattr(jit_tables, "_TRANSLATED", {})
        monkeypatch.setattr(jit_tables, "_FRESH_TABLES", {})
        monkeypatch.setattr(compiler, "_SHARED", None)

    words = indirect_calls(2000)
    new_process()
    first = assert_same(words, engine, 1_000_000, len(words))
    made = first.translator.stats.regions
    assert made >= 1 and calls["discover"] >= made and calls["emit_region"] == made
    new_process()
    calls.update(discover=0, emit_region=0)
    second = assert_same(words, engine, 1_000_000, len(words))
    assert (second.translator.stats.recorded, second.translator.stats.regions) == (made, 0)
    assert calls == {"discover": 0, "emit_region": 0}
    cs = second.translator.compiler.stats
    assert cs.modules == cs.cache_hits == made
    # one word changed (the loop's count): another program, its regions found and written afresh
    new_process()
    other = assert_same([words[0], A.i("addi", 7, 0, 1999), *words[2:]], engine, 1_000_000, len(words))
    assert other.translator.stats.recorded == 0 and other.translator.stats.regions >= 1


def _run_waiting_for_compiles(soc: SingleCoreSoC, max_cycles: int, chunk: int) -> tuple[object, dict[str, np.ndarray]]:
    """``outcome`` of a run in chunks, each after the compiling thread finished what it was given
    (which the core enters itself when it runs on)."""

    def advance(until: int) -> int:
        for job, *_ in soc.translator._compiling:
            job.done.wait()
        return soc.step_until(until)

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = soc.run(max_cycles=max_cycles, chunk=chunk, advance=advance)
    arrays = {n: getattr(soc.state, n).copy() for n in ("st", "ctr", "opc", "regs", "m8")}
    return (result.exit_code, soc.counters()), arrays


def test_auto_on_one_core_compiles_in_the_background_and_changes_nothing(tmp_path, monkeypatch) -> None:
    """auto hands its regions to the compiling thread and interprets them meanwhile; the chunk
    after they arrive runs them translated, with the interpreter's cycles, counters and state."""
    monkeypatch.setattr("robosoc.jit.policy.AUTO_WARMUP_SECONDS", 0.0)  # short runs translate too
    import robosoc.jit.compiler as compiler

    monkeypatch.setenv("ROBOSOC_CACHE", str(tmp_path))
    monkeypatch.setattr(jit_tables, "_TRANSLATED", {})
    monkeypatch.setattr(compiler, "_SHARED", None)
    monkeypatch.setattr(jit_policy, "AUTO_COMPILE_SHARE", 1e9)
    monkeypatch.setattr(jit_policy, "STRETCHES", {"auto": 50})
    words = indirect_calls(2000)
    ref = make_soc(words)
    ref.state.set_code_size(4 * len(words))
    want = outcome(ref, 1_000_000)
    soc = make_soc(words, engine="auto")
    soc.state.set_code_size(4 * len(words))
    soc.forget_translations()
    assert soc.translator.background
    got = _run_waiting_for_compiles(soc, 1_000_000, 5_000)
    assert got[0] == want[0]
    for name, arr in want[1].items():
        assert np.array_equal(got[1][name], arr), f"{name} differs"
    stats = soc.translator.stats
    assert 1 <= stats.regions <= stats.background  # the regions came from the thread
    assert int(soc.translator.tables().ctx[CTX_STEPS]) < got[0][1]["instructions"] // 2  # and ran


def test_a_region_compiling_for_a_core_that_is_gone_keeps_no_other_core_waiting(tmp_path, monkeypatch) -> None:
    """A run that ends while its region compiles leaves it loaded in the process (and in the disk
    cache): the next core that asks for the region enters it, instead of waiting for the first
    core to."""
    monkeypatch.setattr("robosoc.jit.policy.AUTO_WARMUP_SECONDS", 0.0)  # short runs translate too
    import robosoc.jit.compiler as compiler

    monkeypatch.setenv("ROBOSOC_CACHE", str(tmp_path))
    monkeypatch.setattr(jit_tables, "_TRANSLATED", {})
    monkeypatch.setattr(compiler, "_SHARED", None)
    monkeypatch.setattr(jit_policy, "_COMPILING", {})
    monkeypatch.setattr(jit_policy.AutoPolicy, "budget", lambda self: float("inf"))  # always worth compiling
    monkeypatch.setattr(jit_policy, "STRETCHES", {"auto": 50})
    monkeypatch.setitem(jit_policy.THRESHOLDS, "auto", 3)  # a short program: few samples per word
    gate = threading.Event()  # the compiling thread starts once the first run has ended
    work = compiler.Compiler._work
    monkeypatch.setattr(compiler.Compiler, "_work", lambda self: (gate.wait(), work(self)))
    words = indirect_calls(2000)
    first = assert_same(words, "auto", 1_000_000, len(words))
    assert first.translator.stats.regions == 0 and first.translator.compiling() >= 1
    gate.set()
    for job, *_ in first.translator._compiling:
        job.done.wait()
    del first
    second = assert_same(words, "auto", 1_000_000, len(words))
    assert second.translator.stats.deferred == 0  # no region waited for the first core's modules
    assert second.translator.stats.regions >= 1
    stats = second.translator.compiler.stats
    assert stats.reused + stats.cache_hits >= 1  # the thread's module (loaded by it, or in the disk cache)


def _gated_compiling(tmp_path, monkeypatch):  # type: ignore[no-untyped-def]
    """auto in a fresh process (nothing translated, an empty object cache) that translates at
    once, with a compiling thread that starts only when the returned event is set."""
    import robosoc.jit.compiler as compiler
    import robosoc.jit.engine as engine

    monkeypatch.setenv("ROBOSOC_CACHE", str(tmp_path))
    monkeypatch.setattr(jit_tables, "_TRANSLATED", {})
    monkeypatch.setattr(compiler, "_SHARED", None)
    monkeypatch.setattr(jit_policy, "_COMPILING", {})
    monkeypatch.setattr(jit_policy, "AUTO_WARMUP_SECONDS", 0.0)
    monkeypatch.setattr(jit_policy.AutoPolicy, "budget", lambda self: float("inf"))
    monkeypatch.setattr(jit_policy, "STRETCHES", {"auto": 50})
    monkeypatch.setitem(jit_policy.THRESHOLDS, "auto", 3)  # a short program: few samples per word
    gate = threading.Event()
    work = compiler.Compiler._work
    monkeypatch.setattr(compiler.Compiler, "_work", lambda self: (gate.wait(), work(self)))
    return engine, gate


def test_auto_stops_for_no_region_while_its_compiling_queue_is_full(tmp_path, monkeypatch) -> None:
    """With BACKGROUND_QUEUE regions waiting for the compiling thread the loop asks for none (each
    would be parked at once) and comes back every POLL_CYCLES to enter what the thread finished;
    the call that only loads the kernel counts no run time."""
    engine, gate = _gated_compiling(tmp_path, monkeypatch)  # nothing compiled during the run: the queue stays full
    monkeypatch.setattr(jit_policy, "POLL_CYCLES", 100)  # the run is 5,658 cycles long
    calls = []
    dispatch = engine.run_translated
    monkeypatch.setattr(jit_policy, "_dispatch_loop_ready", True)
    monkeypatch.setattr(engine, "run_translated", lambda *args: (calls.append(args[2]), dispatch(*args)))
    words, _ = irq.build(7006, True, "spec")
    soc = make_soc(words, engine="auto", mul=True, sram_size=irq.SRAM_SIZE)
    soc.state.set_code_size(4 * len(words))
    soc.forget_translations()
    soc.step_until(soc.cycle)
    assert soc.translator.stats.run_seconds == 0.0
    got = outcome(soc, irq.MAX_CYCLES)
    gate.set()
    ref = make_soc(words, mul=True, sram_size=irq.SRAM_SIZE)
    ref.state.set_code_size(4 * len(words))
    want = outcome(ref, irq.MAX_CYCLES)
    assert got[0] == want[0] and all(np.array_equal(got[1][n], want[1][n]) for n in want[1])
    stats = soc.translator.stats
    assert soc.translator.compiling() == stats.background == jit_policy.BACKGROUND_QUEUE
    assert stats.deferred == 0  # asked for nothing more once the queue was full
    cycles = int(soc.state.st[0, S_CYCLE])
    assert len(calls) > cycles // (2 * jit_policy.POLL_CYCLES)  # came back to look for finished regions


def test_auto_unparks_no_more_words_than_its_compiling_queue_has_room_for(monkeypatch) -> None:
    """Parked words count arrivals again only as far as the queue has room: the others would stop
    the loop to be parked again."""
    import robosoc.jit.engine as engine

    monkeypatch.setattr(jit_policy, "AUTO_WARMUP_SECONDS", 0.0)
    monkeypatch.setattr(jit_policy.AutoPolicy, "budget", lambda self: float("inf"))
    monkeypatch.setattr(jit_policy, "_COMPILING", {})
    soc = make_soc(indirect_calls(10), engine="auto")
    tr = soc.translator
    assert tr.background
    jt = tr.tables()
    parked = range(2, 8)
    for i in parked:
        jt.hot[i] = engine.NEVER_TRANSLATE
        tr.policy._parked[i] = SRAM_BASE + 4 * i
    tr._compiling = [None] * (jit_policy.BACKGROUND_QUEUE - 2)  # two places left
    tr.ask_threshold(cached=False)
    assert [i for i in parked if jt.hot[i] == 0] == [2, 3] and sorted(tr.policy._parked) == [4, 5, 6, 7]
    tr._compiling = []
    tr.ask_threshold(cached=False)
    assert [i for i in parked if jt.hot[i] == 0] == [2, 3, 4, 5, 6, 7] and not tr.policy._parked


def test_the_compiling_thread_drops_what_no_live_core_could_use(tmp_path, monkeypatch) -> None:
    """A job the thread has not started is dropped when no live core holds its region's code (its
    run ended and nothing else runs the program): a process's later work does not share the host
    with a backlog nobody will run.  Another core with the same code keeps it wanted (a
    benchmark's next run, a chip's other tiles)."""
    _, gate = _gated_compiling(tmp_path, monkeypatch)
    words, _ = irq.build(7006, True, "spec")

    def core(code: list[int]) -> SingleCoreSoC:
        soc = make_soc(code, engine="auto", mul=True, sram_size=irq.SRAM_SIZE)
        soc.state.set_code_size(4 * len(code))
        soc.forget_translations()
        return soc

    first = core(words)
    outcome(first, irq.MAX_CYCLES)
    jobs = [job for job, *_ in first.translator._compiling]
    shared = first.translator.compiler
    assert len(jobs) == jit_policy.BACKGROUND_QUEUE
    second = core(words)  # the same program: wanted while either runs
    del first
    assert all(job.wanted() for job in jobs)
    del second
    assert not any(job.wanted() for job in jobs)
    other = make_soc(words, engine="auto", mul=False, sram_size=irq.SRAM_SIZE)  # the code, another build
    other.state.set_code_size(4 * len(words))
    assert not any(job.wanted() for job in jobs)
    gate.set()
    for job in jobs:
        assert job.done.wait(60)
    assert all(job.dropped and not job.addresses for job in jobs)
    assert shared.stats.modules == 0


@pytest.mark.usefixtures("no_records")
def test_auto_on_a_fresh_install_interprets_until_compiling_the_dispatch_loop_pays(monkeypatch) -> None:
    """numba has not compiled the dispatch loop yet: auto runs the interpreter (which interp would
    compile as well) and counts the time, and takes the dispatch loop once that time would pay for
    compiling it (docs/translation.md)."""
    monkeypatch.setattr("robosoc.jit.policy.AUTO_WARMUP_SECONDS", 0.0)  # short runs translate too

    monkeypatch.setattr(jit_policy, "compiled_or_cached", lambda kernel: False)
    monkeypatch.setattr(jit_policy, "_dispatch_loop_ready", False)
    monkeypatch.setattr(jit_policy, "STRETCHES", {"auto": 50})
    monkeypatch.setattr(jit_policy.AutoPolicy, "budget", lambda self: float("inf"))  # always worth compiling
    monkeypatch.setattr(jit_policy, "AUTO_BACKGROUND", False)  # and compiled before this short run ends
    words = indirect_calls(2000)
    monkeypatch.setattr(jit_policy, "ESTIMATED_DISPATCH_LOOP_SECONDS", 1e12)
    soc = assert_same(words, "auto", 1_000_000, len(words))
    assert soc.translator.stats.regions == soc.translator.stats.reused == 0
    assert int(soc.translator.tables().ctx[CTX_STEPS]) == 0  # the dispatch loop never ran
    assert soc.translator.stats.run_seconds > 0
    assert not jit_policy._dispatch_loop_ready
    # worth it at once: the slices run in the dispatch loop and translate
    monkeypatch.setattr(jit_policy, "ESTIMATED_DISPATCH_LOOP_SECONDS", 0.0)
    monkeypatch.setattr(jit_tables, "_TRANSLATED", {})
    soc = assert_same(words, "auto", 1_000_000, len(words))
    assert jit_policy._dispatch_loop_ready
    assert soc.translator.stats.regions >= 1


def test_compiled_or_cached_knows_a_kernel_numba_has_not_compiled(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import numba
    from numba import njit

    from robosoc.kernels import compiled_or_cached
    from robosoc.kernels.jit_dispatch import run_translated

    with monkeypatch.context() as m:
        # numba caches this function too: an empty cache folder of its own, or a second run of the
        # test would find the first one's
        m.setattr(numba.config, "CACHE_DIR", str(tmp_path))

        @njit(cache=True)
        def never_cached(x: int) -> int:  # not compiled yet, nor in its cache
            return x + 1

    assert not compiled_or_cached(never_cached)
    assert never_cached(1) == 2
    assert compiled_or_cached(never_cached)
    assert_same(indirect_calls(10), "jit")  # compiles (or loads) the dispatch loop, into numba's cache
    assert compiled_or_cached(run_translated)
    # a dispatcher that has compiled nothing yet finds the dispatch loop in numba's cache
    assert compiled_or_cached(njit(cache=True)(run_translated.py_func))


def test_a_breakpoint_set_after_translating_stops_the_core_on_the_interpreter() -> None:
    """Translated blocks hold OP_ENTRY in their predecode rows (the interpreter stops before them
    for the dispatch loop); setting a breakpoint puts the core back on the interpreter, so those
    marks must go: the core then stops at the breakpoint with RUN_BREAK after the loop's 40
    iterations, as on a core that never translated."""
    from robosoc.isa.table import OP_ENTRY
    from robosoc.kernels.core_layout import RUN_BREAK, S_RUN

    loop = [A.i("addi", 10, 0, 0), A.i("addi", 10, 10, 1), A.i("addi", 11, 0, 40), A.branch("bne", 10, 11, -8)]
    words = [*loop, A.i("addi", 12, 10, 0), *exit_with(10)]
    stops = {}
    for engine in ("interp", "jit"):
        soc = make_soc(words, engine=engine)
        soc.step_until(100)  # the loop runs translated (jit)
        if engine == "jit":
            assert (soc.state.op_rows(0) == OP_ENTRY).any()
        soc.set_breakpoint(SRAM_BASE + 4 * len(loop))
        assert not (soc.state.op_rows(0) == OP_ENTRY).any()
        status = soc.step_until(1_000_000)
        stops[engine] = (status, soc.state.pc, soc.cycle, int(soc.state.regs[0, 10]))
        assert status == RUN_BREAK == int(soc.state.st[0, S_RUN])
    assert stops["jit"] == stops["interp"]
    assert (stops["jit"][1], stops["jit"][3]) == (SRAM_BASE + 4 * len(loop), 40)


@pytest.mark.parametrize("engine", ENGINES)
def test_a_trap_whose_shadow_starts_a_translated_block_runs_as_on_the_interpreter(engine: str) -> None:
    """The word 8 bytes after an ecall (its shadow: it runs after the trap, before the vector) is
    also a branch target, hence a translated block start marked OP_ENTRY: at the second ecall the
    interpreter stops before it and the dispatch loop must still run it before taking the vector."""
    from test_interrupts import IRQ, sw_const

    from robosoc.kernels.core_layout import S_ERR

    t1, a4, a5, a6, t3 = 6, 14, 15, 16, 28
    body = [
        *A.li(t3, IRQ),
        *sw_const(t3, 0x00, SRAM_BASE + 0x400),  # IRQ_VECTOR: the handler at word 0x100
        A.i("addi", a6, 0, 3),
        A.ECALL,  # E
        A.i("addi", a4, a4, 1),  # E + 4: the handler returns here
        A.i("addi", a5, a5, 1),  # E + 8: the shadow, and the target of the bne below
        A.i("addi", a6, a6, -1),
        A.branch("beq", a6, 0, 16),  # to the exit
        A.i("andi", t1, a6, 1),
        A.branch("bne", t1, 0, -16),  # odd: back to E + 8
        A.jal(0, -28),  # even: to the ecall again
        *exit_with(a5),
    ]
    handler = [A.NOP, A.load("lw", 13, t3, 0x40), A.i("addi", 27, 13, -4), A.jalr(0, 27, 0)]  # back to E + 4
    words = body + [A.NOP] * (0x100 - len(body)) + handler
    soc = assert_same(words, engine, 100_000, len(words))
    assert soc.counters()["traps"] == 2 and int(soc.state.st[0, S_ERR]) == 0
    assert int(soc.state.regs[0, a5]) == 5  # the shadow twice, and 3 times through E + 4 and the loop


def test_compiled_or_cached_does_not_take_another_checkouts_kernel_for_this_ones(tmp_path: Path) -> None:
    import importlib.util

    from robosoc.kernels import compiled_or_cached

    source = "from numba import njit\n\n@njit(cache=True)\ndef twice(x):\n    return 2 * x\n"
    kernels = []
    for checkout in ("one", "two"):  # the same source in two folders, as in two checkouts
        folder = tmp_path / checkout
        folder.mkdir()
        (folder / "twice_kernel.py").write_text(source)
        spec = importlib.util.spec_from_file_location("twice_kernel", folder / "twice_kernel.py")
        assert spec is not None and spec.loader is not None
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        kernels.append(module.twice)
    one, two = kernels
    assert not compiled_or_cached(one)
    assert one(21) == 42  # compiled and cached under the first folder's name
    assert compiled_or_cached(one)
    assert not compiled_or_cached(two)  # the second checkout's kernel is not in numba's cache


def side_exits_mid_block(count: int) -> list[int]:
    """A loop whose block loads, in its middle, from an SRAM word and from IRQ_MASK (a device) in
    turn: every other iteration the translated block leaves before the load (a side exit counting
    the block's prefix) and the rest of it runs on the interpreter; a taken branch closes each."""
    data = 13  # the word loaded from SRAM
    return [
        A.i("addi", 10, 0, 0),  # 0: acc
        A.i("addi", 28, 0, count),  # 1
        *A.li(29, SRAM_BASE + 4 * data),  # 2, 3: the load's base
        *A.li(30, (SRAM_BASE + 4 * data) ^ 0xF0000020),  # 4, 5: base ^ IRQ_MASK
        A.i("addi", 10, 10, 3),  # 6: loop
        A.r("xor", 29, 29, 30),  # 7: the other base
        A.shift("slli", 11, 10, 2),  # 8
        A.load("lw", 12, 29, 0),  # 9: SRAM or IRQ_MASK
        A.r("add", 10, 10, 12),  # 10
        A.i("addi", 28, 28, -1),  # 11
        A.branch("bne", 28, 0, -24),  # 12: back to word 6
        *exit_with(10),  # 13 (the data word), 14
    ]


@pytest.mark.usefixtures("no_records")
def test_translated_code_leaves_the_interpreters_counters_at_every_stop() -> None:
    """Translated blocks add what they execute to the counters themselves (a block's end its whole
    histogram, a side exit in the middle of a block its prefix): wherever the dispatch loop stops,
    the per-operation counters and ctr (taken branches included) are those of the interpreter
    stopped at the same cycle."""
    from robosoc.kernels.core import run_cores
    from robosoc.kernels.jit_dispatch import CTX_CALLS, CTX_DEVICE, run_translated

    words = side_exits_mid_block(200)
    make_soc(words, engine="jit").run(max_cycles=1_000_000)  # every region translated
    soc, ref = make_soc(words, engine="jit"), make_soc(words)
    tr = soc.translator
    jt = tr.tables()
    for until in (40, 333, 1_000, 1_001, 1_777, 100_000):  # (the program exits near cycle 2,200)
        run_translated(soc.state.arrays(), tr._tiles, until, jt, 1, 0)
        run_cores(ref.state.arrays(), tr._tiles, until)
        assert soc.state.st[0, S_CYCLE] == ref.state.st[0, S_CYCLE] >= min(until, 2_000)
        assert soc.state.st[0, S_RUN] == ref.state.st[0, S_RUN]
        assert np.array_equal(soc.state.opc[0], ref.state.opc[0]), until
        assert np.array_equal(soc.state.ctr[0], ref.state.ctr[0]), until
    assert jt.ctx[CTX_CALLS] > 10 and jt.ctx[CTX_DEVICE] > 10  # translated, leaving before the device loads
    assert ref.state.opc[0].sum() == 6 + 7 * 200 + 3  # (set-up, loop, exit store)


def test_side_exits_mid_block_run_as_on_the_interpreter() -> None:
    words = side_exits_mid_block(60)
    for engine in ENGINES:
        assert_same(words, engine, 100_000, len(words))


def small_and_large_loops() -> list[int]:
    """A loop of three blocks (20 times), then one of five blocks (10 times)."""
    return [
        A.i("addi", 10, 0, 0),  # 0
        A.i("addi", 6, 0, 20),  # 1
        A.i("addi", 10, 10, 1),  # 2: small loop
        A.i("andi", 5, 6, 1),  # 3
        A.branch("beq", 5, 0, 8),  # 4: to 6
        A.i("xori", 10, 10, 3),  # 5
        A.i("addi", 6, 6, -1),  # 6
        A.branch("bne", 6, 0, -20),  # 7: to 2
        A.i("addi", 7, 0, 10),  # 8
        A.i("addi", 10, 10, 5),  # 9: large loop, a block per branch
        A.branch("blt", 10, 0, 4),  # 10
        A.i("addi", 10, 10, 7),  # 11
        A.branch("blt", 10, 0, 4),  # 12
        A.i("addi", 10, 10, 9),  # 13
        A.branch("blt", 10, 0, 4),  # 14
        A.i("addi", 10, 10, 11),  # 15
        A.branch("blt", 10, 0, 4),  # 16
        A.i("addi", 7, 7, -1),  # 17
        A.branch("bne", 7, 0, -36),  # 18: to 9
        *exit_with(10),  # 19-21
    ]


def test_blocks_on_small_cycles_count_through_locals() -> None:
    """The blocks of a cycle of at most MAX_LOOP_BLOCKS blocks count their executions in locals
    (written to the counters at the region function's ways out), the others at each way out of
    the block; the counters come out as the interpreter's either way."""
    import re

    from robosoc.jit.emit_ir import MAX_LOOP_BLOCKS, looped_blocks

    assert MAX_LOOP_BLOCKS == 4  # (the small loop has three blocks, the large one five)
    words = small_and_large_loops()
    view = CodeView(lambda a: words[(a - SRAM_BASE) >> 2], SRAM_BASE, 4 * len(words), 64 * 1024, True)
    region = discover(view, SRAM_BASE)
    starts = [(pc - SRAM_BASE) >> 2 for pc in region.blocks]
    assert starts == [0, 2, 5, 6, 8, 9, 11, 13, 15, 17, 19]
    assert looped_blocks(region, []) == {SRAM_BASE + 4 * w for w in (2, 5, 6)}
    ir = _region_ir(words)
    assert re.findall(r"%bc(\d+) = alloca", ir) == ["1", "2", "3"]  # the blocks at words 2, 5 and 6
    for engine in ENGINES:
        soc = assert_same(words, engine, 100_000, len(words))
    assert int(soc.state.opc[0].sum()) == 2 + 20 * 5 + 10 + 1 + 10 * 10 + 3  # (the xori every other time)
