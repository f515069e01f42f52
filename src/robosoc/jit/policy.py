"""When a translating core translates: the policies of ``jit`` and ``auto``.

``jit`` (:class:`JitPolicy`) translates a region at a word's first arrival, up to whole functions,
compiled in line.  ``auto`` (:class:`AutoPolicy`) interprets first and translates what turns hot:
after a warm-up (:data:`AUTO_WARMUP_SECONDS`), at words sampled :data:`AUTO_THRESHOLD` times, in
small regions, compiled in a background thread, and only while compiling stays a small share of
the run (:data:`AUTO_COMPILE_SHARE`, ski rental); a region it may not pay for yet is parked.  A
policy belongs to one :class:`~robosoc.jit.engine.TranslatingCore` and reads its statistics, its
tables and its manifest (docs/translation.md, "Tiers and cache").
"""

from __future__ import annotations

import math
import weakref
from typing import TYPE_CHECKING

from robosoc.kernels import compiled_or_cached
from robosoc.kernels.jit_dispatch import NEVER_TRANSLATE, run_translated

if TYPE_CHECKING:
    from robosoc.jit.compiler import Pending
    from robosoc.jit.engine import TranslatingCore
    from robosoc.jit.tables import Build

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
#: numba's compile time of the dispatch loop (``run_translated``) once the interpreter it calls is
#: compiled: 2.4 s of CPU on the 2-core machine (2026-11-28; 19 s while numba copied the interpreter
#: into it): ``auto`` on one core of a fresh install interprets (``run_cores``, which ``interp``
#: compiles too) until it has run 1/AUTO_COMPILE_SHARE times that long.  Any chip run, or a ``jit``
#: run, compiles it (into numba's cache) on the way.
ESTIMATED_DISPATCH_LOOP_SECONDS = 3.0
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
STRETCHES = {"jit": 0, "auto": AUTO_STRETCH}
NEVER_ASK = 1 << 40  # a threshold no word reaches

#: build -> seconds its cores ran in the dispatch loop in this process (a warm-up passed by earlier
#: runs of a program, a benchmark's, counts for the next)
_BUILD_SECONDS: dict[Build, float] = {}
#: (build, region start) -> the module the background thread compiles for some core; another core
#: asking for the region waits for it, then enters it itself (the thread loaded it into the engine),
#: so a core that is gone before its region was done (a run that ended) keeps nobody waiting
_COMPILING: dict[tuple[Build, int], Pending] = {}

#: What a policy says of a region asked for (:meth:`JitPolicy.before`): translate it, translate it
#: if its size turns out affordable (:meth:`JitPolicy.pays_for`), or park its word for now.
TRANSLATE, RENT, DEFER = 0, 1, 2


def count_run(build: Build, seconds: float) -> None:
    """The cores of ``build`` ran ``seconds`` in the dispatch loop (towards ``auto``'s warm-up)."""
    _BUILD_SECONDS[build] = _BUILD_SECONDS.get(build, 0.0) + seconds


class JitPolicy:
    """``jit``: every word is translated at its first arrival (regions up to
    :data:`robosoc.jit.regions.MAX_REGION_INSTRUCTIONS`), compiled in line; no manifest read."""

    name = "jit"
    #: whether the core reads its code's manifest (regions compiled by earlier runs, installed at once)
    reads_manifest = False

    def __init__(self, core: TranslatingCore) -> None:
        # a proxy: no reference cycle, so a core dies with its last reference (the compiling thread
        # drops the jobs of cores that are gone: TranslatingCore's ``wanted``)
        self.core = weakref.proxy(core)
        self.threshold = THRESHOLDS[self.name]
        self.stretch = STRETCHES[self.name]
        #: compile regions in the background thread: the core interprets them meanwhile
        self.background = False

    @classmethod
    def region_cap(cls) -> int:
        """The most instructions of a region."""
        from robosoc.jit import regions

        return regions.MAX_REGION_INSTRUCTIONS

    def ask_threshold(self, cached: bool | None = None) -> int:
        """Arrivals at a word before the dispatch loop asks for a translation there."""
        return self.threshold

    def dispatch_loop_ready(self) -> bool:
        """Whether the core may run in the dispatch loop (else: on the interpreter)."""
        return True

    def before(self, pc: int) -> int:
        """Asked for the region at ``pc``: TRANSLATE, RENT or DEFER."""
        return TRANSLATE

    def pays_for(self, pc: int, instructions: int) -> bool:
        """A RENT region found at ``pc`` has ``instructions``: whether it is translated now."""
        return True

    def defer(self, pc: int) -> None:
        """Leave the word at ``pc`` to the interpreter for now."""
        raise AssertionError(f"{self.name} defers no region")

    def new_code(self) -> None:
        """The core's tables were made for new code."""

    def records_grew(self) -> None:
        """Regions of the code's manifest were entered mid-run (:meth:`TranslatingCore.enter_recorded`)."""

    def flushed(self) -> None:
        """Self-modifying code made the core forget its translations."""

    def while_compiling(self, until: int, cycle: int, threshold: int) -> tuple[int, int]:
        """The dispatch loop's end and threshold while regions compile in the background: it comes
        back every POLL_CYCLES to enter those done, and asks for nothing the queue has no room for."""
        stop = min(until, cycle + POLL_CYCLES)
        if len(self.core._compiling) >= BACKGROUND_QUEUE and not self.core.manifest.cached:
            threshold = NEVER_ASK
        return stop, threshold


class AutoPolicy(JitPolicy):
    """``auto``: interpret, translate what turns hot while it pays (see the module doc)."""

    name = "auto"
    reads_manifest = True

    def __init__(self, core: TranslatingCore) -> None:
        super().__init__(core)
        self.background = AUTO_BACKGROUND
        self._parked: dict[int, int] = {}  # word index -> pc of a deferred region (not sampled for now)
        self._sizes: dict[int, int] = {}  # pc -> instructions of the region found there
        #: whether the core's code was translated whole (robosoc.chip.whole_code; None: not looked yet)
        self._whole: bool | None = None

    @classmethod
    def region_cap(cls) -> int:
        return AUTO_MAX_REGION_INSTRUCTIONS

    def ask_threshold(self, cached: bool | None = None) -> int:
        """Not while even a small region could not be compiled within the budget (the loop still
        samples), unless regions compiled by an earlier run (``cached``; default: this core's) can
        be installed."""
        core = self.core
        if self.whole():
            return THRESHOLDS["jit"]
        self.unpark()
        if cached is None:
            cached = core.has_cached_regions()
        cost = 0.0 if self.background else self.estimate(AUTO_MAX_REGION_INSTRUCTIONS)
        warm = max(core.stats.run_seconds, _BUILD_SECONDS.get(core._key(), 0.0)) >= AUTO_WARMUP_SECONDS
        if not cached and (self.budget() <= cost or not warm):
            return NEVER_ASK
        return self.threshold

    def dispatch_loop_ready(self) -> bool:
        """Whether numba has the dispatch loop compiled or cached, or the core has run long enough
        on the interpreter for its compilation to be worth it, as for a region."""
        global _dispatch_loop_ready
        if not _dispatch_loop_ready:
            _dispatch_loop_ready = compiled_or_cached(run_translated) or (
                AUTO_COMPILE_SHARE * self.core.stats.run_seconds >= ESTIMATED_DISPATCH_LOOP_SECONDS
            )
        return _dispatch_loop_ready

    def before(self, pc: int) -> int:
        """A region in the manifest is translated (its object is cached); with background
        compiling the budget pays for finding and writing regions, and the queue is kept short (a
        region asked for meanwhile waits its turn; one another core handed over already is
        entered from there once compiled); in line, a region is rented if even the size found
        there before could be compiled."""
        rent = pc not in self.core.manifest.known
        if rent and self.background:
            if self.budget() <= 0 or not self.may_hand_over(pc):
                return DEFER
            rent = False
        if rent and self.estimate(self._sizes.get(pc, 0)) > self.budget():
            return DEFER
        return RENT if rent else TRANSLATE

    def pays_for(self, pc: int, instructions: int) -> bool:
        self._sizes[pc] = instructions
        return self.estimate(instructions) <= self.budget()

    def new_code(self) -> None:
        self._parked.clear()
        self._whole = None

    def records_grew(self) -> None:
        """Regions of the code's manifest were entered mid-run: it may be whole now."""
        self._whole = None

    def flushed(self) -> None:
        self._sizes.clear()
        self._parked.clear()

    def whole(self) -> bool:
        """Whether the core's code was translated whole (:mod:`robosoc.chip.whole_code`, looked up
        once per code): its regions are entered, and what is left (a word where an interrupt
        resumed inside a block, a word first executed later) is translated as ``jit`` would, at
        its first arrival and whatever the budget, compiled in the background and recorded: a few
        small regions, once per program.  (Interpreted instead, the sleeping 16x16 chip's resumed
        words cost it 1.8x real time against 3x on ``jit``; left to the budget, the fixed + mul
        flight compiled 3-8 of them anew in each process, its sampled words differing.)"""
        if self._whole is None:
            from robosoc.jit.manifest import whole_code_translated

            key = self.core.manifest.key
            self._whole = key is not None and whole_code_translated(key)
        return self._whole

    def budget(self) -> float:
        """Seconds of compiling still allowed (AUTO_COMPILE_SHARE of the run so far, less what was
        spent; no limit for code translated whole)."""
        if self.whole():
            return math.inf
        stats = self.core.stats
        return AUTO_COMPILE_SHARE * stats.run_seconds - stats.translate_seconds

    def estimate(self, instructions: int) -> float:
        """Seconds to compile a region of ``instructions`` (from what compiling took so far in this process)."""
        cs = self.core.compiler.stats
        per_insn = ESTIMATED_SECONDS_PER_INSTRUCTION
        if cs.compiled_instructions:  # the measured figure includes the per-module costs: an upper estimate
            per_insn = cs.compiled_seconds / cs.compiled_instructions
        return ESTIMATED_SECONDS_PER_MODULE + per_insn * instructions

    def defer(self, pc: int) -> None:
        """Park the word: the dispatch loop stops counting its arrivals until the budget could pay
        for its region (:meth:`unpark`), so that a short budget costs one stop per word, not one
        per few arrivals (with regions in the object cache the loop keeps asking)."""
        core = self.core
        i = (pc - core._target().base) >> 2
        core._tables().hot[i] = NEVER_TRANSLATE
        self._parked[i] = pc
        core.stats.deferred += 1

    def unpark(self) -> None:
        """Parked words whose region the budget could pay for twice over count arrivals again
        (the margin keeps a budget at the edge from being spent on stops that defer again); with
        background compiling, as many as the queue has room for (the others would only stop the
        loop to be parked again: 430 stops in a 0.1 s run of the matrix benchmark)."""
        if not self._parked:
            return
        jt = self.core._tables()
        budget = self.budget()
        room = BACKGROUND_QUEUE - len(self.core._compiling)
        if self.background and (room <= 0 or budget <= 0):
            return  # none may go (the look over every parked word cost a flight 0.25 ms per step)
        for i, pc in list(self._parked.items()):
            if self.background:
                ok = room > 0 and budget > 0 and self.may_hand_over(pc)
                room -= ok
            else:
                ok = 2 * self.estimate(self._sizes.get(pc, AUTO_MAX_REGION_INSTRUCTIONS)) <= budget
            if ok:
                if jt.entry_fn[i] == 0 and jt.hot[i] == NEVER_TRANSLATE:
                    jt.hot[i] = 0
                del self._parked[i]

    def may_hand_over(self, pc: int) -> bool:
        """Background compiling: whether the region at ``pc`` may be translated now (this core's
        queue has room, and no core's module of it is still compiling: once done, its object is
        in the process or the disk cache and loading it costs no compiling)."""
        pending = _COMPILING.get((self.core._key(), pc))
        return len(self.core._compiling) < BACKGROUND_QUEUE and (pending is None or pending.done.is_set())


POLICIES: dict[str, type[JitPolicy]] = {"jit": JitPolicy, "auto": AutoPolicy}
