"""The MPSoC: a mesh of HF-RISCV tiles, their network interfaces, the Hermes NoC and the I/O tile.

    chip = MPSoC(ChipConfig(width=2, height=2, powered_off=((1, 1),)))
    chip.load_all(load_elf("ping.elf", chip.regions()))       # or chip.load((x, y), program)
    result = chip.run(on_output=lambda tile, data: print(tile, data))

Everything runs in :func:`robosoc.kernels.chip.run_chip`; this class holds the arrays, loads
programs, talks to the I/O tile and turns counters into per-tile and per-task reports.
"""

from __future__ import annotations

import functools
import time
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from robosoc.chip.core_state import SRAM_BASE, CoreState
from robosoc.chip.counters import counters_dict
from robosoc.chip.engines import Engine, resolve_engine
from robosoc.chip.kernel_entry import KernelEntry
from robosoc.chip.single import (
    ERRATUM_WARNINGS,
    check_budget,
    check_pc,
    core_error,
    errata_counts,
    errata_report,
    exit_word,
)
from robosoc.chip.step_calls import StepCalls, run_calls
from robosoc.chip.translation import ChipTranslation
from robosoc.config.chip import MIN_PACKET_FLITS, ChipConfig
from robosoc.config.ranges import check_memory, format_bytes
from robosoc.isa.disasm import disassemble
from robosoc.isa.table import MEMORY_CYCLES
from robosoc.kernels import chip as kc
from robosoc.kernels import noc as nk
from robosoc.kernels import period_accounts
from robosoc.kernels.core_layout import (
    CTR_SIZE,
    ERRATA_MODES,
    OPC_SIZE,
    RUN_CHUNK,
    S_CYCLE,
    S_EXIT_CODE,
    S_MEM_SIZE,
    S_NI,
    S_PC,
    S_PROF_BASE,
    S_RUN,
)
from robosoc.kernels.period_accounts import sparse_rows
from robosoc.program.elf import Program, Region

XOUT_CAPACITY = 1 << 20
IO_ROWS = 4096
TIMELINE_ROWS = 1 << 14
"""Timeline events one :meth:`MPSoC.step` can hold (a 10 ms sample period of the flight firmware
makes about a hundred: its 1 ms tick wakes each core); more are counted as lost."""
TIMELINE_KEEP = 1 << 19
"""Timeline events kept in all (about a minute of the flight firmware on the seed's chip, 32 MB);
later ones are counted as lost, so a long flight's trace covers its beginning."""

NI_ERRORS = {
    kc.CE_WIDTH: "network-interface registers take word loads and stores only",
    kc.CE_UNKNOWN_REG: "no network-interface register at this address",
    kc.CE_SEND_BUSY: "SEND while the previous packet is still in the send memory (poll NI_STATUS bit 0 first)",
    kc.CE_NO_PACKET: "RECV with no packet waiting (poll NI_STATUS bit 1 or wait for the interrupt)",
    kc.CE_BAD_PACKET: "the packet cannot be sent",
    kc.CE_DMA_RANGE: "DMA address or size outside SRAM (or odd address)",
    kc.CE_TASK_RANGE: f"task id out of range (0..{kc.NTASKS - 1})",
    kc.CE_BAD_COMMAND: "unknown NI_CMD value (1 = SEND, 2 = RECV)",
    kc.CE_READONLY: "store to a read-only network-interface register",
}


TILE_STATES = {kc.K_OFF: "off", kc.K_RUN: "running", kc.K_SLEEP: "sleeping", kc.K_EXITED: "exited",
               kc.K_FAULT: "failed", kc.K_IO: "io"}  # fmt: skip


class ChipError(RuntimeError):
    """A tile failed, or the chip cannot make progress; the message names the tile."""

    def __init__(self, message: str, tile: tuple[int, int] | None) -> None:
        super().__init__(message)
        self.tile = tile


@dataclass
class ChipResult:
    cycles: int
    #: per tile that exited, its exit word, unsigned (0..0xffffffff)
    exit_codes: dict[tuple[int, int], int]
    output: dict[tuple[int, int], bytes]
    host_seconds: float
    io_received: list[tuple[int, list[int]]] = field(default_factory=list)
    #: per tile, how many times each RTL erratum was hit ("spec" mode: would have been)
    errata: dict[tuple[int, int], dict[str, int]] = field(default_factory=dict)
    warnings: list[str] = field(default_factory=list)


def account_counters(row: np.ndarray) -> dict[str, int]:
    """The counters by name of one accounting row (``acc[tile, task]``, the kernels' A_* layout)."""
    c = counters_dict(row[kc.A_CTR : kc.A_CTR + CTR_SIZE], row[:OPC_SIZE], int(row[kc.A_CYCLES]))
    c["sleep_cycle"] = int(row[kc.A_SLEEP])
    c["dma_cycle"] = int(row[kc.A_DMA])
    return c


@functools.cache
def account_counter_map() -> tuple[tuple[str, ...], np.ndarray]:
    """The names of :func:`account_counters` and the integer matrix M with ``M @ row`` their values:
    every counter is a sum of the row's entries times whole numbers (classes, stall cycles per
    operation), so the counters of a difference of rows are the difference of their counters and a
    flight's per-period counters are one matrix product (``tests/chip/test_chip_totals.py``)."""
    basis = np.eye(kc.ACC_SIZE, dtype=np.int64)
    columns = [account_counters(basis[j]) for j in range(kc.ACC_SIZE)]
    names = tuple(columns[0])
    return names, np.array([[c[name] for c in columns] for name in names], dtype=np.int64)


@functools.cache
def _account_counter_rows() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`account_counter_map`'s matrix as the period close takes it (sparse, row by row)."""
    return sparse_rows(account_counter_map()[1])


class MPSoC:
    """A mesh of tiles built from a :class:`ChipConfig`."""

    def __init__(self, config: ChipConfig, lockstep: bool = False, engine: str | Engine | None = None) -> None:
        """Build the chip.

        Args:
            config: the validated platform configuration.
            lockstep: advance everything one cycle at a time instead of in quanta (slow; the
                results must be identical, which the tests use to check the quantum scheme).
            engine: an engine or its name (:func:`robosoc.chip.engines.resolve_engine`): "interp"
                (every core on the interpreter), "jit" (each core translates a region at its first
                arrival) or "auto" (each core translates the regions that turn hot);
                every engine gives the same cycles, counters, outputs and errors
                (docs/translation.md).  Default: the configuration's ``engine``.
        """
        self.engine = resolve_engine(config.engine if engine is None else engine)
        self.config = config
        #: per tile, 1 if its router is switched off (:meth:`ChipConfig.routers_off`), else 0
        self._routers_off = np.zeros(config.n_tiles, np.int64)
        for xy in config.routers_off():
            self._routers_off[config.tile_index(xy)] = 1
        #: the chip's clock, the NoC's and every cycle count's unit; a tile's core may run at a whole
        #: fraction of it (ChipConfig.tile_divider, docs/power.md "Per-tile clock")
        self.clock_ns = config.tile.clock_period_ns
        n = config.n_tiles
        sizes = [config.tile_config(config.tile_xy(t)).sram_bytes for t in range(n)]
        check_memory("sram_bytes", n * max(sizes), f"{n} tiles x {format_bytes(max(sizes))} of SRAM")
        muls = [config.tile_config(config.tile_xy(t)).multiplier for t in range(n)]
        self.cores = CoreState.new(
            mul=muls, sram_size=max(sizes), base=SRAM_BASE, tiles=n, errata=ERRATA_MODES[config.errata], code_size=0
        )
        for t, size in enumerate(sizes):
            self.cores.st[t, S_MEM_SIZE] = size
        self.cores.st[:, S_NI] = 1
        powered = np.array([config.is_powered(config.tile_xy(t)) for t in range(n)], dtype=bool)
        noc = config.noc
        self.noc = nk.noc_alloc(
            config.width, config.height, noc.buffer_depth, noc.routing_latency, noc.max_packet_flits,
            noc.flit_bits, powered, event_capacity=4 * n + 64, queue_rows=IO_ROWS, arbiter=noc.arbiter,
            gate_after=noc.gate_after, wake_cycles=noc.wake_cycles,
        )  # fmt: skip
        self.io = config.tile_index(config.io_tile)
        self.noc.tile[self.io, nk.T_RX_AUTO] = 0  # the outside world takes packets as they come
        self.cst = np.zeros((n, kc.CST_SIZE), dtype=np.int64)
        self.cst[:, kc.K_WAKE] = nk.BIG
        self.cst[:, kc.K_RX_READY] = nk.BIG
        self.cst[:, kc.K_RX_FREE_AT] = nk.BIG
        self.cst[self.io, kc.K_STATE] = kc.K_IO
        self.cst[:, kc.K_DIV] = [config.tile_divider(config.tile_xy(t)) for t in range(n)]
        self.powered = powered
        self.acc = np.zeros((n, kc.NTASKS, kc.ACC_SIZE), dtype=np.int64)
        # touched here, not at the first accounting: a large zeroed array is mapped lazily (and numpy
        # asks for huge pages), so its first touch inside a run would cost up to tens of ms there
        self.acc.fill(0)
        self.snap = np.zeros((n, kc.ACC_SIZE), dtype=np.int64)
        self.gst = np.zeros(kc.GST_SIZE, dtype=np.int64)
        self.gst[kc.G_IO_TILE] = self.io
        # quanta (docs/noc.md, "Lookahead and the chip's time quanta"): a SEND store starting in s
        # injects from s + 3 + n (n >= MIN_PACKET_FLITS, the DMA) and a RECV frees the receive memory
        # from s + 3 + n; a packet sent into an idle network needs at least m cycles per router, so over
        # one hop its last flit is written in s + 3 + n + 2m + n - 1 at the earliest and the receiver
        # sees it (interrupt, NI_STATUS) from the cycle after.
        m = nk.min_router_cycles(int(self.noc.cfg[nk.C_ARBITER]), noc.routing_latency)
        self.gst[kc.G_LOOK_IDLE] = 1 if lockstep else MEMORY_CYCLES + 2 * MIN_PACKET_FLITS + 2 * m
        self.gst[kc.G_LOOK_ACTIVE] = 1 if lockstep else MEMORY_CYCLES + MIN_PACKET_FLITS
        self.gst[kc.G_LOOK_SINGLE] = 1 if lockstep else kc.SINGLE_QUANTUM
        self.xout = np.zeros((n, XOUT_CAPACITY), dtype=np.uint8)
        self.io_out = np.zeros((IO_ROWS, kc.IO_COLS), dtype=np.int64)
        self._work = np.zeros((kc.WORK_ROWS, n), dtype=np.int64)
        self.programs: dict[int, Program] = {}
        self._queue_next = 0
        self._reachable: set[tuple[int, int]] = set()  # destinations inject has checked
        self._io_received: list[tuple[int, list[int]]] = []
        self.rec = np.zeros((0, kc.REC_COLS), dtype=np.int64)
        self._timeline: list[np.ndarray | tuple[int, ...]] = []  # rows of events, or one event (the I/O tile's)
        self._timeline_room = 0
        self._timeline_dropped = 0
        # translated code (engine jit or auto): per tile its translator, created at the first step
        self._jit = ChipTranslation(n, self.engine)
        self._book = kc.ChipBook(self.cst, self.acc, self.snap, self.gst, self.xout, self.io_out, self.rec, self._work)
        # the kernels called at every step and period close, typed once (chip/kernel_entry.py)
        self._run_chip = KernelEntry(kc, "run_chip")
        self._bad_pcs = KernelEntry(kc, "bad_pcs")
        self._close_accounts = KernelEntry(period_accounts, "close_accounts")

    # --- the timeline recorder -------------------------------------------------------------
    def record_timeline(self, rows: int = TIMELINE_ROWS, keep: int = TIMELINE_KEEP) -> None:
        """From now on, record timeline events (kc.R_*: TASK_ID stores, sleeps, packets sent and
        delivered, the I/O tile's included) for :meth:`timeline`; ``rows`` is the buffer per step,
        ``keep`` the most events kept."""
        self.rec = np.zeros((rows, kc.REC_COLS), dtype=np.int64)
        self._timeline_room = keep

    @property
    def recording(self) -> bool:
        return self.rec.shape[0] > 0

    def timeline(self) -> tuple[np.ndarray, int]:
        """The events recorded so far (rows of kc.REC_COLS, in the order recorded) and how many were lost."""
        parts = [np.array([part], dtype=np.int64) if isinstance(part, tuple) else part for part in self._timeline]
        rows = np.concatenate(parts) if parts else np.zeros((0, kc.REC_COLS), dtype=np.int64)
        return rows, int(self.gst[kc.G_REC_LOST]) + self._timeline_dropped

    def _keep(self, rows: np.ndarray) -> None:
        kept = rows[: self._timeline_room]
        if len(kept):
            self._timeline.append(kept.copy())
        self._timeline_room -= len(kept)
        self._timeline_dropped += len(rows) - len(kept)

    def _keep_event(self, event: tuple[int, ...]) -> None:
        """:meth:`_keep` of one event (kept as a tuple until :meth:`timeline`: an array per event
        cost a flight's step some microseconds)."""
        if self._timeline_room > 0:
            self._timeline.append(event)
            self._timeline_room -= 1
        else:
            self._timeline_dropped += 1

    def _drain_rec(self) -> None:
        n = int(self.gst[kc.G_REC_COUNT])
        if n:
            self._keep(self.rec[:n])
            self.gst[kc.G_REC_COUNT] = 0

    # --- geometry --------------------------------------------------------------------------
    def regions(self, xy: tuple[int, int] | None = None) -> list[Region]:
        t = 0 if xy is None else self.config.tile_index(xy)
        return [Region(SRAM_BASE, int(self.cores.st[t, S_MEM_SIZE]), "SRAM")]

    def core_tiles(self) -> list[tuple[int, int]]:
        """Tiles with a powered core (every tile but the I/O tile and powered-off ones)."""
        return [self.config.tile_xy(t) for t in range(self.config.n_tiles) if self.powered[t] and t != self.io]

    @property
    def cycle(self) -> int:
        return int(self.gst[kc.G_TIME])

    # --- loading ---------------------------------------------------------------------------
    def load(self, xy: tuple[int, int], program: Program) -> None:
        """Load ``program`` into tile ``xy`` and make its core runnable."""
        if not self.config.contains(xy):
            raise ValueError(f"tile {xy} is outside the {self.config.width}x{self.config.height} mesh")
        t = self.config.tile_index(xy)
        if t == self.io:
            raise ValueError(f"tile {xy} is the I/O tile: it has no core to load")
        if not self.powered[t]:
            raise ValueError(f"tile {xy} is powered off: it cannot run a program")
        self.cores.set_code_size(program.code_end(SRAM_BASE), tile=t)
        for addr, data in program.segments:
            self.cores.write(addr, data, tile=t)
        self.cores.st[t, S_PC] = program.entry
        self.programs[t] = program
        self._jit.forget(t)
        check_pc(self.cores, t, program.symbolize, f"tile {xy}: entry point: ")
        self.cst[t, kc.K_STATE] = kc.K_RUN

    def load_all(self, program: Program) -> None:
        """The same program on every core tile (it tells tiles apart by reading NI_TILE)."""
        for xy in self.core_tiles():
            self.load(xy, program)

    # --- the I/O tile ----------------------------------------------------------------------
    def inject(self, dest: tuple[int, int], payload: Sequence[int] | np.ndarray, at_cycle: int) -> None:
        """Send a packet from the I/O tile to ``dest`` (payload: 16-bit flits, a sequence or an int
        array) leaving at ``at_cycle``."""
        if at_cycle < self.gst[kc.G_TIME]:
            raise ValueError(f"at_cycle {at_cycle} is in the past (the chip is at cycle {self.cycle})")
        x, y = dest
        if (x, y) not in self._reachable:
            if not self.config.contains(dest):
                raise ValueError(f"destination {dest} is outside the mesh")
            if not self.powered[self.config.tile_index(dest)]:
                raise ValueError(f"destination {dest} is powered off")
            self._reachable.add((x, y))
        if len(payload) + 2 > self.config.noc.max_packet_flits:
            raise ValueError(f"payload of {len(payload)} flits exceeds the maximum packet")
        if len(payload) + 2 < MIN_PACKET_FLITS:
            raise ValueError(
                f"payload of {len(payload)} flits: a packet needs at least {MIN_PACKET_FLITS - 2} payload flit "
                "(on the Hermes RTL a packet without payload swallows the next one)"
            )
        # The rows are a ring used in order and sent in order: the row IO_ROWS injections back is
        # free unless it is still the oldest one waiting (the queue's head) or being sent.
        row = self._queue_next % IO_ROWS
        io_tile = self.noc.tile[self.io]  # (a view: written through)
        if self._queue_next >= IO_ROWS and row in (io_tile[nk.T_Q_HEAD], io_tile[nk.T_SEND_ROW]):
            raise ValueError(f"too many injected packets pending ({IO_ROWS} not yet sent)")
        n = len(payload) + 2  # the flits: the destination, the size, the payload
        head = [nk.NONE] * nk.Q_FLITS  # the row's own columns, then its flits: one write
        head[nk.Q_TILE] = self.io
        head[nk.Q_READY] = at_cycle
        head[nk.Q_LEN] = n
        q = self.noc.queue[row]
        q[: nk.Q_FLITS + 2] = [*head, ((x << 4) | y) & 0xFFFF, n - 2]
        flits = np.asarray(payload)
        if flits.dtype != np.uint16:  # (16-bit flits, as images.io_packets makes them, need no mask)
            flits = np.asarray(payload, dtype=np.int64) & 0xFFFF
        q[nk.Q_FLITS + 2 : nk.Q_FLITS + n] = flits
        tail = io_tile[nk.T_Q_TAIL]
        if tail == nk.NONE:
            io_tile[nk.T_Q_HEAD] = row
        else:
            self.noc.queue[tail, nk.Q_NEXT] = row
            if io_tile[nk.T_Q_HEAD] == nk.NONE:
                io_tile[nk.T_Q_HEAD] = row
        io_tile[nk.T_Q_TAIL] = row
        self._queue_next += 1
        if self.rec.shape[0]:  # recording: the header flits 2, 3 and 5 as given
            head = [int(payload[k - 2]) if k < n else 0 for k in (2, 3, 5)]
            self._keep_event((kc.R_SEND, self.io, at_cycle, (x << 4) | y, n, *head))

    def received(self) -> list[tuple[int, list[int]]]:
        """Packets that reached the I/O tile since the last call: (cycle of the last flit, flits)."""
        out, self._io_received = self._io_received, []
        return out

    def _drain_io(self) -> None:
        n = int(self.gst[kc.G_IO_COUNT])
        for row in self.io_out[:n].tolist():  # Python ints, one conversion for the rows
            last, length, first = row[:3]
            flits = row[3 : 3 + length]
            self._io_received.append((last, flits))
            if self.recording:  # visible from the cycle after the last flit, as on a core tile
                head = [row[3 + k] for k in (2, 3, 5)]  # (a short packet: what the row holds there)
                self._keep_event((kc.R_DELIVER, self.io, last + 1, first, length, *head))
        self.gst[kc.G_IO_COUNT] = 0

    # --- running ---------------------------------------------------------------------------
    def book(self) -> kc.ChipBook:
        """The chip loop's own arrays, as the kernels take them: the same bundle until the timeline's
        buffer is replaced (:meth:`record_timeline`; the others are made once)."""
        if self._book.rec is not self.rec:
            self._book = self._book._replace(rec=self.rec)
        return self._book

    def step(self, until: int) -> int:
        """Advance the chip to ``until`` (or a host event); returns the CHIP_* reason.

        Raises:
            CoreError: a running tile's pc is not an instruction of its loaded code.
        """
        return run_calls(self.step_calls(until))

    def step_calls(self, until: int) -> StepCalls[int]:
        """:meth:`step` as the chip loop calls it makes (:mod:`robosoc.chip.step_calls`): yields
        each call, to be run (in any thread, while nothing else touches this chip) and sent back its
        status and host seconds; the step's Python runs here.  Its value is :meth:`step`'s."""
        # the awake and sleeping cores' pcs, all at once (a Python call per tile per step cost a
        # sleeping 16x16 chip a tenth of its run time); check_pc words the error of the first bad one
        bad = self._bad_pcs(self.cores.st, self.cst)
        for t in bad.tolist() if len(bad) else ():
            xy = self.config.tile_xy(t)
            check_pc(self.cores, t, functools.partial(self.symbolize, xy), f"tile {xy}: ")
        jit = self._jit
        while True:
            jit.prepare(self)
            # auto looks at the tiles that do not translate yet every jit.look_cycles()
            to = min(until, int(self.gst[kc.G_TIME]) + jit.look_cycles()) if jit.watching() else until
            while True:
                status, seconds = yield functools.partial(
                    self._run_chip, self.cores.arrays(), self.noc, self.book(), to, *jit.arguments()
                )
                jit.ran(seconds)
                if status != kc.CHIP_TRANSLATE:
                    break
                jit.translate(int(self.gst[kc.G_BREAK_TILE]))
            if status != kc.CHIP_UNTIL or self.gst[kc.G_TIME] >= until:
                break
        if self.gst[kc.G_IO_COUNT]:
            self._drain_io()
        if self.gst[kc.G_REC_COUNT]:
            self._drain_rec()
        return int(self.gst[kc.G_STATUS])

    def raise_failure(self, status: int) -> None:
        """Raise what a :meth:`step` that returned ``status`` met: a tile that failed.

        Raises:
            CoreError / ChipError: naming the tile, pc, symbol, instruction and address.
        """
        if status == kc.CHIP_ERROR:
            raise self._error()

    def drain_output(self) -> dict[tuple[int, int], bytes]:
        out = {}
        for t in range(self.config.n_tiles):
            m = int(self.cst[t, kc.K_OUT_LEN])
            if m:
                out[self.config.tile_xy(t)] = self.xout[t, :m].tobytes()
                self.cst[t, kc.K_OUT_LEN] = 0
        return out

    def run(
        self,
        max_cycles: int | None = None,
        on_output: Callable[[tuple[int, int], bytes], object] | None = None,
        chunk: int = 1 << 22,
        advance: Callable[[int], int] | None = None,
    ) -> ChipResult:
        """Run until every core has exited.

        Args:
            max_cycles: cycle budget, 1..2**62 (None: none).
            on_output: called with (tile, bytes) as output comes.
            chunk: cycles per kernel call (output and Ctrl-C are seen between calls).

        ``advance`` runs the chip to a cycle and returns the CHIP_* reason, in place of :meth:`step`:
        a debugger's (:meth:`robosoc.debug.GdbServer.advance`), which holds the whole chip while
        the debugged tile is halted and may return before the cycle.

        Raises:
            ValueError: ``max_cycles`` or ``chunk`` out of range.
            CoreError / ChipError: a tile failed (message names tile, pc, symbol, instruction),
                or the budget ran out, or every core waits for something that cannot come.
        """
        check_budget(max_cycles, chunk)
        outputs: dict[tuple[int, int], bytearray] = {}
        advance = advance or self.step
        start = time.perf_counter()
        while True:
            limit = self.cycle + chunk if max_cycles is None else min(self.cycle + chunk, max_cycles)
            why = advance(limit)
            for xy, data in self.drain_output().items():
                outputs.setdefault(xy, bytearray()).extend(data)
                if on_output is not None:
                    on_output(xy, data)
            if why == kc.CHIP_DONE:
                break
            if why == kc.CHIP_ERROR:
                raise self._error()
            if why == kc.CHIP_STUCK:
                raise ChipError(self._stuck_message(), None)
            if why == kc.CHIP_BREAK:
                xy = self.break_tile()
                pc = self.pc(xy)
                raise ChipError(f"tile {xy} stopped at a breakpoint at pc 0x{pc:08x} ({self.symbolize(xy, pc)})", xy)
            if max_cycles is not None and self.cycle >= max_cycles:
                raise ChipError(
                    f"cycle budget of {max_cycles} cycles exhausted; still running: "
                    + ", ".join(f"{xy} at pc 0x{self.pc(xy):08x} ({self.symbolize(xy, self.pc(xy))})"
                                for xy in self.core_tiles() if self.state(xy) in ("running", "sleeping")),
                    None,
                )  # fmt: skip
        self.finish_accounting()
        reports = {xy: self.errata_report(xy) for xy in self.core_tiles()}
        notes = [note for report in reports.values() for _, note in report.values()]
        if self.config.errata == "spec":
            for report in reports.values():
                for name, (_, note) in report.items():
                    warnings.warn(note, ERRATUM_WARNINGS[name], stacklevel=2)
        return ChipResult(
            cycles=self.cycle,
            exit_codes={xy: self.exit_code(xy) for xy in self.core_tiles() if self.state(xy) == "exited"},
            output={xy: bytes(v) for xy, v in outputs.items()},
            host_seconds=time.perf_counter() - start,
            io_received=self.received(),
            errata={xy: errata_counts(r) for xy, r in reports.items()},
            warnings=notes,
        )

    def errata_report(self, xy: tuple[int, int]) -> dict[str, tuple[int, str]]:
        """The RTL errata tile ``xy`` hit: name -> (count, sentence naming tile, pc and symbol)."""
        t = self.config.tile_index(xy)
        return errata_report(
            self.cores.st[t], lambda pc: self.symbolize(xy, pc), self.config.errata, where=f"tile {xy}: "
        )

    # --- debugging -------------------------------------------------------------------------
    def set_breakpoint(self, xy: tuple[int, int], addr: int, on: bool = True) -> None:
        """Stop the whole chip when tile ``xy`` is about to execute ``addr`` (``step`` returns CHIP_BREAK).

        Simulated time only moves while the chip runs, so stopping changes no cycle of anything.
        """
        self.cores.set_breakpoint(addr, on, tile=self.config.tile_index(xy))
        self._jit.stop(self.config.tile_index(xy))  # translated code does not see breakpoints

    def allow_long_quanta(self, on: bool) -> None:
        """Let cores deaf to the packet line run in long quanta (the default; ``docs/noc.md``).

        A debugger turns them off: a tile halted at a breakpoint inside a long quantum would leave
        the others far ahead of it, their output already printed.
        """
        self.gst[kc.G_LONG_OFF] = 0 if on else 1
        if not on:
            self._jit.stop_all()  # a debugger may write memory and set breakpoints: interpret

    def break_tile(self) -> tuple[int, int]:
        """The tile that stopped at a breakpoint (after ``step`` returned CHIP_BREAK)."""
        return self.config.tile_xy(int(self.gst[kc.G_BREAK_TILE]))

    def resume_from_break(self) -> None:
        """Let the stopped tile execute its instruction when the chip runs again.

        Clear or move the breakpoint first, or the tile stops at it again at once.  The next
        ``step`` continues the suspended quantum exactly where it stopped.
        """
        self.cores.st[self.config.tile_index(self.break_tile()), S_RUN] = RUN_CHUNK

    # --- inspection ------------------------------------------------------------------------
    def state(self, xy: tuple[int, int]) -> str:
        return TILE_STATES[int(self.cst[self.config.tile_index(xy), kc.K_STATE])]

    def pc(self, xy: tuple[int, int]) -> int:
        return int(self.cores.st[self.config.tile_index(xy), S_PC])

    def tile_cycle(self, xy: tuple[int, int]) -> int:
        """The chip cycle tile ``xy``'s core has reached (its own cycle times its divider)."""
        t = self.config.tile_index(xy)
        return int(self.cores.st[t, S_CYCLE]) * int(self.cst[t, kc.K_DIV])

    def divider(self, xy: tuple[int, int]) -> int:
        """How many chip cycles one core cycle of tile ``xy`` lasts (1: the chip's clock)."""
        return int(self.cst[self.config.tile_index(xy), kc.K_DIV])

    def regs(self, xy: tuple[int, int]) -> np.ndarray:
        return self.cores.regs[self.config.tile_index(xy), :32]

    def exit_code(self, xy: tuple[int, int]) -> int:
        """The exit word tile ``xy`` stored, unsigned (0..0xffffffff), as :attr:`RunResult.exit_code`."""
        return exit_word(self.cores.st[self.config.tile_index(xy), S_EXIT_CODE])

    def symbolize(self, xy: tuple[int, int], pc: int) -> str:
        program = self.programs.get(self.config.tile_index(xy))
        return program.symbolize(pc) if program else f"0x{pc:08x}"

    def counters(self, xy: tuple[int, int]) -> dict[str, int]:
        """Counters of one tile's core, with sleep and DMA cycles (in the core's own cycles)."""
        t = self.config.tile_index(xy)
        out = counters_dict(self.cores.ctr[t], self.cores.opc[t], int(self.cores.st[t, S_CYCLE]))
        out["sleep_cycle"] = int(self.cst[t, kc.K_SLEEP_CYCLES])
        out["dma_cycle"] = int(self.cst[t, kc.K_DMA_CYCLES])
        out["packets_sent"] = int(self.cst[t, kc.K_SENT])
        out["packets_received"] = int(self.cst[t, kc.K_RECEIVED])
        return out

    def finish_accounting(self) -> None:
        """Attribute everything not yet attributed to the tasks running now."""
        kc.account_all(self.cores.arrays(), self.book())

    def close_accounts(
        self, tiles: np.ndarray, tasks: np.ndarray, previous: np.ndarray, out: np.ndarray, routers: np.ndarray
    ) -> None:
        """:meth:`finish_accounting`, then the named counters (:func:`account_counter_map`'s order) of
        accounting rows ``acc[tiles[r], tasks[r]]`` since the rows ``previous[r]`` into ``out[r]``,
        the rows into ``previous``, and the routers' counters now into ``routers`` (for
        :meth:`noc_counters_of`): one call (:mod:`robosoc.kernels.period_accounts`)."""
        noc = self.noc
        self._close_accounts(
            self.cores.arrays(), self.book(), tiles, tasks, previous, *_account_counter_rows(), out,
            noc.cfg, noc.glob, noc.tile, noc.port, self._routers_off, routers,
        )  # fmt: skip

    def task_counters(self, xy: tuple[int, int]) -> dict[int, dict[str, int]]:
        """Counters per task id of one tile (task 0 is the kernel/idle), for tasks that ran."""
        t = self.config.tile_index(xy)
        return {task: account_counters(self.acc[t, task]) for task in range(kc.NTASKS) if self.acc[t, task].any()}

    def enable_profile(self) -> None:
        """Count every instruction per tile, task and word of code from here on (the exact profile,
        :mod:`robosoc.chip.function_profile`; load the programs first, enable it before the run)."""
        self.cores.enable_profile(kc.NTASKS)
        self._jit.stop_all()  # translated code does not count per word: the cores interpret from here on
        stride = self.cores.profile_stride
        for t in range(self.config.n_tiles):
            self.cores.st[t, S_PROF_BASE] += int(self.cst[t, kc.K_TASK]) * stride

    def noc_counters(self) -> dict[str, int]:
        """Router activity for the energy model (buffer-active and idle port cycles, flit hops) and
        ``rtl_lost_headers``: headers that found no room downstream in their crossing cycle, which
        robosoc lets wait but the Hermes RTL would have lost (docs/noc.md)."""
        counts = np.empty(len(nk.ROUTER_COUNTS), np.int64)
        nk.router_counts(self.noc.cfg, self.noc.glob, self.noc.tile, self.noc.port, self._routers_off, counts)
        return self.noc_counters_of(counts)

    def noc_counters_of(self, counts: np.ndarray) -> dict[str, Any]:
        """:meth:`noc_counters` from the routers' counters as :func:`robosoc.kernels.noc.router_counts`
        gave them (at any moment of this chip's run): Python ints, or for a stack of such rows an
        array of each counter (row by row the same integers)."""
        columns = counts.T if counts.ndim == 2 else counts.tolist()
        cycles, busy_ports, busy, gated, wakeups, hops, injected, delivered, lost = columns
        n = self.config.n_tiles
        off = int(self._routers_off.sum())
        extra = {"router_off_cycles": cycles * off} if off else {}  # never busy, never counted as gated
        return {
            "router_cycles": cycles * n,
            "router_busy_cycles": busy,
            "router_gated_cycles": gated,
            "router_wakeups": wakeups,
            "port_busy_cycles": busy_ports,
            "port_idle_cycles": cycles * n * nk.NPORTS - busy_ports,
            "flit_hops": hops,
            "flits_injected": injected,
            "packets_delivered": delivered,
            "rtl_lost_headers": lost,
            **extra,
        }

    # --- errors ----------------------------------------------------------------------------
    def _error(self) -> Exception:
        t = int(self.gst[kc.G_ERR_TILE])
        if t < 0:
            code = int(self.noc.glob[nk.G_STATUS])
            et = int(self.noc.glob[nk.G_ERR_TILE])
            where = self.config.tile_xy(et) if et >= 0 else None
            return ChipError(f"network error at cycle {int(self.noc.glob[nk.G_ERR_CYCLE])}, tile {where}: "
                             f"{nk.STATUS_TEXT.get(code, code)}", where)  # fmt: skip
        xy = self.config.tile_xy(t)
        st = self.cores.st[t]
        pc = int(st[S_PC])
        code = int(self.cst[t, kc.K_ERR])
        if code != kc.CE_NONE:
            text = NI_ERRORS.get(code, f"network-interface error {code}")
            if code == kc.CE_BAD_PACKET:
                status = int(self.cst[t, kc.K_ERR_INFO])
                text += f": {nk.STATUS_TEXT.get(status, '?')}"
                if status == nk.STATUS_SHORT_PACKET:
                    text += f" (SEND_SIZE = {int(self.cst[t, kc.K_SEND_SIZE])})"
                else:
                    dest = int(self.cores.m16[t, (int(self.cst[t, kc.K_SEND_ADDR]) - SRAM_BASE) // 2])
                    text += f" (destination flit 0x{dest:02x} = tile ({dest >> 4}, {dest & 15}))"
            word = int(self.cores.m32[t, (pc - SRAM_BASE) // 4]) & 0xFFFFFFFF
            addr = int(self.cst[t, kc.K_ERR_ADDR])
            return ChipError(
                f"tile {xy}: {text} at address 0x{addr:08x}, pc 0x{pc:08x} ({self.symbolize(xy, pc)}): "
                f"instruction 0x{word:08x} `{disassemble(word, pc)}`, cycle {int(st[S_CYCLE])}",
                xy,
            )
        return core_error(st, lambda pc: self.symbolize(xy, pc), int(st[S_MEM_SIZE]), where=f"tile {xy}: ")

    def _stuck_message(self) -> str:
        waiting = []
        for xy in self.core_tiles():
            t = self.config.tile_index(xy)
            if self.cst[t, kc.K_STATE] == kc.K_SLEEP:
                waiting.append(f"{xy} sleeps at pc 0x{self.pc(xy):08x} ({self.symbolize(xy, self.pc(xy))})")
        return (
            f"no tile can make progress at cycle {self.cycle}: "
            + "; ".join(waiting)
            + " with no interrupt due and no packet on the way"
        )
