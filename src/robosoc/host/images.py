"""Kernel images: build an application with the robosoc kernel, read its job log and statistics.

    elf = build(["app.c"], mul=False, defines={"OS_TICK_CYCLES": 65536})
    chip = MPSoC(ChipConfig(width=2, height=2))
    chip.load((1, 0), load_elf(elf, chip.regions()))
    chip.run()
    for job in read_job_log(chip, (1, 0)).records: ...

Messages to and from the I/O tile use the kernel's on-chip header (docs/firmware-kernel.md):
:func:`message_packets` turns a message into the payloads :meth:`MPSoC.inject` takes, and
:func:`parse_packet` / :func:`reassemble` turn what :meth:`MPSoC.received` returns into messages.
"""

from __future__ import annotations

import functools
import re
import struct
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, NamedTuple

import numpy as np

from robosoc.config.packet_layout import MAX_PACKET_FLITS, MESSAGE_HEADER_FLITS, NOC_HEADER_FLITS
from robosoc.firmware import KERNEL_DIR, PORT_DIR, kernel_runtime_sources
from robosoc.toolchain import DEFAULT_SRAM_SIZE, build_elf

if TYPE_CHECKING:
    from robosoc.chip.mpsoc import MPSoC

JOB_LOG_SYMBOL = "os_job_log"
STATS_SYMBOL = "os_stats"
JOBLOG_MAGIC = 0x4A4F4253
STATS_MAGIC = 0x4154534B
KERNEL_TASK_ID = 0
IDLE_TASK_ID = 1
FIRST_TASK_ID = 2
JOB_MET, JOB_EVENT, JOB_DEPLETED = 1, 2, 4

#: Message header: flits 0..5 (wire destination and size, then four flits of the kernel's own).
HEADER_FLITS = NOC_HEADER_FLITS + MESSAGE_HEADER_FLITS

#: os_job_record_t, field by field (its struct code)
_RECORD_FIELDS = (
    ("task", "B"), ("flags", "B"), ("job", "H"), ("release", "I"), ("deadline", "I"), ("start", "I"),
    ("completion", "I"), ("exec_cycles", "I"),
)  # fmt: skip
_RECORD = struct.Struct("<" + "".join(code for _, code in _RECORD_FIELDS))
#: the same record as a numpy structured type (a flight's records read as columns at its end)
JOB_RECORD_DTYPE = np.dtype([(name, "<" + {"B": "u1", "H": "u2", "I": "u4"}[code]) for name, code in _RECORD_FIELDS])
_LOG_HEADER = struct.Struct("<IIII")  # magic, capacity, count, tick_cycles
_STATS_FIELDS = (
    "magic", "tick_cycles", "start_cycle", "first_tick", "ticks", "ticks_late", "switches", "msg_sent",
    "msg_received", "pkt_sent", "pkt_received", "pkt_malformed", "msg_dropped", "reserved",
)  # fmt: skip
_STATS = struct.Struct("<" + "I" * (len(_STATS_FIELDS) + 32))


def build(
    app_sources: Sequence[Path | str],
    mul: bool = True,
    defines: Mapping[str, str | int | None] | None = None,
    opt: str = "-O2",
    include_dirs: Sequence[Path | str] = (),
    out: Path | str | None = None,
    sram_size: int | None = None,
) -> Path:
    """Compile an application with the kernel into an ELF for one MPSoC tile (cached).

    Args:
        app_sources: the application's .c/.S files (``main`` creates tasks and calls ``os_start``).
        mul: for the core with the iterative multiplier, or without.
        defines: kernel settings of ``kernel/os_config.h`` and the application's own.
        opt, include_dirs, out: as :func:`robosoc.toolchain.build_elf`.
        sram_size: the tile's SRAM (the stack starts at its top; default: the toolchain's, 2 MiB).

    Raises:
        CompileError: the compiler failed, or a kernel setting is invalid (its ``#error`` names it).
    """
    return build_elf(
        [*app_sources, *kernel_runtime_sources()],
        out=out,
        mul=mul,
        opt=opt,
        defines=dict(defines or {}),
        include_dirs=[*include_dirs, KERNEL_DIR, PORT_DIR],
        runtime=False,
        sram_size=sram_size if sram_size is not None else DEFAULT_SRAM_SIZE,  # build_elf's default
    )


# --- what the host reads from a tile ------------------------------------------------------------


@dataclass(frozen=True)
class JobRecord:
    """One completed job (``os_job_record_t``); cycles are TIMER0 values (32 bits, wrapping)."""

    task: int
    job: int
    release: int
    deadline: int
    start: int
    completion: int
    exec_cycles: int
    met: bool
    event: bool
    depleted: bool

    @property
    def response(self) -> int:
        """Cycles from release to completion."""
        return (self.completion - self.release) & 0xFFFFFFFF


@dataclass(frozen=True)
class JobLog:
    records: list[JobRecord]
    #: records overwritten in the ring before they were read (``count - capacity`` when positive)
    lost: int
    tick_cycles: int
    #: number (0, 1, 2 ... since boot) of ``records[0]``: ``first + len(records)`` jobs were logged
    first: int = 0


def _memory(chip: MPSoC, xy: tuple[int, int], symbol: str, size: int) -> bytes:
    t = chip.config.tile_index(xy)
    return chip.cores.read(_address(chip, xy, t, symbol), size, tile=t)


def _address(chip: MPSoC, xy: tuple[int, int], t: int, symbol: str) -> int:
    """The address of ``symbol`` in the program of tile ``xy`` (index ``t``).

    Raises:
        ValueError: the tile has no program, or its program no such symbol.
    """
    program = chip.programs.get(t)
    if program is None:
        raise ValueError(f"tile {xy} has no program loaded")
    try:
        return program.address_of(symbol)
    except ValueError as exc:
        raise ValueError(f"tile {xy}: {program.path} has no symbol {symbol} (not a kernel image?)") from exc


def _job_record(fields: tuple[int, ...]) -> JobRecord:
    """A record of the log as ``_RECORD`` unpacks it (``os_job_record_t``)."""
    task, flags, job, release, deadline, start, completion, exec_cycles = fields
    return JobRecord(task, job, release, deadline, start, completion, exec_cycles,
                     bool(flags & JOB_MET), bool(flags & JOB_EVENT), bool(flags & JOB_DEPLETED))  # fmt: skip


def read_job_log(chip: MPSoC, xy: tuple[int, int], since: int = 0) -> JobLog:
    """The job records of tile ``xy``, oldest first (the ring keeps the last ``capacity``); only
    those numbered ``since`` or later (a reader that has seen ``since`` records parses no more)."""
    magic, capacity, count, tick = _LOG_HEADER.unpack(_memory(chip, xy, JOB_LOG_SYMBOL, _LOG_HEADER.size))
    if magic != JOBLOG_MAGIC:
        raise ValueError(f"tile {xy}: the job log is not initialised (os_start has not run)")
    raw = _memory(chip, xy, JOB_LOG_SYMBOL, _LOG_HEADER.size + capacity * _RECORD.size)
    kept = min(count, capacity)
    records = []
    first = max(count - kept, min(since, count))
    for i in range(first, count):
        off = _LOG_HEADER.size + (i % capacity) * _RECORD.size
        records.append(_job_record(_RECORD.unpack_from(raw, off)))
    return JobLog(records, count - kept, tick, first)


class JobLogReader:
    """The new job records of tile ``xy``'s log, reading only its header and those records; the tile's
    index and the log's address are looked up once (a flight reads every tile's new records at each
    sample period's close).

    Raises:
        ValueError: the tile has no program, or its program no job log.
    """

    def __init__(self, chip: MPSoC, xy: tuple[int, int]) -> None:
        self.chip = chip
        self.xy = xy
        self.t = chip.config.tile_index(xy)
        self.address = _address(chip, xy, self.t, JOB_LOG_SYMBOL)
        self._header: int | None = None  # where the log's header lies in the tile's row of memory

    def new_records(self, seen: int) -> tuple[bytes, int]:
        """The bytes of the records logged after the first ``seen``, oldest first (parse them with
        :func:`job_record_columns`), and how many the tile has logged in all.

        Raises:
            ValueError: the log is not initialised, or the ring overwrote records after ``seen`` unread.
        """
        cores, t, xy = self.chip.cores, self.t, self.xy
        if self._header is None:
            self._header = cores.offset(self.address, _LOG_HEADER.size, t)
        magic, capacity, count, _ = _LOG_HEADER.unpack_from(cores.m8[t], self._header)
        if magic != JOBLOG_MAGIC:
            raise ValueError(f"tile {xy}: the job log is not initialised (os_start has not run)")
        if count - seen > capacity:
            raise ValueError(
                f"tile {xy}: the job log overflowed: {count - seen} new records, the ring keeps {capacity}"
            )
        if count <= seen:
            return b"", count
        ring = cores.offset(self.address + _LOG_HEADER.size, capacity * _RECORD.size, t)
        memory = cores.m8[t]
        first, last = seen % capacity, count % capacity or capacity
        if first < last:  # (the records in one piece of the ring)
            return memory[ring + first * _RECORD.size : ring + last * _RECORD.size].tobytes(), count
        return (
            memory[ring + first * _RECORD.size : ring + capacity * _RECORD.size].tobytes()
            + memory[ring : ring + last * _RECORD.size].tobytes()
        ), count


def job_record_columns(raw: bytes) -> np.ndarray:
    """The records in ``raw``, bytes of a log's records as :meth:`JobLogReader.new_records` gives
    them, as one structured array (:data:`JOB_RECORD_DTYPE`, a column per field of ``os_job_record_t``)."""
    return np.frombuffer(raw, dtype=JOB_RECORD_DTYPE)


@dataclass(frozen=True)
class KernelStats:
    """``os_stats`` of one tile (field meanings in ``kernel/os.h``)."""

    tick_cycles: int
    start_cycle: int
    first_tick: int
    ticks: int
    ticks_late: int
    switches: int
    msg_sent: int
    msg_received: int
    pkt_sent: int
    pkt_received: int
    pkt_malformed: int
    msg_dropped: int
    #: TASK_ID -> (jobs completed, deadline misses)
    tasks: dict[int, tuple[int, int]]

    def misses(self, task: int) -> int:
        return self.tasks.get(task, (0, 0))[1]

    def jobs(self, task: int) -> int:
        return self.tasks.get(task, (0, 0))[0]


def read_stats(chip: MPSoC, xy: tuple[int, int]) -> KernelStats:
    values = _STATS.unpack(_memory(chip, xy, STATS_SYMBOL, _STATS.size))
    named = dict(zip(_STATS_FIELDS, values, strict=False))
    if named["magic"] != STATS_MAGIC:
        raise ValueError(f"tile {xy}: the kernel statistics are not initialised (os_start has not run)")
    per_task = values[len(_STATS_FIELDS) :]
    tasks = {i: (per_task[2 * i], per_task[2 * i + 1]) for i in range(16) if per_task[2 * i] or per_task[2 * i + 1]}
    fields = {k: v for k, v in named.items() if k not in ("magic", "reserved")}
    return KernelStats(**fields, tasks=tasks)


# --- messages --------------------------------------------------------------------------------


def tile_address(xy: tuple[int, int]) -> int:
    """NoC address (x << 4) | y."""
    return (xy[0] << 4) | xy[1]


class Packet(NamedTuple):
    """A packet with the kernel's header, parsed (``dest`` and ``size`` are the wire flits; a named
    tuple: a flight parses a packet per sample, and a frozen dataclass takes four times as long to make)."""

    dest: int
    size: int
    src_tile: int
    src_port: int
    port: int
    frag: int
    length: int
    seq: int
    data: bytes


class Message(NamedTuple):
    """A message from a core to the I/O tile, reassembled from its packets."""

    src_tile: int
    src_port: int
    dest: int
    port: int
    seq: int
    data: bytes
    #: cycle the last packet reached the I/O tile
    cycle: int


def io_packets(data: bytes, port: int, io_tile: tuple[int, int], seq: int) -> list[np.ndarray]:
    """The payloads carrying one message from the I/O tile at ``io_tile`` to ``port`` (its source
    port the same), for :meth:`MPSoC.inject`: those of :func:`message_packets`, as arrays of 16-bit
    flits (a flight injects a sensor message per sample, and an array goes into the chip's queue at
    once)."""
    return [
        np.frombuffer(_flits_struct(len(header)).pack(*header) + chunk, dtype="<u2")
        for header, chunk in _message_parts(data, port, tile_address(io_tile), port, seq, MAX_PACKET_FLITS)
    ]


def message_packets(
    data: bytes,
    port: int,
    *,
    src_tile: int = 0,
    src_port: int = 0,
    seq: int = 0,
    max_flits: int = MAX_PACKET_FLITS,
) -> list[list[int]]:
    """Payloads (flits after the two wire flits) of the packets carrying one message.

    Pass each to :meth:`MPSoC.inject`; ``src_tile`` is normally the I/O tile's address.
    """
    return [
        header + list(_flits_struct(len(chunk) // 2).unpack(chunk))
        for header, chunk in _message_parts(data, port, src_tile, src_port, seq, max_flits)
    ]


def _message_parts(
    data: bytes, port: int, src_tile: int, src_port: int, seq: int, max_flits: int
) -> list[tuple[list[int], bytes]]:
    """Per packet of a message: the kernel's header flits and the data's bytes it carries (padded to
    whole flits).

    Raises:
        ValueError: a port or tile that is not one byte, a message too long, ``max_flits`` out of range.
    """
    if not 0 <= port <= 255 or not 0 <= src_port <= 255 or not 0 <= src_tile <= 255:
        raise ValueError("port, src_port and src_tile are one byte each")
    if len(data) > 0xFFFF:
        raise ValueError(f"a message holds at most 65535 bytes, got {len(data)}")
    if not HEADER_FLITS < max_flits <= MAX_PACKET_FLITS:
        raise ValueError(f"max_flits must be {HEADER_FLITS + 1}..{MAX_PACKET_FLITS}")
    per_packet = 2 * (max_flits - HEADER_FLITS)
    out = []
    frag = 0
    offset = 0
    while True:
        chunk = data[offset : offset + per_packet]
        header = [(src_tile << 8) | src_port, (port << 8) | (frag & 0xFF), len(data), seq & 0xFFFF]
        out.append((header, chunk + b"\0" * (len(chunk) & 1)))
        offset += len(chunk)
        frag += 1
        if offset >= len(data):
            return out


@functools.cache
def _flits_struct(count: int) -> struct.Struct:
    """The layout of ``count`` 16-bit flits, little-endian (made once per length: a flight packs a
    sensor packet and parses a PWM packet per sample)."""
    return struct.Struct(f"<{count}H")


def parse_packet(flits: Sequence[int]) -> Packet:
    """A whole packet (wire flits included, as :meth:`MPSoC.received` gives them)."""
    if len(flits) < HEADER_FLITS:
        raise ValueError(f"a kernel packet has at least {HEADER_FLITS} flits, got {len(flits)}")
    tail = flits[HEADER_FLITS:]
    layout = _flits_struct(len(tail))  # one pack: a third of a pack per flit
    try:
        body = layout.pack(*tail)  # (the chip's flits are 16-bit already)
    except struct.error:
        body = layout.pack(*[v & 0xFFFF for v in tail])
    return Packet(
        dest=flits[0], size=flits[1], src_tile=flits[2] >> 8, src_port=flits[2] & 0xFF, port=flits[3] >> 8,
        frag=flits[3] & 0xFF, length=flits[4], seq=flits[5], data=body,
    )  # fmt: skip


def reassemble(received: Iterable[tuple[int, Sequence[int]]]) -> list[Message]:
    """Messages from packets in arrival order (``MPSoC.received()``), per source tile in turn.

    Raises:
        ValueError: a packet out of turn or with the wrong number of data bytes.
    """
    pending: dict[int, tuple[Packet, bytearray]] = {}
    out = []
    for cycle, flits in received:
        p = parse_packet(flits)
        if p.frag == 0:
            if p.src_tile in pending:
                raise ValueError(f"packet from tile 0x{p.src_tile:02x}: new message before the last completed")
            if len(p.data) >= p.length:  # the whole message in one packet (a PWM command's, every sample)
                out.append(Message(p.src_tile, p.src_port, p.dest, p.port, p.seq, p.data[: p.length], cycle))
                continue
            head, buf = p, bytearray()
        else:
            if p.src_tile not in pending:
                raise ValueError(f"packet from tile 0x{p.src_tile:02x}: fragment {p.frag} without its first")
            head, buf = pending.pop(p.src_tile)
            if (p.seq, p.port, p.length) != (head.seq, head.port, head.length):
                raise ValueError(f"packet from tile 0x{p.src_tile:02x}: fragment of another message")
        buf += p.data[: head.length - len(buf)]
        if len(buf) >= head.length:
            out.append(Message(head.src_tile, head.src_port, head.dest, head.port, head.seq, bytes(buf), cycle))
        else:
            pending[p.src_tile] = (head, buf)
    return out


def c_header_constants() -> dict[str, int]:
    """Integer ``#define``s of ``kernel/os.h`` (the tests check the Python constants against them)."""
    out = {}
    for m in re.finditer(r"^#define\s+(OS_\w+)\s+\(?(-?(?:0x[0-9a-fA-F]+|\d+))u?\)?\s*(?:/\*.*)?$",
                         (KERNEL_DIR / "os.h").read_text(), re.M):  # fmt: skip
        out[m.group(1)] = int(m.group(2), 0)
    return out


__all__ = [
    "FIRST_TASK_ID",
    "HEADER_FLITS",
    "IDLE_TASK_ID",
    "JOB_LOG_SYMBOL",
    "JOB_MET",
    "JOB_RECORD_DTYPE",
    "KERNEL_TASK_ID",
    "STATS_SYMBOL",
    "JobLog",
    "JobLogReader",
    "JobRecord",
    "KernelStats",
    "Message",
    "Packet",
    "build",
    "c_header_constants",
    "job_record_columns",
    "message_packets",
    "parse_packet",
    "read_job_log",
    "read_stats",
    "reassemble",
    "tile_address",
]
