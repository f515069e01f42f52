"""The translator of one core: its tables, and translating the regions the dispatch loop asks for.

``TranslatingCore(state).step_until(until)`` runs like ``run_cores(state.arrays(), [tile], until)``
and leaves the same RUN_* status; in between it translates the regions that turn hot (``jit``: at
their first arrival; ``auto``: after :data:`AUTO_THRESHOLD` arrivals, and only while compiling stays
a small share of the run, see :data:`AUTO_COMPILE_SHARE`).  Counts, cycles, outputs and errors are
those of the interpreter (docs/translation.md).
"""

from __future__ import annotations

import time
import weakref
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from robosoc.isa.table import OP_ENTRY
from robosoc.jit.compiler import Compiler, Pending, add_to_manifest, manifest_key, read_manifest, shared_compiler
from robosoc.jit.target import Target
from robosoc.kernels import compiled_or_cached
from robosoc.kernels.core import run_cores
from robosoc.kernels.core_layout import (
    ERRATA_RTL,
    RUN_CHUNK,
    S_CODE_SIZE,
    S_CYCLE,
    S_ERRATA,
    S_MEM_BASE,
    S_MEM_SIZE,
    S_MUL,
    S_PC,
    S_RUN,
)
from robosoc.kernels.jit_dispatch import (
    CTX_FLUSHES,
    CTX_WORDS,
    NEVER_TRANSLATE,
    RUN_TRANSLATE,
    JitArrays,
    empty_tables,
    flush_counts,
    run_translated,
)

if TYPE_CHECKING:
    from robosoc.chip.core_state import CoreState
    from robosoc.jit.emit_ir import EmittedRegion
    from robosoc.jit.regions import CodeView, Region

# Finding and writing regions (robosoc.jit.regions, robosoc.jit.emit_ir) is imported at the first
# translation: a short run of auto translates nothing, and importing them cost it 16-20 ms when
# Python had to compile their source.

#: Arrivals at a word without a translation before ``auto`` translates a region there; between
#: arrivals the interpreter runs AUTO_STRETCH cycles at its own speed, so arrivals sample where
#: the program spends its time.  A region costs the run about 10 ms (writing it on the main
#: thread, compiling it beside: docs/translation.md), so only code where the run spends a
#: sizeable share is worth it: with 3 the matrix benchmark translated some 40 regions in its
#: first second, many of them lukewarm; with 20, runs of 0.7, 1.1 and 3.6 s interpreted took
#: 0.66-0.67, 0.88-0.92 and 1.53 s against 0.70, 0.92-1.12 and 1.67 s with 3 (medians of 4-5
#: runs), and the 10 s flight was no slower.
AUTO_THRESHOLD = 20
AUTO_STRETCH = 20_000
#: ``auto`` compiles a region (not in the object cache) only if the compile time spent so far plus
#: its estimate stays within this share of the time the core has run: whatever the program, auto
#: then takes at most (1 + share) x the time of the engine without translation, and less as soon
#: as the translated code runs (ski rental).  A region whose object is cached is installed at once.
AUTO_COMPILE_SHARE = 0.25
#: The estimate of a region's compile time before any was measured in this process (measured on
#: the test programs: about 0.25 ms per guest instruction and 2 ms per module, CPU time).
ESTIMATED_SECONDS_PER_INSTRUCTION = 0.3e-3
ESTIMATED_SECONDS_PER_MODULE = 3e-3
#: numba's compile time of the dispatch loop (``run_translated``, with its copy of the interpreter), 20
#: to 36 s on the 2-core machine: ``auto`` on one core of a fresh install interprets (``run_cores``,
#: which ``interp`` compiles too) until it has run 1/AUTO_COMPILE_SHARE times that long.  Any chip
#: run, or a ``jit`` run, compiles it (into numba's cache) on the way.
ESTIMATED_DISPATCH_LOOP_SECONDS = 30.0
_dispatch_loop_ready = False  # compiled or cached: looked up until it is
#: ``auto`` translates nothing (unless its objects are cached) before the core (the chip), or the
#: cores of the same build in this process, have run this long: a shorter run is interpreted as by
#: ``interp``, at its speed.  Translating costs the main thread time (finding and writing regions,
#: entering them) that a run this short does not win back: the matrix benchmark (0.1 s of
#: interpreting) took 0.15 s without it, 0.11 s with it; at 1.1 s it gives up a third of auto's
#: gain (docs/translation.md).
AUTO_WARMUP_SECONDS = 0.2
#: Regions of ``auto`` are smaller (a hot loop and what it calls, rather than whole functions): the
#: cost of each decision stays small.
AUTO_MAX_REGION_INSTRUCTIONS = 100
#: ``auto`` compiles its regions in a background thread (the core interprets them meanwhile, and a
#: second host core compiles): on one core and on the chip.  Tests that need a region translated
#: before a short run ends set it False (compiling in line, within the budget).
AUTO_BACKGROUND = True
#: auto with background compiling: regions of a core waiting for the compiling thread at most;
#: while the queue is full the dispatch loop asks for no region (each would only stop the loop to
#: be parked: 120-270 stops of about 0.1 ms in a 0.1 s run of the matrix benchmark)
BACKGROUND_QUEUE = 4
#: ... and while regions compile it comes back every this many cycles to enter those done (a few
#: ms of interpreting)
POLL_CYCLES = 1 << 20
THRESHOLDS = {"jit": 1, "auto": AUTO_THRESHOLD}
NEVER_ASK = 1 << 40  # a threshold no word reaches
_KEY_FIELDS = [S_MEM_BASE, S_MEM_SIZE, S_CODE_SIZE, S_ERRATA, S_MUL]  # the state fields of a build
STRETCHES = {"jit": 0, "auto": AUTO_STRETCH}
M32 = 0xFFFFFFFF


@dataclass(frozen=True)
class _Translated:
    """A region translated in this process, reusable while its words hold the same instructions."""

    region: Region
    emitted: EmittedRegion
    address: int  # of the region function (0: nothing translated)
    pcs: np.ndarray  # word indices of the translated instructions
    words: np.ndarray  # their contents when translated
    #: its count slots: (operation or counter, delta) rows, rows per slot, next slot (region-relative, -1: none)
    slot_rows: np.ndarray
    slot_lens: np.ndarray
    slot_next: np.ndarray
    #: addresses of its blocks' starts and the blocks' indices; addresses its side exits continue at
    block_starts: np.ndarray
    block_indices: np.ndarray
    side_exits: np.ndarray
    #: per word of ``pcs``: the instructions from it to the end of its block (1..255: the dispatch
    #: loop's ``tmap``, which lets the interpreter run the rest of a block entered in the middle)
    rest: np.ndarray

    @staticmethod
    def of(
        region: Region, emitted: EmittedRegion, address: int, pcs: np.ndarray, words: np.ndarray, base: int
    ) -> _Translated:
        from robosoc.jit.regions import End

        slots = emitted.slots if region.blocks else []
        rows = np.array([row for h, _ in slots for row in h], dtype=np.int64).reshape(-1, 2)
        lens = np.array([len(h) for h, _ in slots], dtype=np.int64)
        nxt = np.array([n for _, n in slots], dtype=np.int64)
        starts = np.array(list(emitted.blocks), dtype=np.int64)
        indices = np.array(list(emitted.blocks.values()), dtype=np.int64)
        sides = np.array([b.next_pc for b in region.blocks.values() if b.end is End.SIDE], dtype=np.int64)
        left = {(i.pc - base) >> 2: len(b.insns) - k for b in region.blocks.values() for k, i in enumerate(b.insns)}
        rest = np.array([min(left.get(int(w), 1), 255) for w in pcs], dtype=np.uint8)
        return _Translated(region, emitted, address, pcs, words, rows, lens, nxt, starts, indices, sides, rest)


#: (target, multiplier) -> regions translated in this process (any core, any run), in order
_TRANSLATED: dict[tuple[Target, bool], list[_Translated]] = {}
#: (build, region start) -> the module the background thread compiles for some core; another core
#: asking for the region waits for it, then enters it itself (the thread loaded it into the engine),
#: so a core that is gone before its region was done (a run that ended) keeps nobody waiting
_COMPILING: dict[tuple[tuple[Target, bool], int], Pending] = {}


@dataclass(frozen=True)
class _FreshTables:
    """A core's tables right after they were made afresh and the regions known then entered."""

    done_list: list[_Translated]  # _TRANSLATED's list they were made from (a test may replace it)
    seen: int  # its entries then
    code: np.ndarray  # the core's code words then
    code_bytes: bytes  # ... as bytes (compared faster)
    tables: JitArrays
    mark_rows: np.ndarray  # the predecode rows of the words with an entry (OP_ENTRY there)
    slot_hist: tuple[np.ndarray, ...]
    slot_len: tuple[np.ndarray, ...]
    slot_next: tuple[np.ndarray, ...]
    nslots: int
    starts_in: frozenset[int]


#: build -> seconds its cores ran in the dispatch loop in this process (a warm-up passed by earlier
#: runs of a program, a benchmark's, counts for the next)
_BUILD_SECONDS: dict[tuple[Target, bool], float] = {}
#: build -> the last fresh tables made for it (copied by the next core of that build and code)
_FRESH_TABLES: dict[tuple[Target, bool], _FreshTables] = {}


#: the translators of this process (those of ``auto``: whether a region still compiling is wanted)
_LIVE: weakref.WeakSet[TranslatingCore] = weakref.WeakSet()


def _wanted(key: tuple[Target, bool], pcs: np.ndarray, words: np.ndarray) -> Callable[[], bool]:
    """Whether a live core of build ``key`` holds ``words`` at ``pcs`` (asked by the compiling
    thread before it compiles a region: a benchmark's next run, a chip's other tiles still want
    it; the next test's program does not)."""

    def wanted() -> bool:
        try:
            cores = list(_LIVE)
        except RuntimeError:  # the set changed meanwhile (the main thread made or dropped a core)
            return True
        return any(c._key() == key and np.array_equal(c.state.m32[c.tile][pcs], words) for c in cores)

    return wanted


#: the tables a core writes in place (the dispatch loop, entering regions, forgetting them); the
#: others are replaced whole when they change, so cores copying one core's tables share them
_WRITTEN_IN_PLACE = ("entry_fn", "entry_slot", "entry_blk", "hot", "tmap", "cnt", "ctx")


def _own_copy(jt: JitArrays) -> JitArrays:
    """``jt`` with copies of the arrays written in place (for another core, or to keep)."""
    return jt._replace(**{name: getattr(jt, name).copy() for name in _WRITTEN_IN_PLACE})


_ENTERED = 0  # regions entered as translated in this process (any core): see entered_regions()


def entered_regions() -> int:
    """How many times a region was noted as translated in this process: while it stays the same,
    no core has a region of another core to enter (a chip skips its per-tile look)."""
    return _ENTERED


def translated_instructions() -> int:
    """Guest instructions in the regions this process translated."""
    return sum(t.region.instructions for regions in _TRANSLATED.values() for t in regions)


@dataclass
class TranslationStats:
    regions: int = 0
    instructions: int = 0  # guest instructions translated
    flushes: int = 0  # times self-modifying code made the core forget its translations
    reused: int = 0  # regions this process had translated already (same words)
    deferred: int = 0  # auto: hot regions left to the interpreter for now (compiling would cost too much yet)
    background: int = 0  # regions handed to the background thread
    run_seconds: float = 0.0  # host time in the dispatch loop
    translate_seconds: float = 0.0  # host time finding, writing and compiling regions (deferrals included)


class TranslatingCore:
    """Runs one tile of a :class:`CoreState` with translated regions (engine ``jit`` or ``auto``)."""

    def __init__(
        self,
        state: CoreState,
        tile: int = 0,
        mode: str = "jit",
        compiler: Compiler | None = None,
        stats: TranslationStats | None = None,
    ) -> None:
        """``stats``: shared by the translators of one chip (auto's compile budget is the chip's)."""
        if mode not in THRESHOLDS:
            raise ValueError(f"engine: must be one of {', '.join(map(repr, THRESHOLDS))}, got {mode!r}")
        self.state = state
        self.tile = tile
        self.mode = mode
        self.threshold = THRESHOLDS[mode]
        self.stretch = STRETCHES[mode]
        self._compiler = compiler
        self.stats = stats if stats is not None else TranslationStats()
        self._tiles = np.array([tile], dtype=np.int64)
        self._parked: dict[int, int] = {}  # auto: word index -> pc of a deferred region (not sampled for now)
        self._sizes: dict[int, int] = {}  # auto: pc -> instructions of the region found there
        self._code_size = -1
        self._jt: JitArrays | None = None
        self._key_raw = b""  # the state fields _key() was made from, and what it made
        self._key_made: tuple[Target, bool]  # made at the first call (no fields are b"")
        self._manifest: str | None = None  # the loaded code's manifest key (_manifest_key)
        self._known_seen = 0  # entries of _TRANSLATED[key] this core has looked at
        self._known_starts_in: set[int] = set()  # starts of the regions installed from there or translated here
        #: compile regions in the background thread (auto): the core interprets them meanwhile
        self.background = mode == "auto" and AUTO_BACKGROUND
        if self.background:
            _LIVE.add(self)
        self._compiling: list[tuple[Pending, Region, EmittedRegion, np.ndarray, np.ndarray]] = []

    @property
    def compiler(self) -> Compiler:
        """The compiler (created at the first translation: LLVM's set-up is not paid by cold code)."""
        if self._compiler is None:
            self._compiler = shared_compiler()
        return self._compiler

    # --- tables -------------------------------------------------------------------------------
    def forget(self) -> None:
        """Drop every translation (call after writing code from outside the core, or before the
        core goes back to the interpreter for good)."""
        self._clear_marks()
        self._code_size = -1
        self._jt = None

    def _clear_marks(self) -> None:
        """The interpreter no longer stops before translated blocks (their OP_ENTRY rows, see
        :meth:`_mark`, are decoded again when executed)."""
        rows = self.state.op_rows(self.tile)
        rows[rows == OP_ENTRY] = 0

    def _mark(self, at: np.ndarray) -> None:
        """Let the interpreter stop before the blocks starting at word indices ``at`` (OP_ENTRY in
        their predecode rows), so that the dispatch loop runs them translated even when the
        interpreter reaches them in a stretch.  A trap's shadow may be one: the trap sets the
        controller's next look one cycle after it, so the loop runs the shadow (translated or not)
        before the vector."""
        self.state.dec[self.tile, 2 * at] = OP_ENTRY

    def tables(self) -> JitArrays:
        """The tables the dispatch loop reads (its statistics are in ``ctx``: CTX_CALLS, CTX_STEPS ...)."""
        return self._tables()

    def _tables(self) -> JitArrays:
        code = int(self.state.st[self.tile, S_CODE_SIZE])
        if self._jt is None or code != self._code_size:
            self._clear_marks()
            self._code_size = code
            self._flushes_seen = 0
            self._parked.clear()
            if not self._install_as_before():
                self._jt = empty_tables(code // 4 + 1)  # the word after the code: its fetch error is the interpreter's
                self._slot_hist: list[np.ndarray] = []  # per region: (kc, delta) rows of its slots
                self._slot_len: list[np.ndarray] = []
                self._slot_next: list[np.ndarray] = []
                self._nslots = 0
                self._install_known()
                self._remember_install()
            self._manifest = None  # the code's manifest key, made again when first asked for
            self._known_starts = read_manifest(self._manifest_key()) if self.mode == "auto" else set()
            self._cached_starts = frozenset(self._known_starts)  # compiled by an earlier run: installed at once
        return self._jt

    def _manifest_key(self) -> str:
        """The loaded code and build options: the key of the list of regions compiled for them
        before (made once per load of the code: hashing it cost each region 0.1 ms)."""
        if self._manifest is None:
            code = self.state.m8[self.tile, : self._code_size].tobytes()
            self._manifest = manifest_key(code, f"{self._key()!r} {self.mode}")
        return self._manifest

    def _target(self) -> Target:
        return self._key()[0]

    def _view(self) -> CodeView:
        from robosoc.jit.regions import CodeView

        st = self.state.st[self.tile]
        base = int(st[S_MEM_BASE])
        m32 = self.state.m32[self.tile]
        return CodeView(
            word=lambda a: int(m32[(a - base) >> 2]) & M32,
            base=base,
            code_size=int(st[S_CODE_SIZE]),
            mem_size=int(st[S_MEM_SIZE]),
            has_mul=int(st[S_MUL]) != 0,
        )

    # --- translation --------------------------------------------------------------------------
    def _install_known(self) -> None:
        """Enter every region this process translated for the same build whose words are unchanged
        (after the tables were made afresh, or self-modifying code made the core forget them)."""
        self._known_seen = 0
        self._known_starts_in = set()
        self._install_new_known()

    def _install_as_before(self) -> bool:
        """Fresh tables: copy those a core of the same build made fresh if its code held the same
        words, and enter the regions translated since (the cores of a chip load one program: its
        translations are entered once, not once per tile)."""
        key = self._key()
        done_list = _TRANSLATED.get(key)
        made = _FRESH_TABLES.get(key)
        if made is None or done_list is None or made.done_list is not done_list:
            return False
        if self.state.m32[self.tile, : len(made.code)].tobytes() != made.code_bytes:
            return False
        self._take(made.tables, made.slot_hist, made.slot_len, made.slot_next, made.nslots, made.seen, made.starts_in)
        self.state.dec[self.tile, made.mark_rows] = OP_ENTRY  # as _mark(): a 16x16 chip does it 255 times
        if made.seen != len(done_list):
            self._install_new_known()  # translated since
        return True

    def clones(self, tiles: list[int]) -> dict[int, TranslatingCore]:
        """Translators for other tiles of this core's state holding its code and build, their
        tables copies of this core's (which must not have run yet: made in the same look), keyed
        by tile; tiles with other code or another build are left out.  The tiles of a chip load
        one program: made one by one, a translator and its tables cost about 35 µs in Python, 9-13
        ms for a 16x16 chip at the start of every run; copied here, the checks and the predecode
        marks are done once for all."""
        jt = self._tables()
        assert not jt.cnt.any(), "copying the tables of a core that has run would copy its counts"
        st, m32, dec = self.state.st, self.state.m32, self.state.dec
        idx = np.asarray(tiles, dtype=np.int64)
        words = self._code_size // 4
        same = (st[idx][:, _KEY_FIELDS] == st[self.tile, _KEY_FIELDS]).all(axis=1)
        same &= (m32[idx, :words] == m32[self.tile, :words]).all(axis=1)
        idx = idx[same]
        if not len(idx):
            return {}
        rows = dec[idx, 0 : 2 * words : 2]  # a copy: the predecode marks of every tile at once
        rows[rows == OP_ENTRY] = 0  # as _clear_marks()
        rows[:, np.flatnonzero(jt.entry_fn[:words])] = OP_ENTRY  # as _mark()
        dec[idx, 0 : 2 * words : 2] = rows
        made = {}
        for t in idx.tolist():
            translator = TranslatingCore(self.state, t, self.mode, self._compiler, self.stats)
            translator._adopt(self)
            made[t] = translator
        return made

    def _adopt(self, other: TranslatingCore) -> None:
        """Take a copy of ``other``'s tables and what goes with them (:meth:`clones`)."""
        jt = other._jt
        assert jt is not None
        slots = (other._slot_hist, other._slot_len, other._slot_next, other._nslots)
        self._take(jt, *slots, other._known_seen, other._known_starts_in)
        self._code_size = other._code_size
        self._flushes_seen = 0
        self._key_raw, self._key_made = other._key_raw, other._key_made
        self._manifest = other._manifest
        self._known_starts = set(other._known_starts)
        self._cached_starts = other._cached_starts

    def _take(
        self,
        jt: JitArrays,
        slot_hist: Sequence[np.ndarray],
        slot_len: Sequence[np.ndarray],
        slot_next: Sequence[np.ndarray],
        nslots: int,
        seen: int,
        starts_in: Iterable[int],
    ) -> None:
        """Tables made by another core (or kept for the build) and their bookkeeping, as this core's."""
        self._jt = _own_copy(jt)
        self._slot_hist, self._slot_len, self._slot_next = list(slot_hist), list(slot_len), list(slot_next)
        self._nslots = nslots
        self._known_seen = seen
        self._known_starts_in = set(starts_in)
        self.stats.reused += len(self._known_starts_in)

    def _remember_install(self) -> None:
        """Keep the fresh tables just made, for the next core of the same build (:meth:`_install_as_before`)."""
        key = self._key()
        done_list = _TRANSLATED.get(key)
        jt = self._jt
        if done_list is None or jt is None:
            return
        code = self.state.m32[self.tile, : self._code_size // 4].copy()
        _FRESH_TABLES[key] = _FreshTables(
            done_list=done_list,
            seen=self._known_seen,
            code=code,
            code_bytes=code.tobytes(),
            tables=_own_copy(jt),
            mark_rows=2 * np.flatnonzero(jt.entry_fn),
            slot_hist=tuple(self._slot_hist),
            slot_len=tuple(self._slot_len),
            slot_next=tuple(self._slot_next),
            nslots=self._nslots,
            starts_in=frozenset(self._known_starts_in),
        )

    def _install_new_known(self) -> None:
        """Enter the regions translated in this process (by any core) since this core last looked,
        one per start, whose words this core holds too: cores running the same code translate each
        region once between them."""
        done_list = _TRANSLATED.get(self._key(), [])
        if self._known_seen > len(done_list):  # the list was reset
            self._known_seen = 0
        m32 = self.state.m32[self.tile]
        known = []
        for done in done_list[self._known_seen :]:
            start = done.region.start
            if start not in self._known_starts_in and np.array_equal(m32[done.pcs], done.words):
                known.append(done)
                self._known_starts_in.add(start)
        self._known_seen = len(done_list)
        if known:
            self._install_many(known)
            self.stats.reused += len(known)

    def _key(self) -> tuple[Target, bool]:
        """The build this core's code is translated for: its target and whether it multiplies
        (made again only when the state fields it comes from changed: a chip's tiles ask often)."""
        raw = self.state.st[self.tile, _KEY_FIELDS].tobytes()
        if raw != self._key_raw:
            base, mem_size, code_size, errata, mul = self.state.st[self.tile, _KEY_FIELDS].tolist()
            target = Target(base=base, mem_size=mem_size, code_size=code_size, rtl_errata=errata == ERRATA_RTL)
            self._key_raw, self._key_made = raw, (target, mul != 0)
        return self._key_made

    def translate(self, pc: int) -> Region:
        """Translate the region starting at ``pc`` and enter its blocks in the tables.

        With ``auto``, a region that would have to be compiled while compiling is not yet worth it
        is left to the interpreter: its word is parked until the budget could pay for it.
        """
        start = time.perf_counter()
        try:
            return self._translate(pc)
        finally:
            self.stats.translate_seconds += time.perf_counter() - start

    def _budget(self) -> float:
        """auto: seconds of compiling still allowed (AUTO_COMPILE_SHARE of the run so far, less what was spent)."""
        return AUTO_COMPILE_SHARE * self.stats.run_seconds - self.stats.translate_seconds

    def _estimate(self, instructions: int) -> float:
        """Seconds to compile a region of ``instructions`` (from what compiling took so far in this process)."""
        cs = self.compiler.stats
        per_insn = ESTIMATED_SECONDS_PER_INSTRUCTION
        if cs.compiled_instructions:  # the measured figure includes the per-module costs: an upper estimate
            per_insn = cs.compiled_seconds / cs.compiled_instructions
        return ESTIMATED_SECONDS_PER_MODULE + per_insn * instructions

    def _defer(self, pc: int) -> None:
        """Park the word: the dispatch loop stops counting its arrivals until the budget could pay
        for its region (:meth:`_unpark`), so that a short budget costs one stop per word, not one
        per few arrivals (with regions in the object cache the loop keeps asking)."""
        i = (pc - self._target().base) >> 2
        self._tables().hot[i] = NEVER_TRANSLATE
        self._parked[i] = pc
        self.stats.deferred += 1

    def _unpark(self) -> None:
        """auto: parked words whose region the budget could pay for twice over count arrivals again
        (the margin keeps a budget at the edge from being spent on stops that defer again); with
        background compiling, as many as the queue has room for (the others would only stop the
        loop to be parked again: 430 stops in a 0.1 s run of the matrix benchmark)."""
        if not self._parked:
            return
        jt = self._tables()
        budget = self._budget()
        room = BACKGROUND_QUEUE - len(self._compiling)
        for i, pc in list(self._parked.items()):
            if self.background:
                ok = room > 0 and budget > 0 and self._may_hand_over(pc)
                room -= ok
            else:
                ok = 2 * self._estimate(self._sizes.get(pc, AUTO_MAX_REGION_INSTRUCTIONS)) <= budget
            if ok:
                if jt.entry_fn[i] == 0 and jt.hot[i] == NEVER_TRANSLATE:
                    jt.hot[i] = 0
                del self._parked[i]

    def _may_hand_over(self, pc: int) -> bool:
        """Background compiling: whether the region at ``pc`` may be translated now (this core's
        queue has room, and no core's module of it is still compiling: once done, its object is
        in the process or the disk cache and loading it costs no compiling)."""
        pending = _COMPILING.get((self._key(), pc))
        return len(self._compiling) < BACKGROUND_QUEUE and (pending is None or pending.done.is_set())

    def _translate(self, pc: int) -> Region:
        from robosoc.jit.emit_ir import NAME_PLACEHOLDER, EmittedRegion, emit_region
        from robosoc.jit.regions import MAX_REGION_INSTRUCTIONS, Region, discover

        jt = self._tables()
        rent = self.mode == "auto" and pc not in self._known_starts  # compiled only when worth it
        if rent and self.background:
            # compiling costs this thread nothing: the budget pays for finding and writing regions,
            # and the queue is kept short (a region asked for meanwhile waits its turn); a region
            # another core handed over already is entered from there once compiled
            if self._budget() <= 0 or not self._may_hand_over(pc):
                self._defer(pc)
                return Region(pc, {})
            rent = False
        if rent and self._estimate(self._sizes.get(pc, 0)) > self._budget():
            self._defer(pc)  # (not even a region of the size found here before) could be compiled yet
            return Region(pc, {})
        if jt.ctx[CTX_FLUSHES] != self._flushes_seen:  # self-modifying code: the loop forgot everything
            self.stats.flushes += int(jt.ctx[CTX_FLUSHES]) - self._flushes_seen
            self._flushes_seen = int(jt.ctx[CTX_FLUSHES])
            self._install_known()
            self._sizes.clear()
            self._parked.clear()
            if jt.entry_fn[(pc - self._target().base) >> 2] != 0:
                return Region(pc, {})
        self._install_new_known()  # another core may have translated it meanwhile
        if jt.entry_fn[(pc - self._target().base) >> 2] != 0:
            return Region(pc, {})
        target = self._target()
        base = target.base
        view = self._view()
        m32 = self.state.m32[self.tile]
        cap = AUTO_MAX_REGION_INSTRUCTIONS if self.mode == "auto" else MAX_REGION_INSTRUCTIONS
        region = discover(view, pc, cap, translated=lambda a: jt.entry_fn[(a - base) >> 2] != 0)
        if rent:
            self._sizes[pc] = region.instructions
            if self._estimate(region.instructions) > self._budget():
                self._defer(pc)
                return Region(pc, {})
        if region.blocks:
            emitted = emit_region(target, region)
            pcs = np.array(sorted((p - base) >> 2 for p in region.words()), dtype=np.int64)
            if self.background and not self.compiler.ready(emitted.ir):
                # compiled in the background thread; installed by finish_compiles() (the word waits)
                words = m32[pcs].copy()
                job = self.compiler.compile_later(
                    emitted.ir,
                    NAME_PLACEHOLDER,
                    [emitted.function],
                    region.instructions,
                    wanted=_wanted(self._key(), pcs, words),
                )
                self._compiling.append((job, region, emitted, pcs, words))
                _COMPILING[(self._key(), pc)] = job
                jt.hot[(pc - base) >> 2] = NEVER_TRANSLATE
                self.stats.background += 1
                return Region(pc, {})
            address = self.compiler.add(emitted.ir, NAME_PLACEHOLDER, [emitted.function], region.instructions)[0]
        else:
            emitted, address = EmittedRegion(ir="", function="", blocks={}), 0
            pcs = np.array([(pc - base) >> 2], dtype=np.int64)
        return self._enter(region, emitted, address, pcs, m32[pcs].copy())

    def _enter(
        self, region: Region, emitted: EmittedRegion, address: int, pcs: np.ndarray, words: np.ndarray
    ) -> Region:
        """Note a translated region (for every core of this build) and enter it in this core's tables."""
        global _ENTERED
        _ENTERED += 1
        target, has_mul = self._key()
        pc = region.start
        if region.blocks and pc not in self._known_starts and self.compiler.cache_dir is not None:
            self._known_starts.add(pc)
            add_to_manifest(self._manifest_key(), pc)
        done = _Translated.of(region, emitted, address, pcs, words, target.base)
        done_list = _TRANSLATED.setdefault((target, has_mul), [])
        done_list.append(done)
        self._install(done)
        if self._known_seen == len(done_list) - 1:
            self._known_seen = len(done_list)
        self._known_starts_in.add(done.region.start)
        self.stats.regions += 1
        self.stats.instructions += region.instructions
        return region

    def compiling(self) -> int:
        """Regions waiting for the background thread."""
        return len(self._compiling)

    def install_known(self) -> None:
        """Enter the regions other cores of the same build translated since this core last looked
        (with background compiling they are entered at step boundaries, not when asked for)."""
        if self._jt is not None:
            self._install_new_known()

    def finish_compiles(self, wait: bool = False) -> None:
        """Enter the regions the background thread has compiled (all of them, waiting, with
        ``wait``).  A region whose words changed meanwhile is dropped (its word is asked for again)."""
        while self._compiling:
            job, region, emitted, pcs, words = self._compiling[0]
            if not job.done.is_set() and not wait:
                break
            job.done.wait()
            self._compiling.pop(0)
            if _COMPILING.get((self._key(), region.start)) is job:
                del _COMPILING[(self._key(), region.start)]
            start = time.perf_counter()
            address = self.compiler.finish(job)[0]
            jt = self._tables()
            i = (region.start - self._target().base) >> 2
            if np.array_equal(self.state.m32[self.tile][pcs], words) and jt.entry_fn[i] == 0:
                self._enter(region, emitted, address, pcs, words)
            elif jt.entry_fn[i] == 0:
                jt.hot[i] = 0
            self.stats.translate_seconds += time.perf_counter() - start

    def _install(self, done: _Translated) -> None:
        self._install_many([done])

    def _install_many(self, dones: list[_Translated]) -> None:
        """Enter translated regions in the tables (their count slots and words added in one go)."""
        jt = self._jt
        assert jt is not None
        base = self._target().base
        n = int(jt.ctx[CTX_WORDS])
        pcs, words = [jt.tpcs[:n]], [jt.twords[:n]]
        slots_added = False
        for done in dones:
            region = done.region
            if not region.blocks:
                jt.hot[(region.start - base) >> 2] = NEVER_TRANSLATE
                continue
            slot_base = self._nslots
            self._queue_slots(done, slot_base)
            slots_added = True
            at = (done.block_starts - base) >> 2
            free = jt.entry_fn[at] == 0  # a block already entered by an earlier region keeps its entry
            jt.entry_fn[at[free]] = done.address
            self._mark(at[free])
            jt.entry_slot[at[free]] = slot_base
            jt.entry_blk[at[free]] = done.block_indices[free]
            jt.tmap[done.pcs] = done.rest
            pcs.append(done.pcs)
            words.append(done.words)
            sides = (done.side_exits - base) >> 2
            jt.hot[sides[jt.entry_fn[sides] == 0]] = NEVER_TRANSLATE
            if jt.entry_fn[(region.start - base) >> 2] == 0:
                jt.hot[(region.start - base) >> 2] = NEVER_TRANSLATE
        if slots_added:
            self._commit_slots()
        jt = self._jt
        self._jt = jt = jt._replace(tpcs=np.concatenate(pcs), twords=np.concatenate(words))
        jt.ctx[CTX_WORDS] = len(jt.tpcs)

    def _queue_slots(self, done: _Translated, slot_base: int) -> None:
        self._slot_hist.append(done.slot_rows)
        self._slot_len.append(done.slot_lens)
        self._slot_next.append(np.where(done.slot_next >= 0, done.slot_next + slot_base, -1))
        self._nslots += len(done.slot_lens)

    def _commit_slots(self) -> None:
        """The count-slot arrays of every queued slot (counts zero: they are flushed between calls)."""
        rows = np.concatenate(self._slot_hist)
        ptr = np.zeros(self._nslots + 1, dtype=np.int64)
        np.cumsum(np.concatenate(self._slot_len), out=ptr[1:])
        jt = self._jt
        assert jt is not None
        self._jt = jt._replace(
            cnt=np.zeros(self._nslots, dtype=np.int64),
            slot_ptr=ptr,
            slot_next=np.concatenate(self._slot_next),
            slot_kc=rows[:, 0].copy(),
            slot_delta=rows[:, 1].copy(),
        )

    # --- running ------------------------------------------------------------------------------
    def has_cached_regions(self) -> bool:
        """auto: whether an earlier run compiled regions of this code (installed at once when hot)."""
        self._tables()
        return bool(self._cached_starts)

    def ask_threshold(self, cached: bool | None = None) -> int:
        """Arrivals at a word before the dispatch loop asks for a translation there.

        ``auto`` does not ask while even a small region could not be compiled within its budget
        (the loop still samples), unless regions compiled by an earlier run (``cached``; default:
        this core's) can be installed.
        """
        if self.mode != "auto":
            return self.threshold
        self._unpark()
        if cached is None:
            cached = self.has_cached_regions()
        cost = 0.0 if self.background else self._estimate(AUTO_MAX_REGION_INSTRUCTIONS)
        warm = max(self.stats.run_seconds, _BUILD_SECONDS.get(self._key(), 0.0)) >= AUTO_WARMUP_SECONDS
        if not cached and (self._budget() <= cost or not warm):
            return NEVER_ASK
        return self.threshold

    def _dispatch_loop_ready(self) -> bool:
        """auto: whether the dispatch loop may run (numba has it compiled or cached, or the core has
        run long enough on the interpreter for its compilation to be worth it, as for a region)."""
        global _dispatch_loop_ready
        if not _dispatch_loop_ready:
            _dispatch_loop_ready = compiled_or_cached(run_translated) or (
                AUTO_COMPILE_SHARE * self.stats.run_seconds >= ESTIMATED_DISPATCH_LOOP_SECONDS
            )
        return _dispatch_loop_ready

    def step_until(self, until: int) -> int:
        """Run the tile to cycle ``until`` (or an event); its RUN_* status, as ``run_cores`` leaves it."""
        arrays = self.state.arrays()
        st = self.state.st[self.tile]
        if self.mode == "auto" and not self._dispatch_loop_ready():
            start = time.perf_counter()
            run_cores(arrays, self._tiles, until)  # a fresh install: the interpreter numba compiles first
            self.stats.run_seconds += time.perf_counter() - start
            return int(st[S_RUN])
        loading = until <= int(st[S_CYCLE])  # a call that only loads the kernel is no run time
        while True:
            if self._compiling:
                self.finish_compiles()  # what the background thread compiled meanwhile
            start = time.perf_counter()
            jt = self._tables()
            threshold = self.ask_threshold()
            stop = until
            if self._compiling:  # come back soon to enter them; ask nothing the queue has no room for
                stop = min(until, int(st[S_CYCLE]) + POLL_CYCLES)
                if len(self._compiling) >= BACKGROUND_QUEUE and not self._cached_starts:
                    threshold = NEVER_ASK
            run_translated(arrays, self._tiles, stop, jt, threshold, self.stretch)
            status = int(st[S_RUN])
            if status == RUN_CHUNK:  # the loop leaves the block counts in jt only then
                flush_counts(jt, arrays.opc[self.tile], arrays.ctr[self.tile])
            if not loading:
                seconds = time.perf_counter() - start
                self.stats.run_seconds += seconds
                key = self._key()
                _BUILD_SECONDS[key] = _BUILD_SECONDS.get(key, 0.0) + seconds
            if status == RUN_CHUNK and stop < until:
                continue
            if status != RUN_TRANSLATE:
                return status
            self.translate(int(st[S_PC]))
