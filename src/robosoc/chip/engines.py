"""How the cores execute their code: the engines ``interp``, ``jit`` and ``auto`` as objects.

Every engine gives the same cycles, counters, outputs and errors (docs/translation.md); they differ
in host speed only.  :func:`resolve_engine` turns a name (a command-line option, a chip
configuration's ``engine`` field, an argument) into its engine, checking it once; the chips
(:class:`~robosoc.chip.single.SingleCoreSoC`, :class:`~robosoc.chip.mpsoc.MPSoC`) take either.

The interpreter imports nothing of :mod:`robosoc.jit`: the translating engines import it when a
core first gets its translator (a short ``auto`` run whose chip never turns busy does without it,
30-45 ms when Python has to compile its modules' source).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol

from robosoc.config.chip import engine_name

if TYPE_CHECKING:
    from robosoc.chip.core_state import CoreState
    from robosoc.jit.engine import TranslatingCore
    from robosoc.jit.tables import TranslationStats


class Engine(Protocol):
    """What a chip asks of its engine."""

    @property
    def name(self) -> str:
        """As in :data:`~robosoc.config.chip.ENGINE_CHOICES` (``str(engine)`` gives it too)."""
        ...

    @property
    def translates(self) -> bool:
        """Whether any core ever runs translated code (False: the interpreter alone)."""
        ...

    @property
    def waits_for_busy_tiles(self) -> bool:
        """On a chip: whether a tile gets its translator only once it keeps busy (``auto``), rather
        than at the first step (``jit``)."""
        ...

    def translator(
        self, state: CoreState, tile: int = 0, stats: TranslationStats | None = None
    ) -> TranslatingCore | None:
        """The translator of one tile of ``state`` (None: the tile interprets).  ``stats``: shared
        by the translators of one chip (``auto``'s compile budget is the chip's)."""
        ...


@dataclass(frozen=True)
class Interpreter:
    """``interp``: every core on the interpreter (:func:`robosoc.kernels.core.run_cores`)."""

    name: str = "interp"
    translates: bool = False
    waits_for_busy_tiles: bool = False

    def translator(self, state: CoreState, tile: int = 0, stats: TranslationStats | None = None) -> None:
        return None

    def __str__(self) -> str:
        return self.name


@dataclass(frozen=True)
class Translating:
    """``jit`` or ``auto``: the cores run under the dispatch loop with translated regions, by the
    policy of that name (:mod:`robosoc.jit.policy`)."""

    name: str
    waits_for_busy_tiles: bool
    translates: bool = True

    def translator(self, state: CoreState, tile: int = 0, stats: TranslationStats | None = None) -> TranslatingCore:
        from robosoc.jit.engine import TranslatingCore

        return TranslatingCore(state, tile=tile, mode=self.name, stats=stats)

    def __str__(self) -> str:
        return self.name


INTERP = Interpreter()
JIT = Translating("jit", waits_for_busy_tiles=False)
AUTO = Translating("auto", waits_for_busy_tiles=True)
ENGINES: dict[str, Engine] = {engine.name: engine for engine in (INTERP, JIT, AUTO)}


def resolve_engine(engine: str | Engine) -> Engine:
    """The engine named ``engine`` (an engine is returned as it is).

    Raises:
        ValueError: an unknown name, with the choices (:func:`robosoc.config.chip.engine_name`).
    """
    if isinstance(engine, str):
        return ENGINES[engine_name(engine)]
    return engine
