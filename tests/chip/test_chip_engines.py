"""Translated code on the MPSoC's cores gives the interpreter's chip, cycle for cycle.

Every engine must give the same outputs, cycles, per-tile and per-task counters, NoC counters and
errors (docs/translation.md).  The traffic program of ``test_quanta_vs_lockstep`` exercises idle
and busy network phases, DMA, receive interrupts and sleep on every tile; hand-made programs
check a packet copied over translated code, the errors of a network interface misused from
translated code, and that breakpoints and profiles fall back to the interpreter.
"""

from __future__ import annotations

import itertools
from pathlib import Path

import pytest

import robosoc.jit.tables as jit_tables
import rv32_asm as A
from core_harness import exit_with
from robosoc.chip.mpsoc import ChipError, MPSoC
from robosoc.config.chip import ChipConfig, NocConfig
from robosoc.program.elf import Program, load_elf
from robosoc.toolchain import build_elf

TRAFFIC = Path(__file__).parent / "programs" / "traffic.c"
ENGINES = ["jit", "auto"]
SRAM = 0x40000000
NI = 0xE1040000
T0, T1, T2, RA, A0 = 5, 6, 7, 1, 10

pytestmark = pytest.mark.filterwarnings("ignore::robosoc.chip.single.IrqDuringMulErratum")


def outcome(chip: MPSoC, max_cycles: int) -> tuple:
    try:
        result = chip.run(max_cycles=max_cycles)
        ran: tuple = (result.output, result.cycles, result.exit_codes)
    except ChipError as exc:
        ran = ("error", str(exc), exc.tile, chip.cycle)
    tiles = {xy: chip.counters(xy) for xy in chip.core_tiles()}
    tasks = {xy: chip.task_counters(xy) for xy in chip.core_tiles()}
    return ran, tiles, tasks, chip.noc_counters()


def run_traffic(config: ChipConfig, engine: str, rounds: int) -> tuple[tuple, MPSoC]:
    program = load_elf(build_elf([TRAFFIC], mul=True, defines={"ROUNDS": rounds}))
    chip = MPSoC(config, engine=engine)
    chip.load_all(program)
    return outcome(chip, 20_000_000), chip


def count_looks(monkeypatch) -> list[int]:
    """The tiles whose translator installs the known regions (a look at the tile), in order."""
    from robosoc.jit.engine import TranslatingCore

    looks: list[int] = []
    install_known = TranslatingCore.install_known

    def counted(self: TranslatingCore) -> None:
        looks.append(self.tile)
        install_known(self)

    monkeypatch.setattr(TranslatingCore, "install_known", counted)
    return looks


@pytest.mark.parametrize("engine", ENGINES)
@pytest.mark.parametrize(
    "config",
    [ChipConfig(), ChipConfig(width=3, height=2, noc=NocConfig(buffer_depth=2, arbiter="per-output"))],
    ids=["hermes-2x2", "per-output-3x2-shallow"],
)
def test_traffic_on_every_tile_runs_as_on_the_interpreter(config: ChipConfig, engine: str) -> None:
    reference, _ = run_traffic(config, "interp", 4)
    got, chip = run_traffic(config, engine, 4)
    assert got == reference
    assert reference[0][0]  # every tile printed its report
    if engine == "jit":  # every core translated its code at once
        stats = chip._jit.stats
        assert stats is not None and stats.regions + stats.reused > 0


def program(words: list[int], data: dict[int, bytes] | None = None) -> Program:
    segments = [(SRAM, A.words_to_bytes(words)), *(data or {}).items()]
    return Program(path=Path("<asm>"), entry=SRAM, segments=segments)


def flits(*values: int) -> bytes:
    return b"".join((v & 0xFFFF).to_bytes(2, "little") for v in values)


def patcher_and_patched() -> tuple[Program, Program]:
    """Tile (1, 0) sends tile (0, 1) a packet whose payload is the instruction ``addi a0, a0, 100``;
    tile (0, 1) calls a subroutine adding 1 five times, receives the packet over the subroutine's
    first word and calls it once more: a0 = 5 + 100."""
    new = A.i("addi", A0, A0, 100)
    packet = SRAM + 0x400
    send = [
        *A.li(T0, NI),
        *A.li(T1, packet),
        A.store("sw", T1, T0, 0x04),  # SEND_ADDR
        A.i("addi", T2, 0, 4),
        A.store("sw", T2, T0, 0x08),  # SEND_SIZE: destination, length, two payload flits
        A.i("addi", T2, 0, 1),
        A.store("sw", T2, T0, 0x0C),  # SEND
        *exit_with(0),
    ]
    sender = program(send, {packet: flits(0x01, 2, new & 0xFFFF, new >> 16)})
    main = [
        *A.li(T0, NI),  # 0, 1
        A.i("addi", A0, 0, 0),  # 2
        *[A.jal(RA, 4 * (22 - k)) for k in range(3, 8)],  # 3..7: five calls of sub (word 22)
        *A.li(T1, SRAM + 4 * 21),  # 8, 9: the packet's two header flits land on the pad word 21
        A.store("sw", T1, T0, 0x10),  # 10: RECV_ADDR
        A.load("lw", T2, T0, 0x00),  # 11: poll NI_STATUS
        A.i("andi", T2, T2, 2),  # 12
        A.branch("beq", T2, 0, -8),  # 13
        A.i("addi", T2, 0, 2),  # 14
        A.store("sw", T2, T0, 0x0C),  # 15: RECV (the DMA writes words 21 and 22)
        A.jal(RA, 4 * (22 - 16)),  # 16: sub again, patched
        *exit_with(A0),  # 17, 18, 19
        0,  # 20
        0,  # 21: the pad word the header flits overwrite
        A.i("addi", A0, A0, 1),  # 22: sub
        A.jalr(0, RA, 0),  # 23
    ]
    assert len(main) == 24
    return sender, program(main)


@pytest.mark.parametrize("engine", ["interp", *ENGINES])
def test_a_packet_copied_over_translated_code_is_executed(engine: str) -> None:
    sender, patched = patcher_and_patched()
    chip = MPSoC(ChipConfig(), engine=engine)
    chip.load((1, 0), sender)
    chip.load((0, 1), patched)
    ran, tiles, tasks, noc = outcome(chip, 200_000)
    assert ran[2] == {(1, 0): 0, (0, 1): 105}
    if engine != "interp":
        chip_i = MPSoC(ChipConfig())
        chip_i.load((1, 0), sender)
        chip_i.load((0, 1), patched)
        assert (ran, tiles, tasks, noc) == outcome(chip_i, 200_000)


@pytest.mark.parametrize("engine", ENGINES)
def test_network_interface_errors_from_translated_code_are_the_interpreters(engine: str) -> None:
    loop_then_bad_store = [
        *A.li(T0, NI),
        A.i("addi", T1, 0, 50),
        A.i("addi", T1, T1, -1),  # a hot loop first: translated
        A.branch("bne", T1, 0, -4),
        A.store("sb", 0, T0, 0x0C),  # a byte store to NI_CMD
        *exit_with(0),
    ]
    results = []
    for which in ("interp", engine):
        chip = MPSoC(ChipConfig(), engine=which)
        chip.load((1, 0), program(loop_then_bad_store))
        results.append(outcome(chip, 100_000))
    assert results[0] == results[1]
    assert results[0][0][0] == "error" and "word loads and stores" in results[0][0][1]


def test_breakpoints_and_profiles_put_the_tile_back_on_the_interpreter() -> None:
    sender, patched = patcher_and_patched()
    chip = MPSoC(ChipConfig(), engine="jit")
    chip.load((1, 0), sender)
    chip.load((0, 1), patched)
    chip.set_breakpoint((0, 1), SRAM + 4 * 16)
    chip.step(100_000)
    assert chip.break_tile() == (0, 1) and chip.pc((0, 1)) == SRAM + 4 * 16
    assert chip._jit.on.tolist() == [0, 1, 0, 0]  # (1, 0) still translates; (0, 1) interprets
    chip.set_breakpoint((0, 1), SRAM + 4 * 16, on=False)
    chip.resume_from_break()
    chip.enable_profile()
    assert not chip._jit.on.any()
    assert chip.run(max_cycles=200_000).exit_codes[(0, 1)] == 105


def test_an_unknown_engine_is_refused() -> None:
    with pytest.raises(ValueError, match="engine: must be one of 'interp', 'jit', 'auto', got 'fast'"):
        MPSoC(ChipConfig(), engine="fast")


def test_auto_translates_the_busy_tiles_only_and_changes_nothing() -> None:
    """auto looks at each tile every AUTO_LOOK_CYCLES: a tile that computes gets a translator, a
    tile that waits for packets stays on the interpreter; the chip's state is the interpreter's."""
    from robosoc.benchmarks.chip import _build
    from robosoc.chip.translation import AUTO_LOOK_CYCLES

    busy = _build("matrix_bench.c", True, {"BENCH_ITERATIONS": 100000, "BENCH_QUIET": None})
    waiting = program([*A.li(T0, NI), A.store("sw", 0, T0, 0x24), *exit_with(0)])  # sleeps until a packet
    warm = MPSoC(ChipConfig(), engine="jit")  # translates the busy code in this process: auto reuses it at once
    warm.load((1, 0), busy)
    warm.step(100_000)
    states = {}
    for engine in ("interp", "auto"):
        chip = MPSoC(ChipConfig(), engine=engine)
        chip.load((1, 0), busy)
        chip.load((0, 1), busy)
        chip.load((1, 1), waiting)
        chip.step(4 * AUTO_LOOK_CYCLES + 12345)
        states[engine] = (
            chip.cycle,
            {xy: chip.counters(xy) for xy in chip.core_tiles()},
            {xy: chip.task_counters(xy) for xy in chip.core_tiles()},
            {xy: chip.pc(xy) for xy in chip.core_tiles()},
            chip.cores.regs.copy().tolist(),
        )
        if engine == "auto":
            translators = {chip.config.tile_xy(t): tr for t, tr in enumerate(chip._jit.translators)}
            assert translators[(1, 0)] is not None and translators[(0, 1)] is not None
            assert translators[(1, 1)] is None
            stats = chip._jit.stats
            assert stats is not None and stats.reused > 0
    assert states["auto"] == states["interp"]


def test_auto_looks_ever_less_often_at_a_chip_whose_tiles_stay_asleep(monkeypatch) -> None:
    """Every look at the tiles without a translator stops the chip loop; while looks find no busy
    tile the interval doubles up to AUTO_LOOK_MAX_CYCLES (a sleeping chip would otherwise spend its
    host time on them), and the chip's state stays the interpreter's."""
    from robosoc.benchmarks.chip import _build
    from robosoc.chip.translation import AUTO_LOOK_CYCLES, AUTO_LOOK_MAX_CYCLES, ChipTranslation

    sleepy = _build("sleepy_tick.c", True, {"TICKS": 1000})
    looks = []
    prepare = ChipTranslation.prepare

    def counted(self, chip):  # type: ignore[no-untyped-def]
        looks.append(chip.cycle)
        prepare(self, chip)

    monkeypatch.setattr(ChipTranslation, "prepare", counted)
    until = 16 * AUTO_LOOK_MAX_CYCLES
    states = {}
    for engine in ("interp", "auto"):
        looks.clear()
        chip = MPSoC(ChipConfig(), engine=engine)
        chip.load_all(sleepy)
        chip.step(until)
        states[engine] = (chip.cycle, {xy: chip.counters(xy) for xy in chip.core_tiles()})
    assert states["auto"] == states["interp"]
    assert chip._jit.look_cycles() == AUTO_LOOK_MAX_CYCLES
    assert all(tr is None for tr in chip._jit.translators)
    # the gaps between looks: 2**21, 2**22, ... up to 2**24, then 2**24 (against 2**20 throughout)
    gaps = [b - a for a, b in itertools.pairwise(looks)]
    assert gaps == sorted(gaps) and gaps[0] == 2 * AUTO_LOOK_CYCLES, gaps
    assert gaps[-2:] == [AUTO_LOOK_MAX_CYCLES] * 2, gaps
    assert len(looks) < until // AUTO_LOOK_MAX_CYCLES + 5


@pytest.mark.usefixtures("no_records")  # (a program whose code was translated whole gets its translators at once)
def test_auto_leaves_a_tile_that_works_in_short_bursts_on_the_interpreter() -> None:
    """A tile that wakes each millisecond for a short burst of work (about 0.026 instructions per
    cycle, as the fixed+mul flight's EKF tile, and more than AUTO_MIN_INSTRUCTIONS between the
    later looks) gets no translator while its code is not translated whole (robosoc.chip.whole_code):
    below AUTO_BUSY_SHARE the dispatch loop's calls per wake-up and per quantum cost more than the
    few regions auto would make save.  With four times the work per burst (0.1, as the float+mul
    flight's EKF tile) it gets one."""
    from robosoc.benchmarks.chip import _build
    from robosoc.chip.translation import AUTO_BUSY_SHARE, AUTO_LOOK_MAX_CYCLES, AUTO_MIN_INSTRUCTIONS

    shares = {}
    for work in (800, 3200):
        bursts = _build("sleepy_tick.c", True, {"TICKS": 1000, "WORK": work})
        chip = MPSoC(ChipConfig(), engine="auto")
        chip.load_all(bursts)
        chip.step(AUTO_LOOK_MAX_CYCLES)
        c = chip.counters(chip.core_tiles()[0])
        shares[work] = share = c["instructions"] / c["cycles"]
        assert share * AUTO_LOOK_MAX_CYCLES / 4 > AUTO_MIN_INSTRUCTIONS  # enough work for the later looks
        translated = [tr is not None for tr in chip._jit.translators]
        assert any(translated) == (work == 3200), (work, share)
    assert AUTO_BUSY_SHARE / 2 < shares[800] < AUTO_BUSY_SHARE < shares[3200]


@pytest.mark.usefixtures("no_records")  # regions recorded by earlier runs would be entered at once
def test_auto_compiles_in_the_background_and_changes_nothing(monkeypatch) -> None:
    """With a cold object cache auto hands regions to the compiling thread and the tile interprets
    them meanwhile; what the thread compiled is entered at the next step (here: after waiting for
    it), and the chip's state is the interpreter's whatever the timing."""
    monkeypatch.setattr("robosoc.jit.policy.AUTO_WARMUP_SECONDS", 0.0)  # short runs translate too
    from robosoc.benchmarks.chip import _build
    from robosoc.chip.translation import AUTO_LOOK_CYCLES
    from robosoc.jit import tables as jit_tables
    from robosoc.jit.compiler import Compiler

    monkeypatch.setattr(jit_tables, "_TRANSLATED", {})  # nothing an earlier test translated in this process
    monkeypatch.setattr(jit_tables, "_FRESH_TABLES", {})

    monkeypatch.setattr(Compiler, "ready", lambda self, ir: False)  # nothing cached
    busy = _build("matrix_bench.c", True, {"BENCH_ITERATIONS": 100000, "BENCH_QUIET": None})
    states = {}
    for engine in ("interp", "auto"):
        chip = MPSoC(ChipConfig(), engine=engine)
        chip.load((1, 0), busy)
        chip.load((0, 1), busy)
        for k in range(1, 9):
            chip.step(k * AUTO_LOOK_CYCLES)
            chip._jit.finish_compiles(wait=True)
        states[engine] = (
            chip.cycle,
            {xy: chip.counters(xy) for xy in chip.core_tiles()},
            {xy: chip.pc(xy) for xy in chip.core_tiles()},
            chip.cores.regs.copy().tolist(),
        )
    stats = chip._jit.stats
    assert stats is not None and stats.background > 0 and stats.regions > 0
    assert all(tr.compiling() == 0 for tr in chip._jit.translators if tr is not None)
    assert states["auto"] == states["interp"]


@pytest.mark.usefixtures("no_records")
def test_the_chip_looks_at_its_tiles_again_only_when_something_changed(monkeypatch) -> None:
    """Before each run of the chip loop every tile is given what other tiles translated and its
    current tables; when nothing changed since the last look (no region entered anywhere, no tile
    loaded or stopped) the look is skipped, and each of those changes brings it back."""

    def counting(rounds: int) -> Program:
        return program(
            [
                A.i("addi", A0, 0, 0),
                A.i("addi", T1, 0, rounds),
                A.i("addi", A0, A0, 1),  # 2: loop
                A.i("addi", T1, T1, -1),
                A.branch("bne", T1, 0, -8),
                *exit_with(A0),  # 5, 6, 7
                A.i("addi", A0, A0, 2),  # 8: a subroutine nobody calls
                A.jalr(0, RA, 0),
            ]
        )

    sub = SRAM + 4 * 8
    looks = count_looks(monkeypatch)
    chip = MPSoC(ChipConfig(), engine="jit")
    a, b = (chip.config.tile_index(xy) for xy in ((1, 0), (0, 1)))
    chip.load((1, 0), counting(50))
    chip.load((0, 1), counting(50))
    chip.step(20)  # both tiles translate their first regions
    jit = chip._jit
    jit.prepare(chip)
    jit.prepare(chip)
    looks.clear()
    jit.prepare(chip)
    assert looks == []  # nothing new
    translators = jit.translators
    assert translators[a] is not None and translators[b] is not None
    assert translators[b].tables().entry_fn[8] == 0
    translators[a].translate(sub)  # entered by tile a: tile b is given it at the next look
    jit.prepare(chip)
    assert sorted(looks) == sorted([a, b])
    assert translators[b].tables().entry_fn[8] != 0
    looks.clear()
    jit.prepare(chip)
    assert looks == []
    chip.load((0, 1), counting(60))  # as long as before: only the load tells
    jit.prepare(chip)
    assert b in looks
    assert jit._given[b] is translators[b].tables()  # the tables made for the new code
    # the region at the entry held the changed word; the subroutine's words are the same
    assert translators[b].tables().entry_fn[0] == 0 and translators[b].tables().entry_fn[8] != 0
    assert chip.run(max_cycles=100_000).exit_codes == {(1, 0): 50, (0, 1): 60}


@pytest.mark.usefixtures("no_records")
def test_auto_does_not_look_at_its_translators_while_only_an_idle_tile_is_watched(monkeypatch) -> None:
    """auto watches a loaded tile without a translator (it may turn busy): at a look that finds it
    still idle, and between looks, the tiles with translators are not looked at again unless
    something changed (before, every step of a flight looked at them: 0.2 ms per step), and the
    next look at the idle tile comes twice as late."""
    from robosoc.chip.translation import AUTO_LOOK_CYCLES

    monkeypatch.setattr("robosoc.jit.policy.AUTO_WARMUP_SECONDS", 0.0)
    monkeypatch.setattr("robosoc.jit.policy.AUTO_BACKGROUND", False)
    monkeypatch.setattr("robosoc.jit.policy.AutoPolicy.budget", lambda self: float("inf"))
    looks = count_looks(monkeypatch)

    def counting(rounds: int) -> Program:
        loop = [A.i("addi", A0, A0, 1), A.i("addi", T1, T1, -1), A.branch("bne", T1, 0, -8)]
        return program([A.i("addi", A0, 0, 0), *A.li(T1, rounds), *loop, *exit_with(A0)])

    chip = MPSoC(ChipConfig(), engine="auto")
    busy, idle = (chip.config.tile_index(xy) for xy in ((1, 0), (0, 1)))
    chip.load((1, 0), counting(10**7))
    chip.load((0, 1), counting(1))  # exits at once: loaded, never busy
    jit = chip._jit
    for k in range(1, 5):
        chip.step(k * AUTO_LOOK_CYCLES)
    assert jit.translators[busy] is not None and jit.translators[idle] is None
    assert jit.watching()
    jit.prepare(chip)
    looks.clear()
    look = jit.look_cycles()
    for _ in range(3):  # between looks
        jit.prepare(chip)
    assert looks == [] and jit.look_cycles() == look
    chip.step(chip.cycle + look)
    jit.prepare(chip)  # a look at the idle tile: still idle
    assert looks == [] and jit.look_cycles() == min(2 * look, 1 << 24)
    assert jit.translators[idle] is None
    assert jit.translators[busy].tables().entry_fn[0] == 0  # the first word ran once: not translated
    jit.translators[busy].translate(SRAM)  # a region entered: the translators are looked at
    jit.prepare(chip)
    assert looks == [busy]


def test_auto_makes_no_translator_for_a_chip_that_never_turns_busy_yet_counts_its_run_time() -> None:
    """A run whose tiles never turn busy does without the translating engine (not even imported:
    30-45 ms a process); a tile that turns busy later gets a budget and warm-up counted from the
    chip's start."""
    import subprocess
    import sys

    script = (
        "import sys\n"
        "from robosoc.benchmarks.chip import _build\n"
        "from robosoc.chip.mpsoc import MPSoC\n"
        "from robosoc.config.chip import ChipConfig\n"
        "chip = MPSoC(ChipConfig(), engine='auto')\n"
        "chip.load_all(_build('sleepy_tick.c', True, {'TICKS': 20}))\n"
        "chip.step(3_000_000)\n"
        "print(chip._jit.stats is None, 'robosoc.jit.engine' in sys.modules)\n"
    )
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=600, check=True)
    assert done.stdout.split() == ["True", "False"], done.stderr

    from robosoc.benchmarks.chip import _build

    busy = _build("matrix_bench.c", True, {"BENCH_ITERATIONS": 100000, "BENCH_QUIET": None})
    waiting = program([*A.li(T0, NI), A.store("sw", 0, T0, 0x24), *exit_with(0)])  # sleeps until a packet
    chip = MPSoC(ChipConfig(), engine="auto")
    chip.load((1, 1), waiting)
    chip.step(5_000_000)
    assert chip._jit.stats is None
    before = chip._jit._run_seconds
    assert before > 0
    chip.load((1, 0), busy)
    chip.step(chip.cycle + 5_000_000)
    stats = chip._jit.stats
    assert stats is not None and chip._jit.translators[chip.config.tile_index((1, 0))] is not None
    assert stats.run_seconds == chip._jit._run_seconds > before  # counted from the chip's start


def test_the_tiles_holding_one_program_get_copies_of_the_first_tiles_tables(monkeypatch) -> None:
    """A run's first look makes the first new tile's translator and copies its tables for every
    tile holding the same code and build (``TranslatingCore.clones``), then the same for the first
    tile left: each copy equals what the tile would make itself, its own wherever a core writes in
    place; the chip runs as on the interpreter."""
    import numpy as np

    from robosoc.isa.table import OP_ENTRY
    from robosoc.jit.engine import TranslatingCore

    monkeypatch.setattr(jit_tables, "_TRANSLATED", {})
    monkeypatch.setattr(jit_tables, "_FRESH_TABLES", {})

    def counting(rounds: int) -> Program:
        loop = [A.i("addi", A0, 0, 0), A.i("addi", T1, 0, rounds), A.i("addi", A0, A0, 1)]
        return program([*loop, A.i("addi", T1, T1, -1), A.branch("bne", T1, 0, -8), *exit_with(A0)])

    fifty, seventy = counting(50), counting(70)
    loads = {(1, 0): fifty, (2, 0): seventy, (0, 1): fifty, (1, 1): seventy, (2, 1): fifty}

    def chip_with(engine_name: str) -> MPSoC:
        chip = MPSoC(ChipConfig(width=3, height=2), engine=engine_name)
        for xy, prog in loads.items():
            chip.load(xy, prog)
        return chip

    chip_with("jit").run(max_cycles=100_000)  # every region translated once in this process
    adopted = []
    adopt = TranslatingCore._adopt
    monkeypatch.setattr(
        TranslatingCore, "_adopt", lambda self, adoption, copy: (adopted.append(self.tile), adopt(self, adoption, copy))
    )
    chip = chip_with("jit")
    chip._jit.prepare(chip)
    tiles = {xy: chip.config.tile_index(xy) for xy in loads}
    # (1, 0) is made and (0, 1) and (2, 1) copy its tables; then (2, 0), the first tile left, and
    # (1, 1) copies its; a copy's translator is made when asked for
    assert adopted == []
    assert all(chip._jit.on[t] for t in tiles.values())
    assert [t for t, _ in chip._jit.translators.made_items()] == [tiles[(1, 0)], tiles[(2, 0)]]
    assert all(chip._jit.translators[t] is not None for t in tiles.values())
    assert adopted == [tiles[(0, 1)], tiles[(1, 1)], tiles[(2, 1)]]
    got = {t: [a.copy() for a in chip._jit.translators[t].tables()] for t in tiles.values()}
    translators = {t: chip._jit.translators[t] for t in tiles.values()}
    known = {t: (tr._known_seen, set(tr._known_starts_in)) for t, tr in translators.items() if tr}
    marks = {t: chip.cores.dec[t] == OP_ENTRY for t in tiles.values()}
    first, copy = (chip._jit.translators[tiles[xy]].tables() for xy in ((1, 0), (0, 1)))
    other = chip._jit.translators[tiles[(2, 1)]].tables()  # copied in the same round as (0, 1)
    for name in ("entry_fn", "entry_blk", "hot", "tmap", "ctx"):
        assert not np.shares_memory(getattr(first, name), getattr(copy, name)), name
        assert not np.shares_memory(getattr(copy, name), getattr(other, name)), name
    # what the chip loop reads for each tile is what its translator holds (one call set them all)
    for t in tiles.values():
        given = chip._jit._tables[t]
        held = chip._jit.translators[t].tables()
        for name, a, b in zip(held._fields, given, held, strict=True):
            assert a.ctypes.data == b.ctypes.data and a.shape == b.shape, (t, name)
    monkeypatch.setattr(jit_tables, "_FRESH_TABLES", {})
    for t in tiles.values():
        afresh = TranslatingCore(chip.cores, tile=t, mode="jit")
        want = afresh.tables()  # made afresh, marks again
        assert known[t] == (afresh._known_seen, afresh._known_starts_in)
        for name, a, b in zip(want._fields, got[t], want, strict=True):
            assert np.array_equal(a, b), (t, name)
        assert np.array_equal(marks[t], chip.cores.dec[t] == OP_ENTRY)
        assert marks[t].any()
    ran = outcome(chip_with("jit"), 100_000)
    assert ran == outcome(chip_with("interp"), 100_000)
    assert ran[0][2] == {(1, 0): 50, (2, 0): 70, (0, 1): 50, (1, 1): 70, (2, 1): 50}


@pytest.mark.usefixtures("no_records")
def test_a_copys_translator_made_late_holds_the_tables_of_the_first_when_copied(monkeypatch) -> None:
    """A tile whose tables are a copy of the first tile's gets its translator only when asked for;
    made after the first tile translated another region, it holds its copy as made (the first's
    bookkeeping then, not now), is given the new region at the next look, and its tables equal
    those it makes afresh; the chip's counts of reused regions are those of translators made at once."""
    import numpy as np

    monkeypatch.setattr(jit_tables, "_TRANSLATED", {})
    monkeypatch.setattr(jit_tables, "_FRESH_TABLES", {})
    from robosoc.jit.engine import TranslatingCore

    words = [
        A.i("addi", A0, 0, 0),
        A.i("addi", T1, 0, 40),
        A.i("addi", A0, A0, 1),  # 2: loop
        A.i("addi", T1, T1, -1),
        A.branch("bne", T1, 0, -8),
        *exit_with(A0),  # 5, 6, 7
        A.jal(0, 0),  # 8: (a region's blocks go on after the exit store)
        A.i("addi", A0, A0, 2),  # 9: a subroutine nobody calls
        A.jalr(0, RA, 0),
    ]
    prog = program(words)
    xys = [(1, 0), (0, 1), (1, 1)]

    def loaded() -> MPSoC:
        chip = MPSoC(ChipConfig(), engine="jit")
        for xy in xys:
            chip.load(xy, prog)
        return chip

    loaded().run(max_cycles=100_000)  # the loop's regions translated in this process
    chip = loaded()
    jit = chip._jit
    first, b, c = (chip.config.tile_index(xy) for xy in xys)
    jit.prepare(chip)
    assert [t for t, _ in jit.translators.made_items()] == [first]
    reused = jit.stats.reused
    made_first = jit.translators[first]
    assert made_first.tables().entry_fn[9] == 0
    made_first.translate(SRAM + 4 * 9)  # a region only the first tile holds so far
    jit.prepare(chip)  # the others are given it (their translators made now, from their copies)
    assert jit.stats.reused == reused + 2  # each copy entered the new region
    for t in (b, c):
        tr = jit.translators[t]
        assert tr is not None and tr.tables().entry_fn[9] != 0
        given = jit._tables[t]
        assert all(x.ctypes.data == y.ctypes.data for x, y in zip(given, tr.tables(), strict=True))
    got = {t: [a.copy() for a in jit.translators[t].tables()] for t in (b, c)}
    monkeypatch.setattr(jit_tables, "_FRESH_TABLES", {})
    for t in (b, c):
        want = TranslatingCore(chip.cores, tile=t, mode="jit").tables()  # made afresh
        for name, x, y in zip(want._fields, got[t], want, strict=True):
            if name != "ctx":  # (the dispatch loop's addresses and statistics: compared through the run below)
                assert np.array_equal(x, y), (t, name)
    ran = outcome(chip, 100_000)
    assert ran == outcome(loaded_interp(prog, xys), 100_000)
    assert ran[0][2] == dict.fromkeys(xys, 40)


def loaded_interp(prog: Program, xys: list[tuple[int, int]]) -> MPSoC:
    chip = MPSoC(ChipConfig(), engine="interp")
    for xy in xys:
        chip.load(xy, prog)
    return chip


def task_switching(outer: int, inner: int) -> list[int]:
    """Each of ``outer`` rounds stores a TASK_ID (round & 3) and runs a loop of ``inner`` iterations
    whose block loads, in its middle, from an SRAM word and from IRQ_MASK in turn (a side exit of
    the translated block every other iteration)."""
    data = 22  # a word of the program, loaded
    return [
        A.i("addi", A0, 0, 0),  # 0
        A.i("addi", T1, 0, outer),  # 1
        *A.li(T2, NI + 0x20),  # 2, 3: TASK_ID
        *A.li(29, SRAM + 4 * data),  # 4, 5
        *A.li(30, (SRAM + 4 * data) ^ 0xF0000020),  # 6, 7: base ^ IRQ_MASK
        A.i("andi", T0, T1, 3),  # 8: round
        A.store("sw", T0, T2, 0),  # 9: the task switch
        A.i("addi", 28, 0, inner),  # 10
        A.i("addi", A0, A0, 3),  # 11: loop
        A.r("xor", 29, 29, 30),  # 12
        A.shift("slli", 11, A0, 1),  # 13
        A.load("lw", 12, 29, 0),  # 14: SRAM or IRQ_MASK
        A.r("add", A0, A0, 12),  # 15
        A.r("add", A0, A0, 11),  # 16
        A.i("addi", 28, 28, -1),  # 17
        A.branch("bne", 28, 0, -28),  # 18: back to word 11
        A.i("addi", T1, T1, -1),  # 19
        A.branch("bne", T1, 0, -48),  # 20: back to word 8
        A.i("andi", A0, A0, 0xFF),  # 21
        *exit_with(A0),  # 22 (the data word), 23, 24
    ]


@pytest.mark.usefixtures("no_records")
@pytest.mark.parametrize("engine", ENGINES)
def test_task_switches_between_translated_stretches_charge_each_task_as_the_interpreter(
    engine: str, monkeypatch
) -> None:
    """Translated blocks add what they execute to the tile's counters themselves, so a TASK_ID
    store (the chip loop's) charges the task that ran before it with exactly its instructions:
    per operation, per tile and per task, the counters are the interpreter's, with side exits in
    the middle of translated blocks between the switches."""
    from robosoc.kernels.jit_dispatch import CTX_CALLS, CTX_DEVICE

    monkeypatch.setattr(jit_tables, "_TRANSLATED", {})
    prog = program(task_switching(12, 30))
    xys = [(1, 0), (1, 1)]

    def loaded(name: str) -> MPSoC:
        chip = MPSoC(ChipConfig(), engine=name)
        for xy in xys:
            chip.load(xy, prog)
        return chip

    loaded(engine).run(max_cycles=2_000_000)  # the loops translated in this process
    chip = loaded(engine)
    got = outcome(chip, 2_000_000)
    want = outcome(loaded("interp"), 2_000_000)
    assert got == want
    ran, _, tasks, _ = want
    assert ran[2] == dict.fromkeys(xys, ran[2][xys[0]])  # every tile exited
    for xy in xys:
        assert sorted(tasks[xy]) == [0, 1, 2, 3]  # each task charged its rounds
    if engine == "jit":  # (auto may leave such short runs to the interpreter)
        for xy in xys:
            translator = chip._jit.translators[chip.config.tile_index(xy)]
            assert translator is not None
            ctx = translator.tables().ctx
            assert ctx[CTX_CALLS] > 50 and ctx[CTX_DEVICE] > 50  # translated, with side exits
