"""Telemetry: named values a firmware publishes to the logs, read from the chip's memory by the host.

A project declares them (``[[telemetry]]`` in its robosoc.toml: a name, the task, a C variable
with members and an element, and a type); :func:`resolve_telemetry` finds each one's address in the
built ELF through its symbol table and DWARF debug information, and :class:`TelemetryReader` reads
them from the simulated memory.  A host read costs the chip no cycle and changes nothing in it.

When: at the close of each sensor period (:class:`robosoc.cosim.firmware_run.FirmwareRun`), the
values of every task that has no job active then (the kernel's ``job_active`` flag in its task
table, read the same way), so a value is never half updated; a task mid-job keeps its previous
values until a later close.

Names: the flight log's estimate columns (``est_qw``, ``est_qx``, ``est_qy``, ``est_qz``,
``est_height``; ``est_vz`` for the vertical speed) are filled from the telemetry of those names,
the way the quadrotor project's estimate reaches ``flight.csv``; any other name becomes a
column of its own after the flight log's columns.
"""

from __future__ import annotations

import math
import struct
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from robosoc.cache import dwarf_dir
from robosoc.config.firmware import FirmwareConfig
from robosoc.config.project import TelemetrySpec
from robosoc.control.flight import ROW_FIELDS
from robosoc.control.host import Estimate
from robosoc.host.task_table import TaskTable
from robosoc.physics.frames import euler_angles
from robosoc.program.dwarf import debug_index
from robosoc.program.elf import ElfError, load_elf
from robosoc.records import POWER_FIELDS
from robosoc.toolchain.errors import ToolchainError

if TYPE_CHECKING:
    from robosoc.chip.mpsoc import MPSoC

__all__ = [
    "ESTIMATE_HEIGHT",
    "ESTIMATE_NAMES",
    "ESTIMATE_QUATERNION",
    "ESTIMATE_VERTICAL_SPEED",
    "TelemetryError",
    "TelemetryProbe",
    "TelemetryReader",
    "declared_names",
    "estimate_of",
    "own_columns",
    "own_names",
    "resolve_telemetry",
]

Tile = tuple[int, int]
VALUE_BYTES = 4
"""Every telemetry type is one 32-bit word."""
ESTIMATE_QUATERNION = ("est_qw", "est_qx", "est_qy", "est_qz")
"""Telemetry names of the estimated attitude quaternion (w, x, y, z): the flight log's columns."""
ESTIMATE_HEIGHT = "est_height"
ESTIMATE_VERTICAL_SPEED = "est_vz"
ESTIMATE_NAMES = (*ESTIMATE_QUATERNION, ESTIMATE_HEIGHT, ESTIMATE_VERTICAL_SPEED)
"""Telemetry names that fill the flight log's estimate columns rather than columns of their own."""
_TAKEN = frozenset((*ROW_FIELDS, *POWER_FIELDS)) - frozenset(ESTIMATE_NAMES)
"""Names a telemetry value cannot have: the flight log's other columns (its own would repeat one)."""
_Q16 = 1.0 / 65536.0
#: struct code and scale of each type (``real`` by the build's arithmetic)
_DECODE: dict[str, tuple[str, float]] = {
    "f32": ("<f", 1.0), "q16": ("<i", _Q16), "i32": ("<i", 1.0), "u32": ("<I", 1.0)
}  # fmt: skip
_LAYOUT = {code: struct.Struct(code) for code, _ in _DECODE.values()}
_F32_CODE, _U32_CODE = _DECODE["f32"][0], _DECODE["u32"][0]


class TelemetryError(ToolchainError):
    """A declared telemetry value is not in the built program (a build error: the project file
    and its key are named)."""

    def __init__(self, where: str, key: str, reason: str) -> None:
        super().__init__(f"{where}: {key}: {reason}" if where else f"{key}: {reason}")


@dataclass(frozen=True)
class TelemetryProbe:
    """Where one telemetry value lies on the chip, how to decode it, and its task (TASK_ID in the
    kernel's table, whose job flag says when the value may be read)."""

    name: str
    tile: Tile
    address: int
    code: str  # struct format of the word
    scale: float  # value = word * scale
    task_id: int
    table: TaskTable

    def read(self, chip: MPSoC, tile: int) -> float:
        """The value now on the chip (a host read, no cycle), ``tile`` the index of :attr:`tile`."""
        return self.value_in(chip.cores.m8, tile, chip.cores.offset(self.address, VALUE_BYTES, tile))

    def value_in(self, memory: np.ndarray, tile: int, offset: int) -> float:
        """The value whose word is at ``offset`` of tile ``tile``'s row of ``memory`` (the tiles'
        bytes, :attr:`robosoc.chip.core_state.CoreState.m8`)."""
        (value,) = _LAYOUT[self.code].unpack_from(memory[tile], offset)
        return float(value) * self.scale


def resolve_telemetry(
    specs: Sequence[TelemetrySpec],
    elf: Path,
    arith: str,
    tiles: Mapping[str, tuple[Tile, int]],
    where: str = "",
) -> tuple[TelemetryProbe, ...]:
    """The probes of ``specs`` in ``elf`` (built with real_t ``arith``), each on the tile of its task
    (``tiles``: task name -> (tile, TASK_ID there)).

    Raises:
        TelemetryError: a value that is not in the ELF (no such variable or member, an index past the
            array's end, not a 32-bit word), naming ``where`` (the project file) and the key.
    """
    if not specs:
        return ()
    program = load_elf(elf)
    table = TaskTable.of(elf)
    index = debug_index(elf, dwarf_dir())
    out = []
    for i, spec in enumerate(specs):
        if spec.name in _TAKEN:
            raise TelemetryError(
                where, f"telemetry[{i}].name", f"{spec.name!r} is a column of flight.csv already: choose another name"
            )
        key = f"telemetry[{i}].value"
        try:
            offset, size = index.variable_field(spec.variable, spec.member)
            base = program.address_of(spec.variable)
        except ElfError as exc:
            reason = str(exc).removeprefix(f"{elf}: ")  # the cached ELF's path says nothing to the author
            raise TelemetryError(where, key, f"{spec.value!r}: {reason}") from None
        if size < VALUE_BYTES * (spec.index + 1):
            raise TelemetryError(
                where, key, f"{spec.value!r} is {size} bytes: not a 32-bit value (or its index is past the end)"
            )
        if size != VALUE_BYTES and "[" not in spec.value:
            raise TelemetryError(where, key, f"{spec.value!r} is {size} bytes: name a 32-bit member or give an [index]")
        kind = spec.type if spec.type != "real" else ("q16" if arith == "fixed" else "f32")
        code, scale = _DECODE[kind]
        address = base + offset + VALUE_BYTES * spec.index
        tile, task_id = tiles[spec.task]
        out.append(TelemetryProbe(spec.name, tile, address, code, scale, task_id, table))
    return tuple(out)


class TelemetryReader:
    """Reads the values of ``probes`` from ``chip``'s memory: those whose task has no job active now
    (the others are not read: their job may be half-way through updating them).  Each task's tile
    index and each probe's place in its memory are looked up once: a flight reads at every sample
    period's close, every task's flags in one read of the tiles' bytes and every value in one of
    their words.

    Raises:
        ValueError: a probe's word, or a task's table, is outside its tile's SRAM.
    """

    def __init__(self, chip: MPSoC, probes: Sequence[TelemetryProbe]) -> None:
        self.chip = chip
        cores = chip.cores
        tasks = list(dict.fromkeys((probe.tile, probe.task_id, probe.table) for probe in probes))
        #: per (tile, task): the task id, and where its table's ids start in the flags read
        self._tasks: list[tuple[int, int, int]] = []
        flag_tiles: list[int] = []
        flag_places: list[int] = []
        for tile, task_id, table in tasks:
            t = chip.config.tile_index(tile)
            ids, active = table.flag_offsets(cores, t)
            self._tasks.append((task_id, len(flag_places), len(ids)))
            flag_tiles += [t] * (len(ids) + len(active))
            flag_places += ids + active
        # (places in the tiles' memory as one flat array: one gather per read)
        row = cores.m8.shape[1]
        self._flags = np.array(flag_tiles, dtype=np.intp) * row + np.array(flag_places, dtype=np.intp)
        #: per probe, in order: its name, its task's place in _tasks, its word's decoding and scale
        self._values: list[tuple[str, int, str, float]] = []
        word_tiles, offsets = [], []
        for p in probes:
            task = tasks.index((p.tile, p.task_id, p.table))
            t = chip.config.tile_index(p.tile)
            self._values.append((p.name, task, p.code, p.scale))
            word_tiles.append(t)
            offsets.append(cores.offset(p.address, VALUE_BYTES, t))
        #: where the words lie in cores.m32 (None: one is not word-aligned, read each on its own)
        self._words = (
            (np.array(word_tiles, dtype=np.intp) * row + np.array(offsets, dtype=np.intp)) // VALUE_BYTES
            if all(o % VALUE_BYTES == 0 for o in offsets)
            else None
        )
        self._probes = [(p, t, o) for p, t, o in zip(probes, word_tiles, offsets, strict=True)]

    def read(self) -> dict[str, float]:
        """The values readable now, by name, in the probes' order."""
        cores = self.chip.cores
        flags = cores.m8.reshape(-1)[self._flags].tolist()
        quiet = []
        for task_id, start, n in self._tasks:
            ids = flags[start : start + n]
            # a task the table does not hold counts as active: nothing consistent to read of it
            quiet.append(task_id in ids and flags[start + n + ids.index(task_id)] == 0)
        values: dict[str, float] = {}
        if self._words is None:
            for (probe, t, offset), (name, task, _, _) in zip(self._probes, self._values, strict=True):
                if quiet[task]:
                    values[name] = probe.value_in(cores.m8, t, offset)
            return values
        words = cores.m32.reshape(-1)[self._words]
        signed, reals = words.tolist(), words.view(np.float32).tolist()
        for i, (name, task, code, scale) in enumerate(self._values):
            if quiet[task]:
                word = reals[i] if code == _F32_CODE else signed[i] & 0xFFFFFFFF if code == _U32_CODE else signed[i]
                values[name] = float(word) * scale
        return values


def own_columns(names: Sequence[str]) -> tuple[str, ...]:
    """The telemetry ``names`` that are columns of their own (not the estimate's), in their order."""
    return tuple(name for name in names if name not in ESTIMATE_NAMES)


def own_names(probes: Sequence[TelemetryProbe]) -> tuple[str, ...]:
    """The names of ``probes`` that are columns of their own (not the estimate's), in their order."""
    return own_columns([p.name for p in probes])


def declared_names(fw: FirmwareConfig) -> tuple[str, ...]:
    """Every telemetry name ``fw``'s project declares, in its order: what its firmware publishes,
    known from the project file without a build (the physics side of the decoupled mode and the
    ROS node, which have no chip).

    Raises:
        ConfigError: the project file is missing or wrong.
        ValueError: no such project folder.
    """
    return tuple(spec.name for spec in fw.load_project().telemetry)


def estimate_of(values: Mapping[str, float]) -> Estimate:
    """The state estimate that telemetry ``values`` publish (NaN for what they do not name: the
    Euler angles too, unless the whole quaternion is known)."""
    q = [float(values.get(name, math.nan)) for name in ESTIMATE_QUATERNION]
    # (from Python floats, in one array: a flight takes an estimate per sample)
    euler = euler_angles(*q) if not any(map(math.isnan, q)) else (math.nan,) * 3
    both = np.array([*q, *euler])
    height = values.get(ESTIMATE_HEIGHT, math.nan)
    return Estimate(both[:4], both[4:], height, values.get(ESTIMATE_VERTICAL_SPEED, math.nan))
