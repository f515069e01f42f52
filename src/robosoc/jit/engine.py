"""The translator of one core: translating the regions the dispatch loop asks for, and running it.

``TranslatingCore(state).step_until(until)`` runs like ``run_cores(state.arrays(), [tile], until)``
and leaves the same RUN_* status; in between it translates the regions that turn hot.  When it does
is its policy's (:mod:`robosoc.jit.policy`: ``jit`` at a word's first arrival; ``auto`` after
:data:`~robosoc.jit.policy.AUTO_THRESHOLD` arrivals, and only while compiling stays a small share of
the run); its tables, and copying them between cores, are :class:`~robosoc.jit.tables.CoreTables`';
the regions earlier runs compiled for its code are listed in its :class:`~robosoc.jit.manifest.Manifest`.
Counts, cycles, outputs and errors are those of the interpreter (docs/translation.md).
"""

from __future__ import annotations

import dataclasses
import time
import weakref
from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np

from robosoc.jit import policy as policies
from robosoc.jit.compiler import Compiler, Pending, shared_compiler
from robosoc.jit.manifest import Manifest, manifest_key
from robosoc.jit.tables import (
    Adoption,
    Build,
    Cores,
    CoreTables,
    Translated,
    TranslationStats,
    build_of,
    note_translated,
)
from robosoc.kernels.core import run_cores
from robosoc.kernels.core_layout import RUN_CHUNK, S_CODE_SIZE, S_CYCLE, S_MEM_BASE, S_MEM_SIZE, S_MUL, S_PC, S_RUN
from robosoc.kernels.jit_dispatch import (
    CTX_FLUSHES,
    NEVER_TRANSLATE,
    RUN_TRANSLATE,
    JitArrays,
    run_translated,
)

if TYPE_CHECKING:
    from robosoc.jit.emit_ir import EmittedRegion
    from robosoc.jit.regions import CodeView, Region

__all__ = ["TranslatingCore", "TranslationStats"]

# Finding and writing regions (robosoc.jit.regions, robosoc.jit.emit_ir) is imported at the first
# translation: a short run of auto translates nothing, and importing them cost it 16-20 ms when
# Python had to compile their source.

M32 = 0xFFFFFFFF

#: manifest key -> the process's list of regions its records were added to, and how many records
#: the manifest held then (a manifest that grew since, a whole-code translation's, is entered again)
_RECORDS_IN: dict[str, tuple[list[Translated], int]] = {}

#: the translators of this process (those of ``auto``: whether a region still compiling is wanted)
_LIVE: weakref.WeakSet[TranslatingCore] = weakref.WeakSet()


def _wanted(key: Build, pcs: np.ndarray, words: np.ndarray) -> Callable[[], bool]:
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


def code_manifest_key(state: Cores, tile: int, mode: str) -> str:
    """The manifest key of the code tile ``tile`` of ``state`` holds (its code bytes, build and the
    policy ``mode`` with its region cap: :func:`robosoc.jit.manifest.manifest_key`)."""
    code = state.m8[tile, : int(state.st[tile, S_CODE_SIZE])].tobytes()
    cap = policies.POLICIES[mode].region_cap()
    return manifest_key(code, f"{build_of(state.st[tile])!r} {mode} cap{cap}")


class TranslatingCore(CoreTables):
    """Runs one tile of a :class:`~robosoc.jit.tables.Cores` with translated regions (policy
    ``jit`` or ``auto``)."""

    def __init__(
        self,
        state: Cores,
        tile: int = 0,
        mode: str = "jit",
        compiler: Compiler | None = None,
        stats: TranslationStats | None = None,
    ) -> None:
        """``mode``: the policy's name (:data:`robosoc.jit.policy.POLICIES`); ``stats``: shared by
        the translators of one chip (auto's compile budget is the chip's)."""
        super().__init__(state, tile, stats if stats is not None else TranslationStats())
        self.mode = mode
        self.policy = policies.POLICIES[mode](self)
        self._compiler = compiler
        self._tiles = np.array([tile], dtype=np.int64)
        self.manifest = Manifest()  # made again for each code loaded
        self._next_manifest = self.manifest  # read before the tables are made for new code
        self._records_missing: set[int] = set()  # recorded regions whose object was not in the cache
        self._compiling: list[tuple[Pending, Region, EmittedRegion, np.ndarray, np.ndarray]] = []
        if self.background:
            _LIVE.add(self)

    @property
    def threshold(self) -> int:
        return self.policy.threshold

    @property
    def stretch(self) -> int:
        return self.policy.stretch

    @property
    def background(self) -> bool:
        """Whether regions are compiled in the background thread (auto): the core interprets them meanwhile."""
        return self.policy.background

    @property
    def compiler(self) -> Compiler:
        """The compiler (created at the first translation: LLVM's set-up is not paid by cold code)."""
        if self._compiler is None:
            self._compiler = shared_compiler()
        return self._compiler

    # --- what goes with the tables --------------------------------------------------------------
    def _before_install(self) -> None:
        """Read the code's manifest and add the regions earlier runs recorded for it to the
        process's (once per program and process): the tables are made with them entered."""
        key = self._manifest_key()
        manifest = self._next_manifest = Manifest(key)
        if manifest.records:
            self._enter_records(key, manifest)
        # what is left of the records for the policy to install at once: those whose object was gone
        manifest.cached = frozenset(manifest.cached & self._records_missing)

    def _enter_records(self, key: str, manifest: Manifest) -> None:
        """The recorded regions of ``manifest`` whose objects are in the cache, as regions of this
        process (neither found nor written: :mod:`robosoc.jit.manifest`)."""
        from robosoc.jit.emit_ir import NAME_PLACEHOLDER
        from robosoc.jit.tables import _TRANSLATED

        build = self._key()
        done_list = _TRANSLATED.get(build)
        self._records_missing = set()
        # entered already (a test may replace the process's list: entered again then)
        entered, count = _RECORDS_IN.get(key, (None, -1))
        if done_list is not None and entered is done_list and count == len(manifest.records):
            return
        m32 = self.state.m32[self.tile]
        have = {d.start for d in done_list or [] if np.array_equal(m32[d.pcs], d.words)}
        for record in manifest.records.values():
            if record.start in have:
                continue
            addresses = self.compiler.add_cached(record.object_key, NAME_PLACEHOLDER, [record.function])
            if addresses is None:  # its object is gone: translated afresh when it turns hot
                self._records_missing.add(record.start)
                continue
            pcs = record.arrays["pcs"]
            note_translated(build, Translated.of_record(record, addresses[0], m32[pcs].copy()))
            self.stats.recorded += 1
        _RECORDS_IN[key] = (_TRANSLATED.get(build, []), len(manifest.records))

    def enter_recorded(self) -> int:
        """Enter the regions recorded for this core's code since its tables were made (another
        process translated its whole code meanwhile: :meth:`translate_code`); how many."""
        if self._jt is None:
            return 0  # its tables, once made, hold them
        key = self.manifest.key or self._manifest_key()
        manifest = Manifest(key)
        before = self.stats.recorded
        self._enter_records(key, manifest)
        self.manifest.key = key
        self.manifest.known |= set(manifest.records)
        self._install_new_known()
        self.policy.records_grew()
        return self.stats.recorded - before

    def _new_code(self) -> None:
        self.policy.new_code()
        self.manifest = self._next_manifest

    def _sibling(self, tile: int) -> TranslatingCore:
        return TranslatingCore(self.state, tile, self.mode, self._compiler, self.stats)

    def _adoption(self) -> Adoption:
        return dataclasses.replace(super()._adoption(), extra=self.manifest.copy())

    def _adopt(self, adoption: Adoption, copy: JitArrays) -> None:
        super()._adopt(adoption, copy)
        assert isinstance(adoption.extra, Manifest)
        self.manifest = adoption.extra.copy()

    def _manifest_key(self) -> str:
        """The key of the list of regions compiled for this core's code before (made once per load
        of the code: hashing it cost each region 0.1 ms)."""
        return code_manifest_key(self.state, self.tile, self.mode)

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

    def _translate(self, pc: int) -> Region:
        from robosoc.jit.emit_ir import NAME_PLACEHOLDER, EmittedRegion
        from robosoc.jit.regions import Region

        jt = self._tables()
        verdict = self.policy.before(pc)
        if verdict == policies.DEFER:
            self.policy.defer(pc)
            return Region(pc, {})
        if jt.ctx[CTX_FLUSHES] != self._flushes_seen:  # self-modifying code: the loop forgot everything
            self.stats.flushes += int(jt.ctx[CTX_FLUSHES]) - self._flushes_seen
            self._flushes_seen = int(jt.ctx[CTX_FLUSHES])
            self._install_known()
            self.policy.flushed()
            if jt.entry_fn[(pc - self._target().base) >> 2] != 0:
                return Region(pc, {})
        self._install_new_known()  # another core may have translated it meanwhile
        if jt.entry_fn[(pc - self._target().base) >> 2] != 0:
            return Region(pc, {})
        base = self._target().base
        m32 = self.state.m32[self.tile]
        region = self._found(pc, self.policy.region_cap())
        if verdict == policies.RENT and not self.policy.pays_for(pc, region.instructions):
            self.policy.defer(pc)
            return Region(pc, {})
        if region.blocks:
            emitted, pcs = self._written(region)
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
                policies._COMPILING[(self._key(), pc)] = job
                jt.hot[(pc - base) >> 2] = NEVER_TRANSLATE
                self.stats.background += 1
                return Region(pc, {})
            address = self.compiler.add(emitted.ir, NAME_PLACEHOLDER, [emitted.function], region.instructions)[0]
        else:
            emitted, address = EmittedRegion(ir="", function="", blocks={}), 0
            pcs = np.array([(pc - base) >> 2], dtype=np.int64)
        return self._enter(region, emitted, address, pcs, m32[pcs].copy())

    def _found(self, pc: int, cap: int) -> Region:
        """The region from ``pc`` of at most ``cap`` instructions, leaving the blocks entered already
        to their regions."""
        from robosoc.jit.regions import discover

        entry_fn, base = self._tables().entry_fn, self._target().base
        return discover(self._view(), pc, cap, translated=lambda a: entry_fn[(a - base) >> 2] != 0)

    def _written(self, region: Region) -> tuple[EmittedRegion, np.ndarray]:
        """A found region's IR, and the word indices of its instructions."""
        from robosoc.jit.emit_ir import emit_region

        target = self._target()
        pcs = np.array(sorted((p - target.base) >> 2 for p in region.words()), dtype=np.int64)
        return emit_region(target, region), pcs

    def translate_code(
        self, stop: Callable[[], bool] = lambda: False, words: np.ndarray | None = None
    ) -> tuple[int, int]:
        """Translate the loaded code ahead of its run: from the code's first word, a region of
        ``jit``'s size (:data:`robosoc.jit.regions.MAX_REGION_INSTRUCTIONS`) at each word no region
        holds yet (of ``words``, word indices in the code, if given: those a run executed),
        compiled in line and noted in the code's manifest (regions recorded before are entered,
        not made again).  ``stop`` is asked before each region (True: stop there; what was done
        stays recorded).  Returns (regions made, their guest instructions).

        This is what a second process does for ``auto`` (:mod:`robosoc.chip.whole_code`): a later
        run enters every region from the records at once, as ``jit`` would have made them."""
        from robosoc.jit.emit_ir import NAME_PLACEHOLDER
        from robosoc.jit.regions import MAX_REGION_INSTRUCTIONS

        jt = self._tables()  # (with the records of earlier runs entered)
        base = self._target().base
        m32 = self.state.m32[self.tile]
        held = jt.tmap != 0  # words some region translated
        made = instructions = 0
        for w in range(len(jt.entry_fn) - 1) if words is None else words.tolist():
            if held[w] or jt.entry_fn[w] != 0:
                continue
            if stop():
                break
            region = self._found(base + 4 * w, MAX_REGION_INSTRUCTIONS)
            if not region.blocks:
                continue  # not an instruction the translator takes (the interpreter's, if ever reached)
            emitted, pcs = self._written(region)
            address = self.compiler.add(emitted.ir, NAME_PLACEHOLDER, [emitted.function], region.instructions)[0]
            self._enter(region, emitted, address, pcs, m32[pcs].copy())
            held[pcs] = True
            made += 1
            instructions += region.instructions
        return made, instructions

    def _enter(
        self, region: Region, emitted: EmittedRegion, address: int, pcs: np.ndarray, words: np.ndarray
    ) -> Region:
        """Note a translated region (for every core of this build) and enter it in this core's tables."""
        build = self._key()
        done = Translated.of(region, emitted, address, pcs, words, build[0].base)
        if region.blocks and self.compiler.cache_dir is not None:
            record = lambda: done.record(self.compiler.key(emitted.ir), emitted.function)  # noqa: E731
            self.manifest.note(region.start, self._manifest_key, record)
        self._add(done, note_translated(build, done))
        self.stats.regions += 1
        self.stats.instructions += region.instructions
        return region

    def compiling(self) -> int:
        """Regions waiting for the background thread."""
        return len(self._compiling)

    def finish_compiles(self, wait: bool = False) -> None:
        """Enter the regions the background thread has compiled (all of them, waiting, with
        ``wait``).  A region whose words changed meanwhile is dropped (its word is asked for again)."""
        while self._compiling:
            job, region, emitted, pcs, words = self._compiling[0]
            if not job.done.is_set() and not wait:
                break
            job.done.wait()
            self._compiling.pop(0)
            if policies._COMPILING.get((self._key(), region.start)) is job:
                del policies._COMPILING[(self._key(), region.start)]
            start = time.perf_counter()
            address = self.compiler.finish(job)[0]
            jt = self._tables()
            i = (region.start - self._target().base) >> 2
            if np.array_equal(self.state.m32[self.tile][pcs], words) and jt.entry_fn[i] == 0:
                self._enter(region, emitted, address, pcs, words)
            elif jt.entry_fn[i] == 0:
                jt.hot[i] = 0
            self.stats.translate_seconds += time.perf_counter() - start

    # --- running ------------------------------------------------------------------------------
    def has_cached_regions(self) -> bool:
        """Whether an earlier run compiled regions of this code that are not entered yet (their
        records are entered with the tables; ``auto`` installs these at once when hot)."""
        self._tables()
        return bool(self.manifest.cached)

    def ask_threshold(self, cached: bool | None = None) -> int:
        """Arrivals at a word before the dispatch loop asks for a translation there (the policy's:
        ``auto`` does not ask while even a small region could not be compiled within its budget,
        unless regions compiled by an earlier run, ``cached``, default: this core's, can be installed)."""
        return self.policy.ask_threshold(cached)

    def step_until(self, until: int) -> int:
        """Run the tile to cycle ``until`` (or an event); its RUN_* status, as ``run_cores`` leaves it."""
        arrays = self.state.arrays()
        st = self.state.st[self.tile]
        if not self.policy.dispatch_loop_ready():
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
                stop, threshold = self.policy.while_compiling(until, int(st[S_CYCLE]), threshold)
            run_translated(arrays, self._tiles, stop, jt, threshold, self.stretch)
            status = int(st[S_RUN])
            if not loading:
                seconds = time.perf_counter() - start
                self.stats.run_seconds += seconds
                policies.count_run(self._key(), seconds)
            if status == RUN_CHUNK and stop < until:
                continue
            if status != RUN_TRANSLATE:
                return status
            self.translate(int(st[S_PC]))
