"""The GDB stub: GDB's packets in, a simulated core that only moves when GDB lets it.

The server is driven by the simulation's own run loop: :meth:`GdbServer.advance` stands in for
the loop's step function (``SingleCoreSoC.step_until`` or ``MPSoC.step``), so a run loop, or a
flight loop that advances chip and physics in turns, debugs without changing shape::

    server = GdbServer(ChipTarget(chip, (1, 0)), Listener(port))
    with server:
        chip.run(advance=server.advance)          # or, in a flight loop: server.advance(until)

While the core is halted, ``advance`` blocks serving GDB, so nothing in the simulation (the other
tiles, the network, the physics of a flight loop) moves.  When it stops at a breakpoint it first
returns to its caller, which drains the program's output, and serves GDB on the next call.

Packets (docs/debugging.md has the list): registers, memory, Z0-Z4/z0-z4, c/s/C/S, ``?``, D,
k/vKill, qSupported (PacketSize), qXfer:features:read (the RV32 target description),
QStartNoAckMode, qRcmd (``monitor``), thread queries for the single thread.  Unknown packets
get the empty reply, malformed ones ``E01``; nothing a client sends can stop the simulation
except ``k``.
"""

from __future__ import annotations

import contextlib
import signal
import time
from collections import deque
from collections.abc import Callable
from enum import Enum
from types import TracebackType

from robosoc.debug.points import WATCH_KEYWORDS, Kind, Points
from robosoc.debug.rsp import MAX_PAYLOAD, Interrupt, Oversized, Packet, escape_binary, unescape_binary
from robosoc.debug.target import MemoryRefused, Outcome, Progress, Target
from robosoc.debug.tdesc import NUM_REGS, target_xml
from robosoc.debug.transport import Connection, Disconnected, Listener

#: Error replies (GDB only shows that an error happened; docs/debugging.md lists them).
E_MALFORMED = b"E01"  # a packet whose arguments do not parse
E_TOO_LONG = b"E02"  # a packet longer than PacketSize
E_MEMORY = b"E03"  # no memory at the address
E_REFUSED = b"E04"  # a write to device registers
E_NOT_CODE = b"E05"  # a breakpoint that is not on an instruction of the loaded code
#: The answer to a second GDB while one is connected (GDB shows the text after "E.").
SECOND_GDB_REPLY = b"E.robosoc: another GDB is debugging this core already; one GDB at a time"

THREAD = 1
#: seconds between looks at the socket for Ctrl-C while the core runs
POLL_SECONDS = 0.05

MONITOR_HELP = """\
monitor cycles   the core's cycle (and, on the MPSoC, the chip's time)
monitor task     the task id the tile runs (TASK_ID)
monitor tile     which core is being debugged
"""


class DebuggerKill(KeyboardInterrupt):
    """GDB killed the program: the run ends the way Ctrl-C ends it."""


class _Phase(Enum):
    STEP = "step"  # the target executes the instruction the core was resumed at
    RUN = "run"  # the target runs to the next marked instruction


class GdbServer:
    """A GDB remote stub for one :class:`~robosoc.debug.target.Target`."""

    def __init__(self, target: Target, listener: Listener, log: Callable[[str], object] | None = None) -> None:
        self.target = target
        self.listener = listener
        self.points = Points()
        self._log = log or (lambda _: None)
        self._conn: Connection | None = None
        self._attached = True  # False after detach, exit or a lost connection: advance() just runs
        self._halted = True  # the core waits for GDB (it does before its first instruction)
        self._pending: bytes | None = None  # a stop reply to send when the caller calls again
        self._last_stop = self._signal_reply(signal.SIGTRAP)
        self._resume_step = False  # GDB asked for a single step (not a continue)
        self._phase = _Phase.RUN
        self._failure: Progress | None = None  # the run ended in a failure GDB is looking at
        self._early: deque[Packet | Oversized] = deque()  # packets that came while the core ran
        self._gdb_features: set[str] = set()
        self._last_poll = 0.0

    # --- lifetime ----------------------------------------------------------------------------
    @property
    def port(self) -> int:
        return self.listener.port

    def __enter__(self) -> GdbServer:
        return self

    def __exit__(self, kind: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None) -> None:
        self.close()

    def close(self) -> None:
        """End the session: GDB, if it still waits for the core, hears that the program is gone."""
        gdb_waits = not self._halted or self._pending is not None  # for a stop reply
        if self._conn is not None and not self._conn.closed and self._attached and gdb_waits:
            with contextlib.suppress(Disconnected):
                self._conn.send(b"X%02x" % signal.SIGKILL)
        self._end()
        self.listener.close()

    def _end(self) -> None:
        """No more debugging: marks gone, connection closed; advance() only runs from now on."""
        if self._attached:
            self.target.cancel_step()
            self.points.clear()
            self._apply_marks()
        self._attached = False
        if self._conn is not None:
            self._conn.close()

    # --- the run loop's step -----------------------------------------------------------------
    def advance(self, until: int) -> int:
        """Advance the simulation towards ``until`` like the simulator's step function; returns its status.

        Blocks while GDB holds the core.  Returns early (with a "go on" status) when the core has
        just stopped, so that the caller drains the output before GDB hears of the stop.
        """
        if self._attached and self._conn is None:
            self._accept()
        while self._attached:
            if self._halted:
                self._serve()
                continue
            now = self.target.now()
            progress = self.target.run(min(until, now + self.target.slice_cycles))
            outcome = progress.outcome
            if outcome == Outcome.STOPPED:
                if self._stopped_here():
                    return progress.status
            elif outcome == Outcome.EXITED:
                self._send(b"W%02x" % (self.target.exit_code & 0xFF))
                self._log(f"the program exited with code {self.target.exit_code}; GDB detached")
                self._end()
                return progress.status
            elif outcome == Outcome.FAILED:
                self._fail(progress)
                return progress.status
            elif outcome == Outcome.HOST or self.target.now() >= until:
                if self._poll(force=False):
                    self._interrupted()
                return progress.status
            if self._poll(force=outcome == Outcome.SLICE):
                self._interrupted()
                return progress.status
        return self.target.run(until).status

    def _interrupted(self) -> None:
        """GDB's Ctrl-C: the core halts where it is (a step it was in is forgotten)."""
        self.target.cancel_step()
        self._halt(self._signal_reply(signal.SIGINT))

    def _accept(self) -> None:
        self._log(f"waiting for GDB on {self.listener.host}:{self.port}")
        try:
            self._conn = self.listener.accept()
        except OSError as exc:
            self._log(f"no GDB connection ({exc}): running without the debugger")
            self._attached = False
            return
        self._log("GDB connected; the core waits before its first instruction")
        self.listener.refuse_others(
            SECOND_GDB_REPLY, lambda peer: self._log(f"refused a second GDB connection from {peer}: one at a time")
        )

    def _halt(self, reply: bytes) -> None:
        """The core stops here; GDB hears it on the next call (after the caller drained the output)."""
        self._halted = True
        self._pending = reply
        self._last_stop = reply

    def _fail(self, progress: Progress) -> None:
        """The run cannot go on: let GDB look at the core, then tell it the program is gone."""
        self.target.cancel_step()
        sig = self.target.failure_signal(progress.status)
        self._failure = progress
        self._halt(self._signal_reply(sig))
        while self._attached and self._halted:
            self._serve()
        if self._attached:
            self._send(b"X%02x" % sig)
            self._end()

    def _stopped_here(self) -> bool:
        """The core is before an instruction it has not executed; True when it halts there for GDB."""
        pc = self.target.pc
        if self._phase == _Phase.STEP and self._resume_step:
            self._halt(self._signal_reply(signal.SIGTRAP))
            return True
        if pc in self.points.breaks:
            why = "swbreak" if self.points.breaks[pc] == Kind.SOFTWARE else "hwbreak"
            self._halt(self._signal_reply(signal.SIGTRAP, f"{why}:" if f"{why}+" in self._gdb_features else ""))
            return True
        if self._watch_stop():
            return True
        if self.target.is_marked(pc):  # a load or store a watchpoint looked at: execute it
            self.target.start_step()
            self._phase = _Phase.STEP
        else:
            self._apply_marks()  # the program may have stored over a mark since
            self._phase = _Phase.RUN
        return False

    def _watch_stop(self) -> bool:
        """Halt if the instruction at pc is about to make an access a watchpoint watches."""
        word = self.target.word(self.target.pc)
        hit = None if word is None else self.points.watch_hit(word, self.target.cores.regs[self.target.t])
        if hit is None:
            return False
        kind, addr = hit
        self._halt(self._signal_reply(signal.SIGTRAP, f"{WATCH_KEYWORDS[kind]}:{addr:x}"))
        return True

    def _resume(self, step: bool) -> None:
        """GDB said continue or step: the core executes the instruction at pc, whatever marks it."""
        self._resume_step = step
        if self._failure is not None:
            self._halted = False  # nothing can run: _fail() tells GDB the program is gone
            return
        if self._watch_stop():
            self._send_pending()
            return
        self._apply_marks()
        self.target.start_step()
        self._phase = _Phase.STEP
        self._halted = False

    def _apply_marks(self) -> None:
        target = self.target
        target.apply_marks(self.points.marks(target.code_words(), target.code_base))

    def _poll(self, force: bool) -> bool:
        """Look for GDB's Ctrl-C (at most every POLL_SECONDS unless forced); True if it came."""
        now = time.monotonic()
        if not force and now - self._last_poll < POLL_SECONDS:
            return False
        self._last_poll = now
        assert self._conn is not None
        try:
            while (event := self._conn.receive(timeout=0)) is not None:
                if isinstance(event, Interrupt):
                    return True
                self._early.append(event)  # GDB sends nothing else while the core runs: keep it for later
        except Disconnected:
            self._log("GDB disconnected: the program runs on without the debugger")
            self._end()
        return False

    # --- serving GDB while the core is halted ----------------------------------------------
    def _serve(self) -> None:
        """Answer GDB until it resumes the core, detaches or goes away."""
        try:
            self._send_pending()
            while self._attached and self._halted:
                assert self._conn is not None
                event = self._early.popleft() if self._early else self._conn.receive()
                if isinstance(event, Interrupt):
                    continue  # already stopped
                if isinstance(event, Oversized):
                    self._send(E_TOO_LONG)
                    continue
                assert isinstance(event, Packet)
                reply = self._dispatch(event.payload)
                if reply is not None:
                    self._send(reply)
        except Disconnected:
            self._log("GDB disconnected: the program runs on without the debugger")
            self._end()

    def _send_pending(self) -> None:
        if self._pending is not None:
            reply, self._pending = self._pending, None
            self._send(reply)

    def _send(self, payload: bytes) -> None:
        if self._conn is not None and not self._conn.closed:
            self._conn.send(payload)

    @staticmethod
    def _signal_reply(sig: int, reason: str = "") -> bytes:
        """A stop reply; ``reason`` is one ``name:value`` pair (``swbreak:``, ``watch:40000010``)."""
        return f"T{int(sig):02x}thread:{THREAD:x};{reason + ';' if reason else ''}".encode()

    def _dispatch(self, payload: bytes) -> bytes | None:
        """The reply to one packet (None: no reply now)."""
        try:
            text = payload.decode("latin-1")
        except UnicodeDecodeError:  # pragma: no cover - latin-1 decodes every byte
            return E_MALFORMED
        if not text:
            return b""
        head = text[0]
        try:
            if head == "?":
                return self._last_stop
            if head == "g":
                return "".join(f"{v:08x}" for v in _swap_all(self.target.registers())).encode()
            if head == "G":
                return self._write_all_registers(text[1:])
            if head == "p":
                return self._read_register(text[1:])
            if head == "P":
                return self._write_register(text[1:])
            if head == "m":
                return self._read_memory(text[1:])
            if head == "M":
                return self._write_memory_hex(text[1:])
            if head == "X":
                return self._write_memory_binary(payload[1:])
            if head in "Zz":
                return self._point(text, insert=head == "Z")
            if head in "cCsS":
                return self._resume_packet(text)
            if head == "D":
                self._send(b"OK")
                self._log("GDB detached: the program runs on without the debugger")
                self._end()
                return None
            if head == "k":
                self._kill()
            if head == "H":
                return b"OK"
            if head == "T":
                return b"OK" if _hex(text[1:]) in (THREAD, -1, 0) else E_MALFORMED
            if head == "q":
                return self._query(text)
            if head == "Q":
                return self._set(text)
            if head == "v":
                return self._v_packet(text)
        except (ValueError, IndexError):
            return E_MALFORMED
        return b""

    def _kill(self) -> None:
        self._log("GDB killed the program")
        self._end()
        raise DebuggerKill("killed from GDB")

    def _resume_packet(self, text: str) -> bytes | None:
        head, args = text[0], text[1:]
        if head in "CS":
            sig, _, addr = args.partition(";")
            _hex(sig)  # the signal is checked and dropped: bare metal has no signals to deliver
        else:
            addr = args
        if addr:
            self.target.set_register(32, _hex(addr))
        self._resume(step=head in "sS")
        return None

    # registers
    def _read_register(self, args: str) -> bytes:
        n = _hex(args)
        if not 0 <= n < NUM_REGS:
            return E_MALFORMED
        return f"{_swap(self.target.registers()[n]):08x}".encode()

    def _write_register(self, args: str) -> bytes:
        n_text, value = args.split("=")
        n = _hex(n_text)
        if not 0 <= n < NUM_REGS or len(value) != 8:
            return E_MALFORMED
        self.target.set_register(n, _swap(_hex(value)))
        return b"OK"

    def _write_all_registers(self, data: str) -> bytes:
        if len(data) != 8 * NUM_REGS:
            return E_MALFORMED
        values = [_swap(_hex(data[8 * i : 8 * i + 8])) for i in range(NUM_REGS)]
        for n, value in enumerate(values):
            self.target.set_register(n, value)
        return b"OK"

    # memory
    def _read_memory(self, args: str) -> bytes:
        addr, length = _addr_length(args)
        data = self.target.read_memory(addr, min(length, MAX_PAYLOAD // 2))
        if not data and length:
            return E_MEMORY
        return data.hex().encode()

    def _write_memory_hex(self, args: str) -> bytes:
        where, _, data = args.partition(":")
        addr, length = _addr_length(where)
        if len(data) != 2 * length:
            return E_MALFORMED
        return self._write_memory(addr, bytes.fromhex(data))

    def _write_memory_binary(self, payload: bytes) -> bytes:
        where, sep, data = payload.partition(b":")
        if not sep:
            return E_MALFORMED
        addr, length = _addr_length(where.decode("latin-1"))
        raw = unescape_binary(data)
        if len(raw) != length:
            return E_MALFORMED
        return self._write_memory(addr, raw)

    def _write_memory(self, addr: int, data: bytes) -> bytes:
        try:
            self.target.write_memory(addr, data)
        except MemoryRefused:
            return E_REFUSED
        self._apply_marks()  # the write dropped the marks of the words it changed
        return b"OK"

    # breakpoints and watchpoints
    def _point(self, text: str, insert: bool) -> bytes:
        fields = text[1:].split(";")[0].split(",")
        if len(fields) != 3:
            return E_MALFORMED
        kind_n, addr, length = _hex(fields[0]), _hex(fields[1]), _hex(fields[2])
        if not 0 <= kind_n <= 4:
            return b""  # an unknown type: unsupported, as the protocol says
        kind = Kind(kind_n)
        if kind in (Kind.SOFTWARE, Kind.HARDWARE):
            if insert and not self.target.is_code(addr):
                return E_NOT_CODE
        elif length <= 0:
            return E_MALFORMED
        if insert:
            self.points.insert(kind, addr, length)
        else:
            self.points.remove(kind, addr, length)
        self._apply_marks()
        return b"OK"

    # queries
    def _query(self, text: str) -> bytes:
        name, _, args = text.partition(":")
        if name == "qSupported":
            self._gdb_features = set(args.split(";")) if args else set()
            return f"PacketSize={MAX_PAYLOAD:x};qXfer:features:read+;swbreak+;hwbreak+;QStartNoAckMode+".encode()
        if name == "qXfer" and args.startswith("features:read:"):
            return self._features(args.removeprefix("features:read:"))
        if text == "qAttached" or text.startswith("qAttached:"):
            return b"1"  # detach, not kill, when GDB quits
        if text == "qC":
            return f"QC{THREAD:x}".encode()
        if text == "qfThreadInfo":
            return f"m{THREAD:x}".encode()
        if text == "qsThreadInfo":
            return b"l"
        if text.startswith("qThreadExtraInfo,"):
            return self.target.description.encode().hex().encode()
        if text.startswith("qSymbol"):
            return b"OK"
        if text.startswith("qRcmd,"):
            return self._monitor(bytes.fromhex(text.removeprefix("qRcmd,")).decode("utf-8", "replace"))
        return b""

    def _features(self, args: str) -> bytes:
        annex, _, span = args.partition(":")
        offset, length = _addr_length(span)
        if annex != "target.xml":
            return b"E00"
        xml = target_xml().encode()
        chunk = xml[offset : offset + min(length, MAX_PAYLOAD // 2)]
        return (b"l" if offset + len(chunk) >= len(xml) else b"m") + escape_binary(chunk)

    def _monitor(self, command: str) -> bytes:
        words = command.split()
        name = words[0] if words else "help"
        if name == "cycles":
            text = self.target.monitor_cycles()
        elif name == "task":
            text = self.target.monitor_task()
        elif name == "tile":
            text = self.target.description
        elif name == "help":
            text = MONITOR_HELP.rstrip()
        else:
            text = f"unknown monitor command {name!r}; try: monitor help"
        return (text + "\n").encode().hex().encode()

    def _set(self, text: str) -> bytes | None:
        if text == "QStartNoAckMode":
            self._send(b"OK")  # still acknowledged by GDB; nothing after it is
            assert self._conn is not None
            self._conn.ack_mode = False
            return None
        return b""

    def _v_packet(self, text: str) -> bytes:
        if text.startswith("vKill"):
            self._send(b"OK")
            self._kill()
        return b""  # vCont, vRun, vFile, vMustReplyEmpty...: not supported


def _hex(text: str) -> int:
    """A hex number of at most 32 bits (ValueError otherwise)."""
    if not 0 < len(text) <= 8 or any(c not in "0123456789abcdefABCDEF" for c in text):
        raise ValueError(f"not a 32-bit hex number: {text!r}")
    return int(text, 16)


def _addr_length(text: str) -> tuple[int, int]:
    addr, length = text.split(",")
    return _hex(addr), _hex(length)


def _swap(value: int) -> int:
    """A 32-bit register value as GDB's hex (target byte order, little endian) reads it."""
    return int.from_bytes((value & 0xFFFFFFFF).to_bytes(4, "little"), "big")


def _swap_all(values: list[int]) -> list[int]:
    return [_swap(v) for v in values]
