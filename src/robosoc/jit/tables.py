"""The tables of one translating core: entering translated regions, copying them between cores.

The compiled dispatch loop (:mod:`robosoc.kernels.jit_dispatch`) reads a core's tables: per code
word its entry (region function, block), the arrivals counted towards a translation, the
instructions left in a translated block.
:class:`CoreTables` makes them for the code a tile holds and enters regions in them: those the
core translates and those any core of the process translated for the same build (the regions of
a process are kept here, :data:`_TRANSLATED`, and entered wherever their words are unchanged).  The
cores of a chip load one program: a core making fresh tables copies those the last core of its
build made (:meth:`CoreTables._install_as_before`), and a chip's first look clones the first new
tile's tables for every tile holding the same code (:meth:`CoreTables.clones`).  Translating
(:mod:`robosoc.jit.engine`) and when to do it (:mod:`robosoc.jit.policy`) are elsewhere.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Generic, Protocol, Self, TypeVar

import numpy as np

from robosoc.isa.table import OP_ENTRY
from robosoc.jit.target import Target
from robosoc.kernels.core_layout import BUILD_FIELDS, ERRATA_RTL, S_CODE_SIZE
from robosoc.kernels.jit_dispatch import CTX_WORDS, NEVER_TRANSLATE, JitArrays, empty_tables

if TYPE_CHECKING:
    from robosoc.jit.emit_ir import EmittedRegion
    from robosoc.jit.manifest import RegionRecord
    from robosoc.jit.regions import Region
    from robosoc.kernels.core import CoreArrays


class Cores(Protocol):
    """The state arrays of a set of cores, one row per tile, as a translator reads and writes them
    (:class:`robosoc.chip.core_state.CoreState` is one; the translator needs nothing else of the chip)."""

    st: np.ndarray
    m8: np.ndarray
    m32: np.ndarray
    dec: np.ndarray

    def op_rows(self, tile: int = 0) -> np.ndarray:
        """The predecode operation row of every word of the tile's loaded code (a view)."""
        ...

    def arrays(self) -> CoreArrays:
        """The arrays as the numba kernels take them."""
        ...


_T = TypeVar("_T")

#: A build: the target a core's code is translated for, and whether the core multiplies.
Build = tuple[Target, bool]


def build_of(st: np.ndarray) -> Build:
    """The build of the core whose state row is ``st``."""
    base, mem_size, code_size, errata, mul = st[BUILD_FIELDS].tolist()
    target = Target(base=base, mem_size=mem_size, code_size=code_size, rtl_errata=errata == ERRATA_RTL)
    return target, mul != 0


@dataclass
class TranslationStats:
    regions: int = 0
    instructions: int = 0  # guest instructions translated
    flushes: int = 0  # times self-modifying code made the core forget its translations
    reused: int = 0  # regions this process had translated already (same words)
    recorded: int = 0  # regions an earlier run recorded, entered without finding or writing them
    deferred: int = 0  # auto: hot regions left to the interpreter for now (compiling would cost too much yet)
    background: int = 0  # regions handed to the background thread
    run_seconds: float = 0.0  # host time in the dispatch loop
    translate_seconds: float = 0.0  # host time finding, writing and compiling regions (deferrals included)


@dataclass(frozen=True)
class Translated:
    """A region translated in this process, reusable while its words hold the same instructions."""

    start: int
    instructions: int
    address: int  # of the region function (0: nothing translated)
    pcs: np.ndarray  # word indices of the translated instructions
    words: np.ndarray  # their contents when translated
    #: addresses of its blocks' starts and the blocks' indices; addresses its side exits continue at
    block_starts: np.ndarray
    block_indices: np.ndarray
    side_exits: np.ndarray
    #: per word of ``pcs``: the instructions from it to the end of its block (1..255: the dispatch
    #: loop's ``tmap``, which lets the interpreter run the rest of a block entered in the middle)
    rest: np.ndarray
    #: the region found (None: entered from an earlier run's record, :mod:`robosoc.jit.manifest`)
    region: Region | None = None

    @staticmethod
    def of(
        region: Region, emitted: EmittedRegion, address: int, pcs: np.ndarray, words: np.ndarray, base: int
    ) -> Translated:
        from robosoc.jit.regions import End

        starts = np.array(list(emitted.blocks), dtype=np.int64)
        indices = np.array(list(emitted.blocks.values()), dtype=np.int64)
        sides = np.array([b.next_pc for b in region.blocks.values() if b.end is End.SIDE], dtype=np.int64)
        left = {(i.pc - base) >> 2: len(b.insns) - k for b in region.blocks.values() for k, i in enumerate(b.insns)}
        rest = np.array([min(left.get(int(w), 1), 255) for w in pcs], dtype=np.uint8)
        arrays = (starts, indices, sides, rest)
        return Translated(region.start, region.instructions, address, pcs, words, *arrays, region)

    def record(self, object_key: str, function: str) -> RegionRecord:
        """What a later run of the same program needs to enter this region (:mod:`robosoc.jit.manifest`)."""
        from robosoc.jit.manifest import RegionRecord

        names = ("pcs", "block_starts", "block_indices", "side_exits", "rest")
        return RegionRecord(self.start, self.instructions, object_key, function, {n: getattr(self, n) for n in names})

    @staticmethod
    def of_record(record: RegionRecord, address: int, words: np.ndarray) -> Translated:
        """A region an earlier run recorded, its object loaded at ``address``; ``words``: the
        program's words at its ``pcs``."""
        a = record.arrays
        return Translated(
            record.start,
            record.instructions,
            address,
            a["pcs"],
            words,
            a["block_starts"],
            a["block_indices"],
            a["side_exits"],
            a["rest"],
        )


#: build -> regions translated in this process (any core, any run), in order
_TRANSLATED: dict[Build, list[Translated]] = {}


@dataclass(frozen=True)
class _FreshTables:
    """A core's tables right after they were made afresh and the regions known then entered."""

    done_list: list[Translated]  # _TRANSLATED's list they were made from (a test may replace it)
    seen: int  # its entries then
    code: np.ndarray  # the core's code words then
    code_bytes: bytes  # ... as bytes (compared faster)
    tables: JitArrays
    mark_rows: np.ndarray  # the predecode rows of the words with an entry (OP_ENTRY there)
    starts_in: frozenset[int]


#: build -> the last fresh tables made for it (copied by the next core of that build and code)
_FRESH_TABLES: dict[Build, _FreshTables] = {}

#: the tables a core writes in place (the dispatch loop, entering regions, forgetting them); the
#: others are replaced whole when they change, so cores copying one core's tables share them
_WRITTEN_IN_PLACE = ("entry_fn", "entry_blk", "hot", "tmap", "ctx")


def _own_copy(jt: JitArrays) -> JitArrays:
    """``jt`` with copies of the arrays written in place (for another core, or to keep)."""
    return jt._replace(**{name: getattr(jt, name).copy() for name in _WRITTEN_IN_PLACE})


def stacked_copies(jt: JitArrays, n: int) -> dict[str, np.ndarray]:
    """``n`` copies of each array of ``jt`` written in place, as the rows of one array per name
    (row ``k`` of each: the ``k``-th copy; a row of a C-contiguous array is one, as the dispatch
    loop takes it)."""
    return {name: np.repeat(getattr(jt, name)[None, :], n, axis=0) for name in _WRITTEN_IN_PLACE}


_ENTERED = 0  # regions entered as translated in this process (any core): see entered_regions()


def entered_regions() -> int:
    """How many times a region was noted as translated in this process: while it stays the same,
    no core has a region of another core to enter (a chip skips its per-tile look)."""
    return _ENTERED


def translated_instructions() -> int:
    """Guest instructions in the regions this process translated."""
    return sum(t.instructions for regions in _TRANSLATED.values() for t in regions)


def note_translated(build: Build, done: Translated) -> list[Translated]:
    """Keep a region translated for ``build`` (every core of the build enters it); the build's list."""
    global _ENTERED
    _ENTERED += 1
    done_list = _TRANSLATED.setdefault(build, [])
    done_list.append(done)
    return done_list


@dataclass(frozen=True)
class Adoption:
    """What a copy of a core's tables goes with, as it was when copied (:meth:`CoreTables.clones`)."""

    seen: int
    starts_in: frozenset[int]
    code_size: int
    key_raw: bytes
    key_made: Build
    extra: object = None  # what a subclass keeps besides (a translator: its manifest)


class Clones(Generic[_T]):
    """Copies of one core's tables for other tiles holding its code and build
    (:meth:`CoreTables.clones`): ``tiles`` in order, ``rows`` their tables (the arrays a core writes
    in place as one array per name whose row ``k`` is ``tiles[k]``'s, the others shared: a chip
    hands them to its loop in one call, :func:`robosoc.kernels.jit_dispatch.set_table_copies`).
    A tile's translator is made only when asked for (:meth:`translator`): a 16x16 chip's run
    otherwise made 254 of them at its start, 2-4 ms, though a run that translates nothing new never
    needs one."""

    def __init__(self, maker: CoreTables, tiles: np.ndarray, rows: JitArrays, adoption: Adoption | None) -> None:
        self._maker = maker
        self.tiles = tiles
        self.rows = rows
        self._adoption = adoption
        self._index = {t: k for k, t in enumerate(tiles.tolist())}

    def __len__(self) -> int:
        return len(self.tiles)

    def __contains__(self, tile: int) -> bool:
        return tile in self._index

    def tables(self, tile: int) -> JitArrays:
        """Tile ``tile``'s copy (views of ``rows``)."""
        k = self._index[tile]
        rows = self.rows
        written = set(_WRITTEN_IN_PLACE)
        return JitArrays(*(getattr(rows, n)[k] if n in written else getattr(rows, n) for n in rows._fields))

    def translator(self, tile: int) -> _T:
        """Tile ``tile``'s translator, holding its copy (made now)."""
        assert self._adoption is not None
        made = self._maker._sibling(tile)
        made._adopt(self._adoption, self.tables(tile))
        return made  # type: ignore[return-value]  # the maker's class: _sibling makes one like it


class CoreTables:
    """The dispatch loop's tables of one tile of a :class:`Cores`, for the code it holds: made at
    the first use and again when the code size changed, dropped by :meth:`forget`."""

    def __init__(self, state: Cores, tile: int, stats: TranslationStats) -> None:
        self.state = state
        self.tile = tile
        self.stats = stats
        self._code_size = -1
        self._jt: JitArrays | None = None
        self._flushes_seen = 0  # the dispatch loop's flushes (self-modifying code) seen
        self._key_raw = b""  # the state fields _key() was made from, and what it made
        self._key_made: Build  # made at the first call (no fields are b"")
        self._known_seen = 0  # entries of _TRANSLATED[key] this core has looked at
        self._known_starts_in: set[int] = set()  # starts of the regions installed from there or translated here

    def _before_install(self) -> None:
        """The tables are about to be made for the code the tile holds (a subclass adds the regions
        earlier runs recorded for it to the process's, :data:`_TRANSLATED`, which are entered then)."""

    def _new_code(self) -> None:
        """The tables were made for new code (a subclass resets what depends on it)."""

    def _sibling(self, tile: int) -> Self:
        """A core like this one for another tile of the same state (:meth:`clones`)."""
        raise NotImplementedError

    # --- making them ---------------------------------------------------------------------------
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
            self._before_install()
            if not self._install_as_before():
                self._jt = empty_tables(code // 4 + 1)  # the word after the code: its fetch error is the interpreter's
                self._install_known()
                self._remember_install()
            self._new_code()
        assert self._jt is not None  # made above or by _install_as_before
        return self._jt

    def _key(self) -> Build:
        """The build this core's code is translated for: its target and whether it multiplies
        (made again only when the state fields it comes from changed: a chip's tiles ask often)."""
        raw = self.state.st[self.tile, BUILD_FIELDS].tobytes()
        if raw != self._key_raw:
            self._key_raw, self._key_made = raw, build_of(self.state.st[self.tile])
        return self._key_made

    def _target(self) -> Target:
        return self._key()[0]

    # --- the regions of the process ------------------------------------------------------------
    def _install_known(self) -> None:
        """Enter every region this process translated for the same build whose words are unchanged
        (after the tables were made afresh, or self-modifying code made the core forget them)."""
        self._known_seen = 0
        self._known_starts_in = set()
        self._install_new_known()

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
            start = done.start
            if start not in self._known_starts_in and np.array_equal(m32[done.pcs], done.words):
                known.append(done)
                self._known_starts_in.add(start)
        self._known_seen = len(done_list)
        if known:
            self._install_many(known)
            self.stats.reused += len(known)

    def install_known(self) -> None:
        """Enter the regions other cores of the same build translated since this core last looked
        (with background compiling they are entered at step boundaries, not when asked for)."""
        if self._jt is not None:
            self._install_new_known()

    def _add(self, done: Translated, done_list: list[Translated]) -> None:
        """Enter a region this core translated (``done_list``: its build's, ``done`` last in it)."""
        self._install(done)
        if self._known_seen == len(done_list) - 1:
            self._known_seen = len(done_list)
        self._known_starts_in.add(done.start)

    # --- copies of another core's --------------------------------------------------------------
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
        self._take(made.tables, made.seen, made.starts_in)
        self.state.dec[self.tile, made.mark_rows] = OP_ENTRY  # as _mark(): a 16x16 chip does it 255 times
        if made.seen != len(done_list):
            self._install_new_known()  # translated since
        return True

    def clones(self, tiles: list[int]) -> Clones[Self]:
        """Copies of this core's tables (which must not have run yet: made in the same look) for
        other tiles of its state holding its code and build, made one for all; tiles with other
        code or another build are left out.  The tiles of a chip load one program: made one by one,
        a translator and its tables cost about 35 µs in Python, 9-13 ms for a 16x16 chip at the
        start of every run; copied here, the checks, the predecode marks and the copies are made
        once for all, and a tile's translator when it is asked for."""
        jt = self._tables()
        st, m32, dec = self.state.st, self.state.m32, self.state.dec
        idx = np.asarray(tiles, dtype=np.int64)
        words = self._code_size // 4
        same = (st[idx][:, BUILD_FIELDS] == st[self.tile, BUILD_FIELDS]).all(axis=1)
        same &= (m32[idx, :words] == m32[self.tile, :words]).all(axis=1)
        idx = idx[same]
        if not len(idx):
            return Clones(self, idx, jt, None)
        rows = dec[idx, 0 : 2 * words : 2]  # a copy: the predecode marks of every tile at once
        rows[rows == OP_ENTRY] = 0  # as _clear_marks()
        rows[:, np.flatnonzero(jt.entry_fn[:words])] = OP_ENTRY  # as _mark()
        dec[idx, 0 : 2 * words : 2] = rows
        # the copies of the arrays a core writes in place, one block per array for all the tiles (a
        # copy per tile and array cost a 16x16 chip 2 ms at each run's start): each tile's row
        rows_of = stacked_copies(jt, len(idx))
        self.stats.reused += len(idx) * len(self._known_starts_in)  # (as _take() would count them)
        return Clones(self, idx, jt._replace(**rows_of), self._adoption())

    def _adoption(self) -> Adoption:
        """What a copy of this core's tables goes with, as it is now (:meth:`clones`)."""
        return Adoption(
            self._known_seen,
            frozenset(self._known_starts_in),
            self._code_size,
            self._key_raw,
            self._key_made,
        )

    def _adopt(self, adoption: Adoption, copy: JitArrays) -> None:
        """Take ``copy``, a copy of another core's tables, and what goes with them (:meth:`clones`)."""
        a = adoption
        self._take(copy, a.seen, a.starts_in, copied=True)
        self._code_size = a.code_size
        self._flushes_seen = 0
        self._key_raw, self._key_made = a.key_raw, a.key_made

    def _take(
        self,
        jt: JitArrays,
        seen: int,
        starts_in: Iterable[int],
        copied: bool = False,
    ) -> None:
        """Tables made by another core (or kept for the build) and their bookkeeping, as this core's
        (``copied``: ``jt`` is a copy already, its arrays written in place this core's own, and
        its regions counted as reused by :meth:`clones`)."""
        self._jt = jt if copied else _own_copy(jt)
        self._known_seen = seen
        self._known_starts_in = set(starts_in)
        if not copied:
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
            starts_in=frozenset(self._known_starts_in),
        )

    # --- entering regions ----------------------------------------------------------------------
    def _install(self, done: Translated) -> None:
        self._install_many([done])

    def _install_many(self, dones: list[Translated]) -> None:
        """Enter translated regions in the tables (their words added in one go)."""
        jt = self._jt
        assert jt is not None
        base = self._target().base
        n = int(jt.ctx[CTX_WORDS])
        pcs, words = [jt.tpcs[:n]], [jt.twords[:n]]
        for done in dones:
            if done.address == 0:  # nothing translatable there
                jt.hot[(done.start - base) >> 2] = NEVER_TRANSLATE
                continue
            at = (done.block_starts - base) >> 2
            free = jt.entry_fn[at] == 0  # a block already entered by an earlier region keeps its entry
            jt.entry_fn[at[free]] = done.address
            self._mark(at[free])
            jt.entry_blk[at[free]] = done.block_indices[free]
            jt.tmap[done.pcs] = done.rest
            pcs.append(done.pcs)
            words.append(done.words)
            sides = (done.side_exits - base) >> 2
            jt.hot[sides[jt.entry_fn[sides] == 0]] = NEVER_TRANSLATE
            if jt.entry_fn[(done.start - base) >> 2] == 0:
                jt.hot[(done.start - base) >> 2] = NEVER_TRANSLATE
        self._jt = jt = jt._replace(tpcs=np.concatenate(pcs), twords=np.concatenate(words))
        jt.ctx[CTX_WORDS] = len(jt.tpcs)
