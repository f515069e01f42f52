"""Translated code on the MPSoC's cores: one translator per tile, and the tables the chip loop reads.

:class:`~robosoc.chip.mpsoc.MPSoC` holds one :class:`ChipTranslation`.  Before each call of
:func:`robosoc.kernels.chip.run_chip` it makes sure every loaded core tile has its translator
(:class:`robosoc.jit.engine.TranslatingCore`, made by the chip's engine,
:mod:`robosoc.chip.engines`: ``jit`` or ``auto``) and hands the loop each
tile's tables in a numba typed list; when a tile turns hot at a word without a translation the
loop stops with CHIP_TRANSLATE, :meth:`ChipTranslation.translate` translates a region there and
the loop goes on where it stopped.  The translators of one chip share their statistics, so
``auto``'s compile budget is a share of the chip's run time.
"""

from __future__ import annotations

import time
from typing import TYPE_CHECKING

import numpy as np
from numba.typed import List

from robosoc.kernels import chip as kc
from robosoc.kernels.core_layout import BUILD_FIELDS, RUN_CHUNK, S_CODE_SIZE, S_PC, S_RUN
from robosoc.kernels.jit_dispatch import JitArrays, empty_tables, set_table_copies, set_tables, tables_list

if TYPE_CHECKING:
    from collections.abc import Callable, Iterator

    from robosoc.chip.engines import Engine
    from robosoc.chip.mpsoc import MPSoC
    from robosoc.jit.engine import TranslatingCore
    from robosoc.jit.tables import Clones, TranslationStats


#: auto on the chip: a tile gets its translator once, since the last look, it executed at least
#: AUTO_BUSY_SHARE instructions per chip cycle and AUTO_MIN_INSTRUCTIONS in all.  A tile that works
#: in short bursts between sleeps pays a call of the dispatch loop per quantum and per wake-up, and
#: the flush of its blocks' counts once per chip-loop call costs about what counting the distinct
#: instructions it ran costs the interpreter, which eats what its translated blocks save when it
#: runs little.  Measured on the 10 s lockstep flight (2026-11-28, docs/translation.md), the EKF
#: tile runs 0.49 instructions per cycle (float, no mul), 0.095 (float + mul), 0.078 (fixed, no
#: mul) and 0.026 (fixed + mul), the other tile 0.005-0.05; `jit` flew the first three builds
#: 15-60 % faster than `interp` and the fixed+mul build about 8 % slower.  The sleeping 16x16
#: chip's tiles run about 0.002.  A busy core runs 0.3..1 instruction per cycle.
AUTO_BUSY_SHARE = 0.04
AUTO_MIN_INSTRUCTIONS = 100_000
#: auto: chip cycles between looks at the tiles that do not translate yet (a long step is cut into
#: pieces of this length while there are such tiles: stopping the chip loop anywhere is exact)
AUTO_LOOK_CYCLES = 1 << 20
#: ... doubled after each look that gave no tile a translator, up to this (a mostly sleeping chip
#: runs millions of cycles per millisecond of host time: a stop per 2**20 cycles halved its speed)
AUTO_LOOK_MAX_CYCLES = 1 << 24
#: auto: host seconds between looks at the dispatch loop's threshold while nothing else changed
#: (it moves with the run time only: the budget grows, the warm-up passes)
THRESHOLD_LOOK_SECONDS = 0.005
#: auto: host seconds between looks at the whole-code translations (:mod:`robosoc.chip.whole_code`):
#: a tile that ran enough starts one, a finished one gives its code's tiles their regions
WHOLE_CODE_LOOK_SECONDS = 0.1


#: (program object id, build fields) of the programs this process saw translated whole: a later
#: chip holding them gives their tiles translators at its first step, not after the warm-up of a
#: look (a short run of a sleeping 16x16 chip, 40 ms, had half of it interpreted).  A program whose
#: object's id was reused by another only gets its translators early: their tables hold what the
#: manifest of its own code holds.
_WHOLE_PROGRAMS: set[tuple[int, bytes]] = set()


class TileTranslators:
    """Per tile its translator (None: it interprets), as a list; a tile whose tables are a copy of
    another's (:meth:`robosoc.jit.tables.CoreTables.clones`) gets its translator when first asked
    for (:meth:`made` lists only those made)."""

    def __init__(self, tiles: int) -> None:
        self._made: list[TranslatingCore | None] = [None] * tiles
        self._lazy: dict[int, Clones[TranslatingCore]] = {}
        self._listed: list[TranslatingCore] | None = None  # made()'s list, until a translator changes

    def __len__(self) -> int:
        return len(self._made)

    def __getitem__(self, t: int) -> TranslatingCore | None:
        clones = self._lazy.pop(t, None)
        if clones is not None:
            self._made[t] = clones.translator(t)
            self._listed = None
        return self._made[t]

    def __setitem__(self, t: int, translator: TranslatingCore | None) -> None:
        self._lazy.pop(t, None)
        self._made[t] = translator
        self._listed = None

    def __iter__(self) -> Iterator[TranslatingCore | None]:
        return (self[t] for t in range(len(self._made)))

    def add(self, clones: Clones[TranslatingCore]) -> None:
        """The translators of ``clones``' tiles, made when asked for."""
        for t in clones.tiles.tolist():
            self._made[t] = None
            self._lazy[t] = clones
        self._listed = None

    def has(self, t: int) -> bool:
        """Whether tile ``t`` has a translator (made or not yet)."""
        return t in self._lazy or self._made[t] is not None

    def made_items(self) -> list[tuple[int, TranslatingCore]]:
        """(tile, translator) of the translators made so far."""
        return [(t, tr) for t, tr in enumerate(self._made) if tr is not None]

    def made(self) -> list[TranslatingCore]:
        """The translators made so far (a copy's, once asked for; the first of a program's tiles
        always: the others' are copies of its tables).  The same list until one changes (the chip
        asks before every step): do not change it."""
        if self._listed is None:
            self._listed = [tr for tr in self._made if tr is not None]
        return self._listed


class ChipTranslation:
    """Per tile: whether it runs translated code, its translator and its tables (see the module doc)."""

    def __init__(self, tiles: int, engine: Engine) -> None:
        self.engine = engine
        self.on = np.zeros(tiles, dtype=np.int64)
        self.params = np.zeros(kc.J_SIZE, dtype=np.int64)
        self._empty = empty_tables()
        self._tables = tables_list(self._empty, tiles)
        self._given: list[JitArrays | None] = [None] * tiles  # what _tables holds per tile, if translated
        self.translators = TileTranslators(tiles)
        self._stopped = np.zeros(tiles, dtype=bool)  # tiles that interpret from now on
        self.stats: TranslationStats | None = None
        self._seen = np.zeros((tiles, 2), dtype=np.int64)  # auto: (instructions, chip cycle) at the last look
        self._watched: set[int] = set()  # auto: loaded tiles without a translator yet
        self._cached = False  # auto: some translator's code has regions compiled by an earlier run
        self._look = AUTO_LOOK_CYCLES  # auto: chip cycles to the next look
        self._looked = 0  # auto: the chip cycle of the last look
        #: what :meth:`prepare` last saw (:meth:`_situation`): the same again, it has nothing to do
        self._prepared: tuple[int, int, bytes] | None = None
        self._changes = 0  # tiles whose code was loaded since the chip was made
        self._run_seconds = 0.0  # host seconds in the chip loop
        # auto's whole-code translations (robosoc.chip.whole_code)
        self._keys: dict[int, str] = {}  # tile -> its code's manifest key (made once per load)
        self._key_memo: dict[tuple[int, bytes], str] = {}  # (program id, build fields) -> key
        self._whole: set[str] = set()  # keys whose whole code is translated
        self._asked: set[int] = set()  # tiles whose code's translation was started (or failed)
        self._entered: set[int] = set()  # tiles whose code is whole and that were given its regions
        self._ready: set[int] = set()  # tiles to get their translator at the next look: their code is whole
        self._seen_before: dict[str, bool] = {}  # key -> whether an earlier chip ran that code (whole_code.seen_before)
        self._whole_look = 0.0  # host time of the next look
        self._threshold_look = 0.0  # host time auto's threshold is looked at next, if nothing else changed
        self._entered_regions: Callable[[], int] | None = None  # robosoc.jit.tables.entered_regions, once imported

    def arguments(self) -> tuple[np.ndarray, List, np.ndarray]:
        """``run_chip``'s jit_on, jit_tables and jit_params (the same types whatever the engine: the
        chip loop is compiled once, with the dispatch loop in it)."""
        return self.on, self._tables, self.params

    def prepare(self, chip: MPSoC) -> None:
        """Before a run: a translator for every loaded core tile, and its current tables."""
        if not self.engine.translates:
            return
        situation = self._situation(chip)
        due = bool(self._watched) and chip.cycle - self._looked >= self._look  # auto's look at watched tiles
        now = time.perf_counter()
        if self.engine.waits_for_busy_tiles and now >= self._whole_look:
            self._look_whole_code(chip)
            due = due or bool(self._ready)
        busy = self._busy(chip) if self.engine.waits_for_busy_tiles and due else None
        if busy is not None and self._ready:
            busy[sorted(self._ready)] = True  # their regions are all compiled: nothing left to wait for
            self._ready.clear()
        turned = busy is not None and bool(busy[sorted(self._watched)].any())  # a watched tile turned busy
        if situation is not None and situation == self._prepared and not turned:
            # nothing new for any tile (a per-tile look cost a sleeping 16x16 chip 1 ms per step,
            # and auto's flight 0.2 ms per step while it watched its other tile): only auto's
            # threshold moves with the run time (looked at every THRESHOLD_LOOK_SECONDS: 15 us a
            # step), and the next look at watched tiles comes later
            if now >= self._threshold_look:
                self._threshold_look = now + THRESHOLD_LOOK_SECONDS
                live = self.translators.made()
                if live:
                    self._set_threshold(live[0])
            if busy is not None:
                self._look = min(2 * self._look, AUTO_LOOK_MAX_CYCLES)
            return
        if busy is None and self.engine.waits_for_busy_tiles:
            busy = self._busy(chip)
        new: list[int] = []
        # the loaded core tiles that may translate, in tile order (looked at together: a Python
        # look per tile cost a sleeping 16x16 chip on auto 0.5 ms at each run's start)
        tiles = np.array(sorted(chip.programs), dtype=np.int64)
        tiles = tiles[~self._stopped[tiles] & (chip.cores.st[tiles, S_CODE_SIZE] != 0)]
        if busy is not None:
            idle = (self.on[tiles] == 0) & ~busy[tiles]  # (a tile has a translator while on)
            self._watched.update(tiles[idle].tolist())  # auto: no translator until it turns busy
            tiles = tiles[~idle]
        for t in tiles.tolist():
            if not self.translators.has(t):
                self._watched.discard(t)
                new.append(t)  # made below, all at once
                continue
            self._watched.discard(t)
            translator = self.translators[t]
            assert translator is not None
            translator.finish_compiles()
            translator.install_known()  # what the other tiles' compiles gave
            self._give(t)
        if new:
            self._make_translators(chip, new)
        made = bool(new)
        if busy is not None:
            self._look = AUTO_LOOK_CYCLES if made else min(2 * self._look, AUTO_LOOK_MAX_CYCLES)
        live = self.translators.made()  # (a copy's translator has its first's cached regions)
        # (only a policy that reads its code's manifest has cached regions: auto)
        self._cached = bool(live) and live[0].policy.reads_manifest and any(tr.has_cached_regions() for tr in live)
        if live:
            self._set_threshold(live[0])
        self._prepared = self._situation(chip)

    def _situation(self, chip: MPSoC) -> tuple[int, int, bytes] | None:
        """What decides the tiles' tables: regions entered in the process, code loaded into tiles,
        the code sizes (None: a look is due anyway, for regions still compiling; auto's watched
        tiles are looked at by :meth:`prepare`).  A stopped tile needs no look: :meth:`stop` took
        its tables away."""
        if any(tr.compiling() for tr in self.translators.made()):  # (a copy not made compiles nothing)
            return None
        entered = 0 if self._entered_regions is None else self._entered_regions()
        return entered, self._changes, chip.cores.st[:, S_CODE_SIZE].tobytes()

    def _make_translators(self, chip: MPSoC, tiles: list[int]) -> None:
        """Translators for ``tiles``: the first made, the tiles holding the same code and build
        copies of it (:meth:`TranslatingCore.clones`); then the same for the first tile left, and
        so on (one round per program loaded)."""
        left = tiles
        while left:
            first = self._translator(chip, left[0])
            clones = first.clones(left[1:])
            self.translators[left[0]] = first
            self.on[left[0]] = 1
            self._give(left[0])
            if len(clones):  # the copies' tables to the loop, in one call
                self.translators.add(clones)
                self.on[clones.tiles] = 1
                set_table_copies(self._tables, clones.tiles, clones.rows)
                for t in clones.tiles.tolist():
                    self._given[t] = None  # (its translator's tables, once made, are given again: the same arrays)
            left = [t for t in left[1:] if t not in clones]

    def _translator(self, chip: MPSoC, t: int) -> TranslatingCore:
        """A translator for tile ``t`` (the translating engine is imported only now: a short run of
        ``auto`` whose tiles never turn busy does without it, 30-45 ms when Python has to compile
        its modules' source)."""
        from robosoc.jit.tables import TranslationStats

        if self.stats is None:
            from robosoc.jit.tables import entered_regions

            self.stats = TranslationStats(run_seconds=self._run_seconds)
            self._entered_regions = entered_regions
        translator = self.engine.translator(chip.cores, t, self.stats)
        assert translator is not None, f"engine {self.engine} made no translator"
        return translator

    def _set_threshold(self, translator: TranslatingCore) -> None:
        """The dispatch loop's parameters, from a translator (they share mode and budget) and whether
        some translator has cached regions (known from :meth:`prepare`: not scanned per translation)."""
        self.params[kc.J_THRESHOLD] = translator.ask_threshold(self._cached)
        self.params[kc.J_STRETCH] = translator.stretch

    def look_cycles(self) -> int:
        """auto: chip cycles from now to the next look at the tiles without a translator."""
        return self._look

    def watching(self) -> bool:
        """auto: whether some loaded tile may still get a translator (the chip is looked at again)."""
        return bool(self._watched)  # only an engine that waits for busy tiles watches any

    def _look_whole_code(self, chip: MPSoC) -> None:
        """auto: the whole-code translations (:mod:`robosoc.chip.whole_code`) of the tiles whose
        program executed :data:`~robosoc.chip.whole_code.WHOLE_CODE_MIN_INSTRUCTIONS` (on all the
        tiles holding it) once the chip loop ran :data:`~robosoc.chip.whole_code.WHOLE_CODE_MIN_SECONDS`
        (a short run imports nothing of the translator for them), or at once for a program this
        process knows is translated whole.  Such a tile gets its translator at the next look (or,
        having one, enters the regions); the first whose code is not translated whole has it
        translated in a second process."""
        from robosoc.chip.whole_code import WHOLE_CODE_MIN_INSTRUCTIONS, WHOLE_CODE_MIN_SECONDS

        warm = self._run_seconds >= WHOLE_CODE_MIN_SECONDS
        if not warm and not _WHOLE_PROGRAMS:
            return  # (looked at again at the next step: a short run ran 0.02 s after 0.04 s)
        tiles = np.array(sorted(chip.programs), dtype=np.int64)
        tiles = tiles[~self._stopped[tiles] & (chip.cores.st[tiles, S_CODE_SIZE] != 0)]
        if _WHOLE_PROGRAMS:
            known = [t for t in tiles.tolist() if t not in self._entered and self._memo(chip, t) in _WHOLE_PROGRAMS]
            self._enter_whole(chip, known)
        if not warm:
            return
        self._whole_look = time.perf_counter() + WHOLE_CODE_LOOK_SECONDS
        # the instructions executed by all tiles holding the same program: its translation serves
        # them all (a sleeping 16x16 chip's tiles run a few thousand each)
        executed = chip.cores.opc[tiles].sum(axis=1)
        programs = np.array([id(chip.programs[t]) for t in tiles.tolist()], dtype=np.int64)
        group = np.unique(programs, return_inverse=True)[1]
        tiles = tiles[np.bincount(group, weights=executed)[group] >= WHOLE_CODE_MIN_INSTRUCTIONS]
        if len(tiles):
            self._enter_whole(chip, tiles.tolist())
            self._start_whole(chip, tiles.tolist())

    def _enter_whole(self, chip: MPSoC, tiles: list[int]) -> None:
        """Of ``tiles``, those whose code is translated whole get their translators at the next look
        (or, having one, enter the regions)."""
        from robosoc.chip.whole_code import whole_code_translations
        from robosoc.jit.manifest import whole_code_translated

        translations = whole_code_translations()
        running = translations.running()
        for t in tiles:
            if t not in self._keys:
                self._keys[t] = self._key_of(chip, t)
        for key in {self._keys[t] for t in tiles} - self._whole:
            if key in translations.done or (key != running and whole_code_translated(key)):
                self._whole.add(key)
        for t in tiles:
            if self._keys[t] not in self._whole or t in self._entered:
                continue
            self._entered.add(t)
            _WHOLE_PROGRAMS.add(self._memo(chip, t))
            if not self.translators.has(t):
                self._ready.add(t)
                continue
            translator = self.translators[t]
            assert translator is not None
            if translator.enter_recorded():
                self._give(t)

    def _start_whole(self, chip: MPSoC, tiles: list[int]) -> None:
        """The code of the first of ``tiles`` not translated whole (nor started) that an earlier
        chip ran too is translated in a second process, if none runs."""
        from robosoc.chip.whole_code import seen_before, whole_code_translations

        translations = whole_code_translations()
        if translations.running() is not None:
            return
        for t in tiles:
            key = self._keys[t]
            if t in self._asked or key in self._whole:
                continue
            if key not in self._seen_before:
                self._seen_before[key] = seen_before(key)
            if not self._seen_before[key]:
                continue  # its first run: the next chip running it starts the translation
            if translations.start(chip.cores, t, key):
                self._asked.update(u for u in tiles if self._keys[u] == key)
                return  # one at a time
            if translations.running() is None and key in translations.failed:
                self._asked.add(t)

    @staticmethod
    def _memo(chip: MPSoC, t: int) -> tuple[int, bytes]:
        """What tile ``t``'s code is known by in this process: its program object and build."""
        return id(chip.programs[t]), chip.cores.st[t, BUILD_FIELDS].tobytes()

    def _key_of(self, chip: MPSoC, t: int) -> str:
        """The manifest key of tile ``t``'s code for auto (made once per program and build)."""
        from robosoc.jit.engine import code_manifest_key

        memo = self._memo(chip, t)
        key = self._key_memo.get(memo)
        if key is None:
            key = self._key_memo[memo] = code_manifest_key(chip.cores, t, self.engine.name)
        return key

    def _busy(self, chip: MPSoC) -> np.ndarray:
        """auto: per tile, whether it worked enough since the last look to be worth translating."""
        done = chip.cores.opc.sum(axis=1)
        now = chip.cycle
        instructions = done - self._seen[:, 0]
        cycles = now - self._seen[:, 1]
        self._seen[:, 0] = done
        self._seen[:, 1] = now
        self._looked = now
        return (instructions >= AUTO_MIN_INSTRUCTIONS) & (instructions >= AUTO_BUSY_SHARE * cycles)

    def _give(self, t: int) -> None:
        translator = self.translators[t]
        assert translator is not None
        tables = translator.tables()
        if tables is not self._given[t]:
            set_tables(self._tables, t, tables)
            self._given[t] = tables

    def ran(self, seconds: float) -> None:
        """The chip loop ran for ``seconds`` of host time (auto's budget and warm-up count from the
        chip's start, not from its first translator's)."""
        self._run_seconds += seconds
        if self.stats is not None:
            self.stats.run_seconds += seconds

    def translate(self, t: int) -> None:
        """After CHIP_TRANSLATE: translate the region at tile ``t``'s pc and let the tile go on."""
        translator = self.translators[t]
        assert translator is not None, f"tile {t} asked for a translation without a translator"
        state = translator.state
        translator.finish_compiles()
        translator.translate(int(state.st[t, S_PC]))  # or installs what another core translated there
        self._give(t)
        state.st[t, S_RUN] = RUN_CHUNK
        self._set_threshold(translator)

    def forget(self, t: int) -> None:
        """Tile ``t``'s code was (re)loaded from outside: its translations no longer hold."""
        self._changes += 1
        self._keys.pop(t, None)
        self._asked.discard(t)
        self._entered.discard(t)
        self._ready.discard(t)
        self._whole_look = 0.0
        translator = self.translators[t]
        if translator is not None:
            translator.forget()

    def stop(self, t: int) -> None:
        """Tile ``t`` interprets from now on (a breakpoint, a profile)."""
        self._stopped[t] = True
        self._watched.discard(t)
        self.on[t] = 0
        translator = self.translators[t]
        if translator is not None:
            translator.forget()  # the interpreter stops before none of its blocks
        self.translators[t] = None
        set_tables(self._tables, t, self._empty)
        self._given[t] = None

    def finish_compiles(self, wait: bool = False) -> None:
        """Enter what the background thread compiled (all of it, waiting, with ``wait``)."""
        for t, translator in self.translators.made_items():  # (a copy not made compiles nothing)
            if translator.compiling():
                translator.finish_compiles(wait)
                self._give(t)

    def stop_all(self) -> None:
        for t in range(len(self.on)):
            self.stop(t)
