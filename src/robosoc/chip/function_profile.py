"""The exact profile of a run: cycles, instructions and energy per firmware function, tile and task.

With profiling on (:meth:`robosoc.chip.mpsoc.MPSoC.enable_profile`) the core counts, per tile, task
and word of code, how often the instruction there executed and the dynamic extra cycles it took
(taken branches, multiplier steps).  Here words become functions through the ELF symbols, and counts
become cycles and energy by the rules the run's own counters use: an instruction costs one cycle
plus the fixed extra cycles of its timing class plus its dynamic ones (:mod:`robosoc.isa.table`,
:func:`robosoc.chip.counters.counters_dict`), and energy is Σ count × coefficient of the same
:class:`robosoc.chip.energy.EnergyModel`.  Nothing is sampled.

Cycles no instruction takes get rows of their own, so that a tile's rows add up to its cycles and
energy exactly (:func:`profile_totals`):

* ``(interrupt entry)``: the vector-fetch bubbles of interrupt and trap entries;
* ``(DMA)``: cycles the core waits while its network interface copies a packet;
* ``(sleep)``: clock-gated cycles between a SLEEP store and the wake-up;
* ``(reset)``: the pipeline fill before the first instruction;

and the chip has one more, ``(NoC)``: the routers' energy (no core cycles).
"""

from __future__ import annotations

import csv
import io
import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from robosoc.chip.core_state import CoreState
from robosoc.chip.energy import INSTRUCTION_CLASSES, STALL_KINDS, EnergyModel
from robosoc.chip.mpsoc import MPSoC
from robosoc.chip.single import SingleCoreSoC
from robosoc.isa.table import CLASS_NAMES, FIXED_EXTRA_CYCLES, STALL_KIND, lookup
from robosoc.kernels.core_layout import PIPELINE_FILL
from robosoc.program.elf import Program

SCHEMA = 1

ENTRY_ROW = "(interrupt entry)"
DMA_ROW = "(DMA)"
SLEEP_ROW = "(sleep)"
RESET_ROW = "(reset)"
NOC_ROW = "(NoC)"
#: Rows that are not functions, and the counter each one is made of (None: the NoC's energy).
OTHER_ROWS: dict[str, str | None] = {
    ENTRY_ROW: "entry_cycle",
    DMA_ROW: "dma_cycle",
    SLEEP_ROW: "sleep_cycle",
    RESET_ROW: None,
    NOC_ROW: None,
}
#: The counts each row keeps: instructions per class and cycles per stall kind (the energy model's names).
COUNT_NAMES: tuple[str, ...] = (*INSTRUCTION_CLASSES, *STALL_KINDS)
CSV_FIELDS = ("tile", "task", "task_name", "function", "cycles", "instructions", "energy_nj", *COUNT_NAMES)

_KIND_INDEX = {kind: k for k, kind in enumerate(STALL_KINDS)}


@dataclass(frozen=True)
class ProfileRow:
    """One function (or one of :data:`OTHER_ROWS`) of one task on one tile (``tile`` None: the chip)."""

    tile: tuple[int, int] | None
    task: int | None
    task_name: str
    function: str
    cycles: int
    instructions: int
    counts: dict[str, int]
    energy_pj: float

    @property
    def tile_text(self) -> str:
        return "" if self.tile is None else f"{self.tile[0]},{self.tile[1]}"


@dataclass
class FunctionProfile:
    """Every row of a run's profile, and the clock (for times)."""

    rows: list[ProfileRow]
    clock_ns: float
    notes: list[str] = field(default_factory=list)

    def tiles(self) -> list[tuple[int, int]]:
        return sorted({r.tile for r in self.rows if r.tile is not None})

    def top(self, tile: tuple[int, int], task: int, n: int = 10) -> list[ProfileRow]:
        """The ``n`` rows of ``task`` on ``tile`` that took the most cycles (then energy)."""
        mine = [r for r in self.rows if r.tile == tile and r.task == task]
        return sorted(mine, key=lambda r: (-r.cycles, -r.energy_pj, r.function))[:n]

    def to_json(self) -> dict[str, Any]:
        totals = profile_totals(self)
        return {
            "schema": SCHEMA,
            "clock_ns": self.clock_ns,
            "totals": {
                "cycles": {_text(xy): t["cycles"] for xy, t in totals.items() if xy is not None},
                "instructions": {_text(xy): t["instructions"] for xy, t in totals.items() if xy is not None},
                "tiles_uj": {_text(xy): t["energy_pj"] / 1e6 for xy, t in totals.items() if xy is not None},
                "noc_uj": totals[None]["energy_pj"] / 1e6 if None in totals else 0.0,
                "total_uj": math.fsum(t["energy_pj"] for t in totals.values()) / 1e6,
            },
            "notes": list(self.notes),
            "rows": [
                {
                    "tile": r.tile_text,
                    "task": r.task,
                    "task_name": r.task_name,
                    "function": r.function,
                    "cycles": r.cycles,
                    "instructions": r.instructions,
                    "energy_nj": r.energy_pj / 1000,
                    "counts": {k: v for k, v in r.counts.items() if v},
                }
                for r in self.rows
            ],
        }

    def csv_text(self) -> str:
        out = io.StringIO()
        writer = csv.writer(out, lineterminator="\n")
        writer.writerow(CSV_FIELDS)
        for r in self.rows:
            writer.writerow([
                r.tile_text, "" if r.task is None else r.task, r.task_name, r.function, r.cycles, r.instructions,
                f"{r.energy_pj / 1000:.6f}", *(r.counts.get(k, 0) for k in COUNT_NAMES),
            ])  # fmt: skip
        return out.getvalue()

    def json_text(self) -> str:
        return json.dumps(self.to_json(), indent=1) + "\n"


def _text(xy: tuple[int, int]) -> str:
    return f"{xy[0]},{xy[1]}"


def _energy(model: EnergyModel, counts: Mapping[str, int]) -> float:
    return math.fsum(model.breakdown_pj(dict(counts)).values())


@dataclass(frozen=True)
class _CodeTable:
    """Per word of a tile's executed code: function index, class, fixed extra cycles and their stall
    kind, and the stall kind of its dynamic extra cycles (-1: none)."""

    functions: list[str]
    function: np.ndarray
    cls: np.ndarray
    fixed: np.ndarray
    fixed_kind: np.ndarray
    dyn_kind: np.ndarray


def _code_table(cores: CoreState, t: int, program: Program | None, words: np.ndarray) -> _CodeTable:
    names: dict[str, int] = {}
    n = len(words)
    function = np.full(n, -1, dtype=np.int64)
    cls = np.full(n, -1, dtype=np.int64)
    fixed = np.zeros(n, dtype=np.int64)
    fixed_kind = np.full(n, -1, dtype=np.int64)
    dyn_kind = np.full(n, -1, dtype=np.int64)
    for j, w in enumerate(words):
        pc = cores.base + 4 * int(w)
        ins = lookup(int(cores.m32[t, int(w)]) & 0xFFFFFFFF)
        if ins is None or ins.unsupported:
            continue  # an illegal or unimplemented instruction stops the core: no cycle, not counted
        sym = program.symbol_at(pc) if program is not None else None
        name = sym.name if sym is not None else f"0x{pc:08x}"
        function[j] = names.setdefault(name, len(names))
        cls[j] = INSTRUCTION_CLASSES.index(CLASS_NAMES[ins.cls])
        kind = STALL_KIND.get(ins.timing)
        fixed[j] = FIXED_EXTRA_CYCLES[ins.timing]
        if kind is not None:
            fixed_kind[j] = dyn_kind[j] = _KIND_INDEX[kind]
    return _CodeTable(list(names), function, cls, fixed, fixed_kind, dyn_kind)


def tile_rows(
    cores: CoreState,
    t: int,
    xy: tuple[int, int],
    program: Program | None,
    counters: Mapping[int, Mapping[str, int]],
    model: EnergyModel,
    task_names: Mapping[int, str],
) -> list[ProfileRow]:
    """The rows of core ``t`` (shown as tile ``xy``) of a profiled run: its functions per task bank,
    and per task the rows that are not functions, from ``counters`` (task -> its counters, as
    :meth:`MPSoC.task_counters` gives them).

    Raises:
        RuntimeError: profiling was not enabled.
    """
    if not cores.profiling:
        raise RuntimeError("profiling is off: enable it before the run")
    stride = cores.profile_stride
    banks = cores.executions(t)
    extras = cores.pext[t].reshape(-1, stride)
    words = np.nonzero(banks.any(axis=0))[0]
    table = _code_table(cores, t, program, words)
    rows: list[ProfileRow] = []
    for task in sorted(set(counters) | set(np.nonzero(banks.any(axis=1))[0].tolist())):
        name = task_names.get(task, f"task {task}")
        rows += _task_rows(xy, task, name, banks[task, words], extras[task, words], table, model)
        c = counters.get(task, {})
        for row, counter in OTHER_ROWS.items():
            value = c.get(counter, 0) if counter is not None else 0
            if row == RESET_ROW and task == 0:
                value = PIPELINE_FILL  # a core starts in task 0 (TASK_ID reads 0 after reset)
            if value:
                counts = {counter: value} if counter is not None else {}
                rows.append(ProfileRow(xy, task, name, row, value, 0, counts, _energy(model, counts)))
    return rows


def chip_profile(
    chip: MPSoC,
    tiles: Sequence[tuple[int, int]],
    model: EnergyModel,
    task_names: Mapping[tuple[tuple[int, int], int], str] | None = None,
    tile_models: Mapping[tuple[int, int], EnergyModel] | None = None,
) -> FunctionProfile:
    """The profile of ``tiles`` of a chip run with profiling on (:meth:`MPSoC.enable_profile`), plus
    the NoC's row.  Finishes the chip's accounting (the per-task counters give the other rows).
    ``tile_models``: a tile's own coefficients (a core on its own clock), else ``model``'s; a tile's
    cycles are its core's own.

    Raises:
        RuntimeError: profiling was not enabled.
    """
    names = dict(task_names or {})
    chip.finish_accounting()
    rows: list[ProfileRow] = []
    for xy in tiles:
        t = chip.config.tile_index(xy)
        mine = {task: name for (where, task), name in names.items() if where == xy}
        own = (tile_models or {}).get(xy, model)
        rows += tile_rows(chip.cores, t, xy, chip.programs.get(t), chip.task_counters(xy), own, mine)
    noc = math.fsum(model.noc_pj(chip.noc_counters()).values())
    rows.append(ProfileRow(None, None, "", NOC_ROW, 0, 0, {}, noc))
    return FunctionProfile(rows, chip.clock_ns)


def core_profile(soc: SingleCoreSoC, model: EnergyModel, task_name: str = "program") -> FunctionProfile:
    """The profile of a single core run with profiling on (:meth:`SingleCoreSoC.enable_profile`),
    as tile (0, 0), task 0."""
    rows = tile_rows(soc.state, 0, (0, 0), soc.program, {0: soc.counters()}, model, {0: task_name})
    return FunctionProfile(rows, model.clock_ns)


def _task_rows(
    xy: tuple[int, int],
    task: int,
    name: str,
    execs: np.ndarray,
    extra: np.ndarray,
    table: _CodeTable,
    model: EnergyModel,
) -> list[ProfileRow]:
    valid = (table.function >= 0) & (execs > 0)
    if not valid.any():
        return []
    nf = len(table.functions)
    f = table.function[valid]
    e = execs[valid]
    x = extra[valid]
    by_class = np.zeros((nf, len(INSTRUCTION_CLASSES)), dtype=np.int64)
    np.add.at(by_class, (f, table.cls[valid]), e)
    stalls = np.zeros((nf, len(STALL_KINDS)), dtype=np.int64)
    fk = table.fixed_kind[valid]
    has = fk >= 0
    np.add.at(stalls, (f[has], fk[has]), (e * table.fixed[valid])[has])
    dk = table.dyn_kind[valid]
    has = dk >= 0
    np.add.at(stalls, (f[has], dk[has]), x[has])
    if (x[dk < 0] != 0).any():
        raise AssertionError("extra cycles on an instruction whose timing has none")
    rows = []
    for i in np.nonzero(by_class.any(axis=1))[0]:
        counts = {k: int(v) for k, v in zip(INSTRUCTION_CLASSES, by_class[i], strict=True)}
        counts.update({k: int(v) for k, v in zip(STALL_KINDS, stalls[i], strict=True)})
        instructions = int(by_class[i].sum())
        cycles = instructions + int(stalls[i].sum())
        energy = _energy(model, counts)
        rows.append(ProfileRow(xy, task, name, table.functions[i], cycles, instructions, counts, energy))
    return rows


def profile_totals(profile: FunctionProfile) -> dict[tuple[int, int] | None, dict[str, Any]]:
    """Per tile (and None: the NoC) the sums of its rows: cycles, instructions, counts, energy in pJ."""
    out: dict[tuple[int, int] | None, dict[str, Any]] = {}
    for r in profile.rows:
        t = out.setdefault(r.tile, {"cycles": 0, "instructions": 0, "counts": dict.fromkeys(COUNT_NAMES, 0),
                                    "parts_pj": []})  # fmt: skip
        t["cycles"] += r.cycles
        t["instructions"] += r.instructions
        for k, v in r.counts.items():
            t["counts"][k] += v
        t["parts_pj"].append(r.energy_pj)
    for t in out.values():
        t["energy_pj"] = math.fsum(t.pop("parts_pj"))
    return out


def summary_mismatches(profile: FunctionProfile, summary: Mapping[str, Any], rel: float = 1e-9) -> list[str]:
    """Where the profile's totals differ from a run's ``summary.json`` (its ``cycles`` object, if it
    has one, and its ``energy``): one sentence each, empty when they agree (energy to ``rel``, cycles
    exactly)."""
    data = profile.to_json()["totals"]
    out = []
    cycles = (summary.get("cycles") or {}).get("tiles")
    if cycles is not None:  # None: an older summary.json, without them
        for tile, value in cycles.items():
            got = data["cycles"].get(tile)
            if got != value:
                out.append(f"tile {tile}: {got} cycles in the profile, {value} in summary.json")
    energy = summary.get("energy") or {}
    pairs = [("total_uj", data["total_uj"], energy.get("total_uj")), ("noc_uj", data["noc_uj"], energy.get("noc_uj"))]
    pairs += [(f"tile {k}", data["tiles_uj"].get(k), v) for k, v in (energy.get("tiles_uj") or {}).items()]
    for label, got, want in pairs:
        if not isinstance(want, int | float) or got is None or not math.isclose(got, want, rel_tol=rel, abs_tol=1e-12):
            out.append(f"{label}: {got!r} uJ in the profile, {want!r} in summary.json")
    return out


__all__ = [
    "CSV_FIELDS",
    "OTHER_ROWS",
    "FunctionProfile",
    "ProfileRow",
    "chip_profile",
    "core_profile",
    "profile_totals",
    "summary_mismatches",
    "tile_rows",
]
