"""One side's UDP endpoint of the decoupled mode: a socket, fault injection, counters and a log.

:class:`UdpLink` sends data datagrams (sensor batches, actuator commands) numbered 0, 1, 2 ...
through an optional :class:`~robosoc.cosim.link_faults.FaultInjector`, and control datagrams
(hello, bye) as they are.  :meth:`UdpLink.receive` waits up to a timeout, then takes every
datagram that is there; it never raises for what arrives: bad datagrams are classified, counted
(:class:`~robosoc.cosim.link_counters.ReceiveCounts`) and logged, datagrams from anyone but the
peer are logged and dropped, socket errors are logged and counted.  The log is a text file, one
line per event, flushed line by line.
"""

from __future__ import annotations

import errno
import ipaddress
import select
import socket
import time
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Protocol

import numpy as np

from robosoc.config.link import LinkFaults
from robosoc.cosim.datagram import (
    Body,
    Bye,
    CommandBatch,
    Datagram,
    Hello,
    Kind,
    Rejected,
    SensorBatch,
    TelemetryBatch,
    decode,
    encode,
)
from robosoc.cosim.link_counters import Arrival, ReceiveCounts
from robosoc.cosim.link_faults import FaultInjector
from robosoc.output_files import open_in_place

__all__ = ["MAX_LINES_PER_KIND", "Address", "ChipTransport", "LinkError", "LinkLog", "UdpLink", "parse_address"]

#: Stream of the run's seed that drives each direction's faults ("one seed drives every random number").
FAULT_STREAM = {"physics": 0x5EED_0001, "chip": 0x5EED_0002}
RECEIVE_BUFFER_BYTES = 1 << 20
RECEIVE_BYTES = 65536  # a whole UDP datagram, so that an oversized one is classified by its real length


class LinkError(Exception):
    """The link cannot be set up (address in use, cannot be resolved, not local): the message says why."""


@dataclass(frozen=True)
class Address:
    """A UDP address as the user wrote it: host (IPv4, IPv6 or a name) and port."""

    host: str
    port: int

    def __str__(self) -> str:
        return f"[{self.host}]:{self.port}" if ":" in self.host else f"{self.host}:{self.port}"


def parse_address(text: str, *, any_port: bool) -> Address:
    """``"127.0.0.1:5600"``, ``"[::1]:5600"``, ``"localhost:5600"`` -> :class:`Address`.

    ``any_port`` allows port 0 (bind to any free port).

    Raises:
        ValueError: not HOST:PORT, or the port is out of range.
    """
    host, colon, port_text = text.strip().rpartition(":")
    if not colon or not host:
        raise ValueError(f"expected HOST:PORT such as 127.0.0.1:5600, got {text!r}")
    if host.startswith("[") and host.endswith("]"):
        host = host[1:-1]
    elif ":" in host:
        raise ValueError(f"write an IPv6 address in brackets, [::1]:5600, got {text!r}")
    if not host or any(c.isspace() for c in host):
        raise ValueError(f"expected HOST:PORT such as 127.0.0.1:5600, got {text!r}")
    if not port_text.isdigit():
        raise ValueError(f"the port must be a number, got {text!r}")
    port = int(port_text)
    lo = 0 if any_port else 1
    if not lo <= port <= 65535:
        raise ValueError(f"the port must be between {lo} and 65535, got {text!r}")
    return Address(host, port)


def resolve(address: Address) -> tuple[int, tuple]:
    """(address family, socket address) of ``address``.

    Raises:
        LinkError: the host cannot be resolved.
    """
    try:
        ipaddress.ip_address(address.host)
        flags: int = socket.AI_NUMERICHOST
    except ValueError:
        flags = 0
    try:
        infos = socket.getaddrinfo(address.host, address.port, type=socket.SOCK_DGRAM, flags=flags)
    except (socket.gaierror, UnicodeError) as exc:
        raise LinkError(f"{address}: cannot resolve the host ({exc})") from None
    family, _, _, _, sockaddr = infos[0]
    return family, sockaddr


MAX_LINES_PER_KIND = 100
"""Lines a link log gives each kind of repeated event (a rejected datagram, a gap, a hello sent ...):
after that they are only counted, and the count is the log's last line for that kind.  A peer (or
anyone) sending garbage at line rate cannot fill the disk."""


class LinkLog:
    """The side's log file (or nothing): ``<seconds since start> <event>`` per line, flushed.

    Events of a ``kind`` (the per-datagram ones) get at most ``per_kind`` lines; the rest are
    counted, said once when the limit is reached and totalled when the log is closed.
    """

    def __init__(self, path: Path | None, per_kind: int = MAX_LINES_PER_KIND) -> None:
        self.path = path
        self._file: IO[str] | None = open_in_place(path, "w", encoding="utf-8") if path is not None else None
        self._start = time.monotonic()
        self.per_kind = per_kind
        self.lines: dict[str, int] = {}
        self.suppressed: dict[str, int] = {}

    def write(self, event: str, kind: str | None = None) -> None:
        if self._file is None or self._file.closed:
            return
        if kind is not None:
            seen = self.lines.get(kind, 0) + 1
            self.lines[kind] = seen
            if seen > self.per_kind:
                self.suppressed[kind] = self.suppressed.get(kind, 0) + 1
                return
            if seen == self.per_kind:
                event += f" (the {self.per_kind}th '{kind}' line: further ones are counted, not logged)"
        self._file.write(f"{time.monotonic() - self._start:10.4f} {event}\n")
        self._file.flush()

    def close(self) -> None:
        if self._file is not None and not self._file.closed:
            for kind, count in self.suppressed.items():
                self.write(f"{kind}: {count} more not logged")
            self._file.close()


def _describe(body: Body) -> str:
    if isinstance(body, SensorBatch):
        return f"sensors k={[r.k for r in body.readings]}"
    if isinstance(body, CommandBatch):
        return f"commands seq={[c.seq for c in body.commands]} chip_now={body.chip_now_ns} ns"
    if isinstance(body, TelemetryBatch):
        return f"telemetry k={[e.k for e in body.entries]}"
    if isinstance(body, Hello):
        return f"hello period={body.sample_period_ns} ns telemetry={list(body.telemetry)}"
    assert isinstance(body, Bye)
    return f"bye {body.reason.name.lower()} data_sent={body.data_sent} end={body.end_ns} ns"


class ChipTransport(Protocol):
    """What the chip side (:func:`robosoc.cosim.decoupled_chip.serve_chip`) needs of its link to the
    physics: :class:`UdpLink`, or the ROS 1 node's (:class:`robosoc.cosim.ros_chip.RosChipLink`)."""

    sent: int

    def receive(self, timeout: float) -> list[Datagram]: ...
    def send_data(self, body: CommandBatch | TelemetryBatch) -> None: ...
    def send_control(self, body: Hello | Bye) -> None: ...
    def silent_for(self, now: float) -> float: ...
    def report(self) -> dict[str, object]: ...
    def close(self) -> None: ...


class UdpLink:
    """One side's socket (``side``: "physics" or "chip").

    Args:
        bind: where to listen (port 0: any free port; :attr:`address` says which).
        side: names the side in the log and picks its fault stream.
        faults, seed: faults to inject on data datagrams sent, seeded by the run's seed.
        log: the side's log.
        peer: where to send (the physics side learns it from the chip's hello instead).

    Raises:
        LinkError: the address cannot be bound (in use, not local, cannot be resolved).
    """

    def __init__(
        self,
        bind: Address,
        side: str,
        faults: LinkFaults | None = None,
        seed: int = 0,
        log: LinkLog | None = None,
        peer: Address | None = None,
    ) -> None:
        self.side = side
        self.log = log or LinkLog(None)
        family, sockaddr = resolve(bind)
        self.peer: tuple | None = None
        if peer is not None:
            peer_family, self.peer = resolve(peer)
            if peer_family != family:
                raise LinkError(f"{bind} and {peer} are of different address families (IPv4 and IPv6)")
        self.sock = socket.socket(family, socket.SOCK_DGRAM)
        try:
            self.sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, RECEIVE_BUFFER_BYTES)
            self.sock.bind(sockaddr)
        except OSError as exc:
            self.sock.close()
            if exc.errno == errno.EADDRINUSE:
                raise LinkError(
                    f"{bind}: the address is in use (another robosoc serve, or pick another port)"
                ) from None
            if exc.errno == errno.EADDRNOTAVAIL:
                raise LinkError(f"{bind}: not an address of this machine") from None
            if exc.errno == errno.EACCES:
                raise LinkError(f"{bind}: permission denied (ports below 1024 need privileges)") from None
            raise LinkError(f"{bind}: cannot bind ({exc.strerror or exc})") from None
        self.sock.setblocking(False)
        host, port = self.sock.getsockname()[:2]
        self.address = Address(host, port)
        self.injector = FaultInjector(faults or LinkFaults(), np.random.default_rng([seed, FAULT_STREAM[side]]))
        self.counts = ReceiveCounts()
        self.sent = 0
        self.send_errors = 0
        self.receive_errors = 0
        self.foreign = 0
        self.last_heard: float | None = None  # time.monotonic() of the peer's last valid datagram
        self.log.write(f"{side}: listening on {self.address}" + (f", peer {peer}" if peer else ""))
        if faults is not None and faults.any:
            self.log.write(f"{side}: injecting faults on what it sends: {faults.as_dict()}")

    # --- sending ------------------------------------------------------------------------------

    def _sendto(self, data: bytes) -> None:
        if self.peer is None:
            return
        try:
            self.sock.sendto(data, self.peer)
        except OSError as exc:  # the peer's port closed (ICMP), buffer full, network down: keep going
            self.send_errors += 1
            self.log.write(f"send error: {exc}", "send error")

    def send_data(self, body: SensorBatch | CommandBatch | TelemetryBatch) -> None:
        """Send ``body`` as the next data datagram, through the fault injector."""
        datagram = encode(body, self.sent)
        self.sent += 1
        for wire in self.injector.plan(datagram):
            self._sendto(wire)

    def send_control(self, body: Hello | Bye) -> None:
        """Send a hello or bye (never faulted); a bye first sends a datagram still held back."""
        if isinstance(body, Bye):
            for wire in self.injector.flush():
                self._sendto(wire)
        self._sendto(encode(body))
        self.log.write(f"sent {_describe(body)}", f"sent {type(body).__name__.lower()}")

    # --- receiving ----------------------------------------------------------------------------

    def receive(self, timeout: float) -> list[Datagram]:
        """Wait up to ``timeout`` s for datagrams; every valid, new one that is there (in arrival order)."""
        try:
            ready, _, _ = select.select([self.sock], [], [], max(0.0, timeout))
        except (OSError, ValueError) as exc:
            self.receive_errors += 1
            self.log.write(f"receive error: {exc}", "receive error")
            return []
        out: list[Datagram] = []
        while ready:
            try:
                data, source = self.sock.recvfrom(RECEIVE_BYTES)
            except BlockingIOError:
                break
            except OSError as exc:  # e.g. ECONNREFUSED after an ICMP port unreachable
                self.receive_errors += 1
                self.log.write(f"receive error: {exc}", "receive error")
                break
            item = self._take(data, source)
            if item is not None:
                out.append(item)
        return out

    def _take(self, data: bytes, source: tuple) -> Datagram | None:
        if self.peer is not None and source[:2] != self.peer[:2]:
            self.foreign += 1
            self.log.write(f"dropped {len(data)} bytes from {source[0]}:{source[1]}, not the peer", "foreign")
            return None
        result = decode(data)
        if isinstance(result, Rejected):
            self.counts.reject(result.reason)
            self.log.write(f"rejected {result.size} bytes: {result.reason.value}: {result.detail}", "rejected")
            return None
        if self.peer is None:
            if result.kind is not Kind.HELLO:
                self.foreign += 1
                self.log.write(
                    f"dropped {_describe(result.body)} from {source[0]}:{source[1]} before any hello", "foreign"
                )
                return None
            self.peer = source
            self.log.write(f"peer is {source[0]}:{source[1]}")
        self.last_heard = time.monotonic()
        if result.kind in (Kind.HELLO, Kind.BYE):
            if isinstance(result.body, Bye):
                self.counts.announced = result.body.data_sent
                tail = result.body.data_sent - self.counts.highest - 1
                if tail > 0:
                    self.log.write(
                        f"lost {tail} datagram(s) at the end: #{self.counts.highest + 1}..#{result.body.data_sent - 1}"
                    )
            self.log.write(f"received {_describe(result.body)}", f"received {type(result.body).__name__.lower()}")
            return result
        arrival, gap = self.counts.arrive(result.seq)
        if gap:
            self.log.write(f"lost {gap} datagram(s): #{result.seq - gap}..#{result.seq - 1}", "lost")
        if arrival == Arrival.DUPLICATE:
            self.log.write(f"duplicate #{result.seq} dropped", "duplicate")
            return None
        if arrival == Arrival.LATE:
            self.log.write(f"#{result.seq} arrived late (after #{self.counts.highest})", "late")
        return result

    def report(self) -> dict[str, object]:
        """The side's part of ``"link"``: what it sent (``to_PEER``), what it received (``from_PEER``)."""
        peer = "chip" if self.side == "physics" else "physics"
        return {
            f"to_{peer}": {
                "sent": self.sent,
                "injected": dict(self.injector.injected),
                "send_errors": self.send_errors,
            },
            f"from_{peer}": self.counts.as_dict(),
            "foreign": self.foreign,
            "receive_errors": self.receive_errors,
        }

    def silent_for(self, now: float) -> float:
        """Seconds since the peer's last valid datagram (since ``now`` if never heard)."""
        return now - self.last_heard if self.last_heard is not None else 0.0

    def close(self) -> None:
        """Close the socket (sending a datagram still held back first)."""
        for wire in self.injector.flush():
            self._sendto(wire)
        self.sock.close()
