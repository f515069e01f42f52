"""The translator of one core: its tables, and translating the regions the dispatch loop asks for.

``TranslatingCore(state).step_until(until)`` runs like ``run_cores(state.arrays(), [tile], until)``
and leaves the same RUN_* status; in between it translates the regions that turn hot (``jit``: at
their first arrival; ``auto``: after :data:`AUTO_THRESHOLD` arrivals).  Counts, cycles, outputs
and errors are those of the interpreter (docs/translation.md).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from robosoc.jit.compiler import Compiler, shared_compiler
from robosoc.jit.emit_ir import NAME_PLACEHOLDER, EmittedRegion, Target, emit_region
from robosoc.jit.regions import CodeView, End, Region, discover
from robosoc.kernels.core_layout import ERRATA_RTL, S_CODE_SIZE, S_ERRATA, S_MEM_BASE, S_MEM_SIZE, S_MUL, S_PC, S_RUN
from robosoc.kernels.jit_dispatch import (
    CTX_FLUSHES,
    CTX_SIZE,
    CTX_WORDS,
    NEVER_TRANSLATE,
    RUN_TRANSLATE,
    JitArrays,
    run_translated,
)

if TYPE_CHECKING:
    from robosoc.chip.core_state import CoreState

#: Arrivals at a word without a translation before ``auto`` translates a region there; between
#: arrivals the interpreter runs AUTO_STRETCH cycles at its own speed, so arrivals sample where
#: the program spends its time.
AUTO_THRESHOLD = 3
AUTO_STRETCH = 20_000
THRESHOLDS = {"jit": 1, "auto": AUTO_THRESHOLD}
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


#: (target, multiplier) -> regions translated in this process (any core, any run), in order
_TRANSLATED: dict[tuple[Target, bool], list[_Translated]] = {}


def translated_instructions() -> int:
    """Guest instructions in the regions this process translated."""
    return sum(t.region.instructions for regions in _TRANSLATED.values() for t in regions)


@dataclass
class TranslationStats:
    regions: int = 0
    instructions: int = 0  # guest instructions translated
    flushes: int = 0  # times self-modifying code made the core forget its translations
    reused: int = 0  # regions this process had translated already (same words)


class TranslatingCore:
    """Runs one tile of a :class:`CoreState` with translated regions (engine ``jit`` or ``auto``)."""

    def __init__(self, state: CoreState, tile: int = 0, mode: str = "jit", compiler: Compiler | None = None) -> None:
        if mode not in THRESHOLDS:
            raise ValueError(f"engine: must be one of {', '.join(map(repr, THRESHOLDS))}, got {mode!r}")
        self.state = state
        self.tile = tile
        self.mode = mode
        self.threshold = THRESHOLDS[mode]
        self.compiler = compiler or shared_compiler()
        self.stats = TranslationStats()
        self._tiles = np.array([tile], dtype=np.int64)
        self._code_size = -1
        self._jt: JitArrays | None = None

    # --- tables -------------------------------------------------------------------------------
    def forget(self) -> None:
        """Drop every translation (call after writing code from outside the core)."""
        self._code_size = -1
        self._jt = None

    def tables(self) -> JitArrays:
        """The tables the dispatch loop reads (its statistics are in ``ctx``: CTX_CALLS, CTX_STEPS ...)."""
        return self._tables()

    def _tables(self) -> JitArrays:
        code = int(self.state.st[self.tile, S_CODE_SIZE])
        if self._jt is None or code != self._code_size:
            words = code // 4 + 1  # the word after the code: its fetch error is the interpreter's
            hot = np.zeros(words, dtype=np.int32)
            hot[-1] = NEVER_TRANSLATE
            self._jt = JitArrays(
                entry_fn=np.zeros(words, dtype=np.int64),
                entry_slot=np.zeros(words, dtype=np.int64),
                entry_blk=np.zeros(words, dtype=np.int64),
                hot=hot,
                tmap=np.zeros(words, dtype=np.uint8),
                tpcs=np.zeros(0, dtype=np.int64),
                twords=np.zeros(0, dtype=np.int32),
                cnt=np.zeros(0, dtype=np.int64),
                slot_ptr=np.zeros(1, dtype=np.int64),
                slot_next=np.zeros(0, dtype=np.int64),
                slot_kc=np.zeros(0, dtype=np.int64),
                slot_delta=np.zeros(0, dtype=np.int64),
                ctx=np.zeros(CTX_SIZE, dtype=np.int64),
            )
            self._code_size = code
            self._slot_hist: list[np.ndarray] = []  # per region: (kc, delta) rows of its slots
            self._slot_len: list[np.ndarray] = []
            self._slot_next: list[np.ndarray] = []
            self._nslots = 0
            self._flushes_seen = 0
            self._install_known()
        return self._jt

    def _target(self) -> Target:
        st = self.state.st[self.tile]
        return Target(
            base=int(st[S_MEM_BASE]),
            mem_size=int(st[S_MEM_SIZE]),
            code_size=int(st[S_CODE_SIZE]),
            rtl_errata=int(st[S_ERRATA]) == ERRATA_RTL,
        )

    def _view(self) -> CodeView:
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
        """Enter every region this process translated for the same build whose words are unchanged."""
        m32 = self.state.m32[self.tile]
        for done in _TRANSLATED.get(self._key(), []):
            if np.array_equal(m32[done.pcs], done.words):
                self._install(done)
                self.stats.reused += 1

    def _key(self) -> tuple[Target, bool]:
        return self._target(), int(self.state.st[self.tile, S_MUL]) != 0

    def translate(self, pc: int) -> Region:
        """Translate the region starting at ``pc`` and enter its blocks in the tables."""
        jt = self._tables()
        if jt.ctx[CTX_FLUSHES] != self._flushes_seen:  # self-modifying code: the loop forgot everything
            self.stats.flushes += int(jt.ctx[CTX_FLUSHES]) - self._flushes_seen
            self._flushes_seen = int(jt.ctx[CTX_FLUSHES])
            self._install_known()
            if jt.entry_fn[(pc - self._target().base) >> 2] != 0:
                return Region(pc, {})
        target, has_mul = self._key()
        base = target.base
        view = self._view()
        m32 = self.state.m32[self.tile]
        region = discover(view, pc, translated=lambda a: jt.entry_fn[(a - base) >> 2] != 0)
        if region.blocks:
            emitted = emit_region(target, region)
            address = self.compiler.add(emitted.ir, NAME_PLACEHOLDER, [emitted.function])[0]
            pcs = np.array(sorted((p - base) >> 2 for p in region.words()), dtype=np.int64)
        else:
            emitted, address = EmittedRegion(ir="", function="", blocks={}), 0
            pcs = np.array([(pc - base) >> 2], dtype=np.int64)
        done = _Translated(region, emitted, address, pcs, m32[pcs].copy())
        _TRANSLATED.setdefault((target, has_mul), []).append(done)
        self._install(done)
        self.stats.regions += 1
        self.stats.instructions += region.instructions
        return region

    def _install(self, done: _Translated) -> None:
        jt = self._jt
        assert jt is not None
        base = self._target().base
        region = done.region
        if not region.blocks:
            jt.hot[(region.start - base) >> 2] = NEVER_TRANSLATE
            return
        slot_base = self._nslots
        self._add_slots(done.emitted.slots, slot_base)
        jt = self._jt
        for start, k in done.emitted.blocks.items():
            i = (start - base) >> 2
            if jt.entry_fn[i] == 0:
                jt.entry_fn[i] = done.address
                jt.entry_slot[i] = slot_base
                jt.entry_blk[i] = k
        jt.tmap[done.pcs] = 1
        n = int(jt.ctx[CTX_WORDS])
        self._jt = jt = jt._replace(
            tpcs=np.concatenate([jt.tpcs[:n], done.pcs]), twords=np.concatenate([jt.twords[:n], done.words])
        )
        jt.ctx[CTX_WORDS] = n + len(done.pcs)
        for block in region.blocks.values():
            if block.end is End.SIDE:
                i = (block.next_pc - base) >> 2
                if jt.entry_fn[i] == 0:
                    jt.hot[i] = NEVER_TRANSLATE
        if jt.entry_fn[(region.start - base) >> 2] == 0:
            jt.hot[(region.start - base) >> 2] = NEVER_TRANSLATE

    def _add_slots(self, slots: list[tuple[list[tuple[int, int]], int]], slot_base: int) -> None:
        hist = [row for h, _ in slots for row in h]
        self._slot_hist.append(np.array(hist, dtype=np.int64).reshape(-1, 2))
        self._slot_len.append(np.array([len(h) for h, _ in slots], dtype=np.int64))
        self._slot_next.append(np.array([n + slot_base if n >= 0 else -1 for _, n in slots], dtype=np.int64))
        self._nslots += len(slots)
        rows = np.concatenate(self._slot_hist)
        ptr = np.zeros(self._nslots + 1, dtype=np.int64)
        np.cumsum(np.concatenate(self._slot_len), out=ptr[1:])
        jt = self._jt
        assert jt is not None
        self._jt = jt._replace(
            cnt=np.zeros(self._nslots, dtype=np.int64),  # all zero between dispatcher calls
            slot_ptr=ptr,
            slot_next=np.concatenate(self._slot_next),
            slot_kc=rows[:, 0].copy(),
            slot_delta=rows[:, 1].copy(),
        )

    # --- running ------------------------------------------------------------------------------
    def step_until(self, until: int) -> int:
        """Run the tile to cycle ``until`` (or an event); its RUN_* status, as ``run_cores`` leaves it."""
        arrays = self.state.arrays()
        st = self.state.st[self.tile]
        while True:
            run_translated(arrays, self._tiles, until, self._tables(), self.threshold, STRETCHES[self.mode])
            status = int(st[S_RUN])
            if status != RUN_TRANSLATE:
                return status
            self.translate(int(st[S_PC]))
