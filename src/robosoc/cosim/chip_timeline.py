"""What each core did when: task spans, interrupts, sleeps and NoC packets, from the chip's recorder.

The chip records a few events where it already does the work (:func:`robosoc.kernels.chip.record`,
switched on by :meth:`robosoc.chip.mpsoc.MPSoC.record_timeline`): every TASK_ID store (the
firmware writes it on every switch, docs/firmware-kernel.md), every SLEEP store, every packet sent
and every packet delivered, the I/O tile's included.  This module turns them into intervals:

* **task spans**: between two TASK_ID stores of a tile its cycles are the task's, exactly as the
  per-task counters charge them (the tests check the sums against ``MPSoC.task_counters``);
* **interrupts**: a TASK_ID store of the kernel (0) made in ``_irq_entry`` is an interrupt entry
  (a kernel call from a task writes 0 elsewhere; a voluntary switch writes it into the frame);
* **sleeps**: from the SLEEP store to the wake-up, which is the store's cycle plus what the sleep
  counter (carried by every TASK_ID and SLEEP event) grew by at the tile's next such event; a sleep
  still going at the end has no end;
* **packets**: each send paired with its delivery by destination and header flits 2, 3 and 5 (the
  kernel's source, port/fragment and sequence: unique per message fragment), in order.
"""

from __future__ import annotations

from collections import defaultdict, deque
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from robosoc.chip.mpsoc import MPSoC
from robosoc.host import images
from robosoc.kernels import chip as kc

Tile = tuple[int, int]

IRQ_ENTRY_SYMBOL = "_irq_entry"


@dataclass(frozen=True)
class TaskSpan:
    tile: Tile
    task: int  # TASK_ID
    start: int  # cycles [start, end)
    end: int
    interrupt: bool = False  # a kernel span entered by an interrupt


@dataclass(frozen=True)
class Sleep:
    tile: Tile
    start: int
    end: int | None  # None: still asleep when the recording ended


@dataclass(frozen=True)
class Packet:
    src: Tile
    dest: Tile
    sent: int  # the cycle its first flit starts leaving the sender
    flits: int
    first: int | None  # the cycle its first flit reached the receiver (None: not delivered yet)
    visible: int | None  # the cycle the receiver sees it (interrupt, NI_STATUS)


@dataclass
class ChipTimeline:
    tiles: list[Tile]
    io_tile: Tile
    spans: list[TaskSpan] = field(default_factory=list)
    sleeps: list[Sleep] = field(default_factory=list)
    packets: list[Packet] = field(default_factory=list)
    lost: int = 0  # events the recorder had no room for
    end_cycle: int = 0  # the chip's cycle when the timeline was taken


def timeline_of(
    chip: MPSoC,
    tiles: list[Tile] | None = None,
    symbolize: Callable[[Tile, int], str] | None = None,
) -> ChipTimeline:
    """The timeline the chip recorded so far (:meth:`MPSoC.record_timeline` must have been called
    before the chip ran).

    Args:
        chip: the chip.
        tiles: the core tiles to report (default: every core tile).
        symbolize: pc → symbol of a tile (default: the chip's loaded programs).

    Raises:
        ValueError: the chip is not recording.
    """
    if not chip.recording:
        raise ValueError("the chip is not recording its timeline (call MPSoC.record_timeline() before running it)")
    tiles = list(tiles) if tiles is not None else chip.core_tiles()
    symbolize = symbolize or chip.symbolize
    rows, lost = chip.timeline()
    config = chip.config
    io = config.io_tile
    out = ChipTimeline(tiles, (int(io[0]), int(io[1])), lost=lost, end_cycle=chip.cycle)
    ends = {xy: chip.tile_cycle(xy) for xy in tiles}
    index = {config.tile_index(xy): xy for xy in tiles}
    _spans_and_sleeps(rows, index, ends, symbolize, out)
    _packets(rows, config, out)
    return out


def _spans_and_sleeps(
    rows: np.ndarray,
    index: dict[int, Tile],
    ends: dict[Tile, int],
    symbolize: Callable[[Tile, int], str],
    out: ChipTimeline,
) -> None:
    mine = rows[np.isin(rows[:, 0], (kc.R_TASK, kc.R_SLEEP)) & np.isin(rows[:, 1], list(index))]
    by_tile: dict[int, list[np.ndarray]] = defaultdict(list)
    for row in mine[np.argsort(mine[:, 2], kind="stable")]:
        by_tile[int(row[1])].append(row)
    for t, xy in index.items():
        events = by_tile.get(t, [])
        start, task, interrupt = 0, None, False
        asleep: tuple[int, int] | None = None  # (from, sleep counter then)
        for row in events:
            kind, cycle, sleep_count = int(row[0]), int(row[2]), int(row[6])
            if asleep is not None and sleep_count > asleep[1]:
                out.sleeps.append(Sleep(xy, asleep[0], asleep[0] + sleep_count - asleep[1]))
                asleep = None
            if kind == kc.R_SLEEP:
                asleep = (cycle, sleep_count)
                continue
            new, old, pc = int(row[3]), int(row[4]), int(row[5])
            if task is None:
                task = old  # what ran from the start
            if cycle > start:
                out.spans.append(TaskSpan(xy, task, start, cycle, interrupt))
            start, task = cycle, new
            interrupt = new == images.KERNEL_TASK_ID and symbolize(xy, pc).split("+")[0] == IRQ_ENTRY_SYMBOL
        if asleep is not None:
            out.sleeps.append(Sleep(xy, asleep[0], None))
        end = ends[xy]
        if task is not None and end > start:
            out.spans.append(TaskSpan(xy, task, start, end, interrupt))


def _packets(rows: np.ndarray, config, out: ChipTimeline) -> None:
    sends = rows[rows[:, 0] == kc.R_SEND]
    delivered = rows[rows[:, 0] == kc.R_DELIVER]
    waiting: dict[tuple[int, ...], deque[np.ndarray]] = defaultdict(deque)
    for row in delivered[np.argsort(delivered[:, 2], kind="stable")]:
        waiting[(int(row[1]), int(row[5]), int(row[6]), int(row[7]))].append(row)
    for row in sends[np.argsort(sends[:, 2], kind="stable")]:
        flit0 = int(row[3])
        dest = ((flit0 >> 4) & 0xF, flit0 & 0xF)
        src = config.tile_xy(int(row[1]))
        key = (config.tile_index(dest), int(row[5]), int(row[6]), int(row[7]))
        match = waiting[key].popleft() if waiting[key] else None
        out.packets.append(
            Packet(
                src=(int(src[0]), int(src[1])), dest=dest, sent=int(row[2]), flits=int(row[4]),
                first=int(match[3]) if match is not None else None,
                visible=int(match[2]) if match is not None else None,
            )
        )  # fmt: skip


__all__ = ["IRQ_ENTRY_SYMBOL", "ChipTimeline", "Packet", "Sleep", "TaskSpan", "timeline_of"]
