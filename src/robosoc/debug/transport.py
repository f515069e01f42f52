"""The TCP side of the GDB stub: a loopback listener and one connection with its acknowledgements.

The connection answers the protocol's acknowledgements itself (``+`` for a good packet, ``-`` for
a bad checksum, the last packet again on ``-``) until no-ack mode is switched on, so the server
above it only sees packets, oversized packets and interrupts.
"""

from __future__ import annotations

import contextlib
import errno
import select
import socket
import threading
from collections import deque
from collections.abc import Callable

from robosoc.debug.rsp import Ack, BadChecksum, Event, Interrupt, Nack, Oversized, Packet, PacketReader, frame

LOOPBACK = "127.0.0.1"
_RECV_BYTES = 65536


class ListenError(OSError):
    """The port cannot be listened on (in use, or not allowed); the message says which and what to do."""


class Disconnected(Exception):
    """GDB closed the connection (or it broke)."""


class Listener:
    """A socket listening on the loopback interface only, for one GDB at a time."""

    def __init__(self, port: int, host: str = LOOPBACK) -> None:
        """Listen on ``host:port`` (port 0: any free port, see :attr:`port`).

        Raises:
            ListenError: the port is in use or cannot be bound.
        """
        if not 0 <= port <= 65535:
            raise ListenError(f"GDB port {port} is not a TCP port (0..65535; 0 picks a free one)")
        sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)  # a port left in TIME_WAIT is free
        try:
            sock.bind((host, port))
            sock.listen(1)
        except OSError as exc:
            sock.close()
            if exc.errno == errno.EADDRINUSE:
                raise ListenError(
                    f"port {port} on {host} is already in use: another program listens there; "
                    "choose another port with --gdb PORT (0 picks a free one)"
                ) from exc
            raise ListenError(f"cannot listen for GDB on {host}:{port}: {exc.strerror or exc}") from exc
        self._sock = sock
        self._refusing = threading.Event()  # set: the thread answering further connections is to stop
        self._refuser: threading.Thread | None = None

    @property
    def port(self) -> int:
        return int(self._sock.getsockname()[1])

    @property
    def host(self) -> str:
        return str(self._sock.getsockname()[0])

    def accept(self) -> Connection:
        """Wait for GDB to connect (Ctrl-C interrupts the wait)."""
        sock, _ = self._sock.accept()
        return Connection(sock)

    def refuse_others(self, reply: bytes, on_refused: Callable[[str], object] = lambda _: None) -> None:
        """From now on answer every further connection (a second GDB) with the packet ``reply`` and
        close it, in a thread, instead of leaving it in the backlog unanswered; ``on_refused`` is told
        the peer's address."""
        if self._refuser is not None:
            return

        def loop() -> None:
            while not self._refusing.is_set():
                try:
                    ready, _, _ = select.select([self._sock], [], [], 0.1)
                    if not ready:
                        continue
                    sock, peer = self._sock.accept()
                except (OSError, ValueError):
                    return  # the listener is closed
                with sock, contextlib.suppress(OSError):
                    sock.settimeout(2.0)
                    sock.recv(_RECV_BYTES)  # GDB's first packet (qSupported): the reply answers it
                    sock.sendall(b"+" + frame(reply))
                    sock.shutdown(socket.SHUT_WR)
                    while sock.recv(_RECV_BYTES):  # let GDB read the reply before the connection goes
                        pass
                on_refused(f"{peer[0]}:{peer[1]}")

        self._refuser = threading.Thread(target=loop, name="gdb-refuse-others", daemon=True)
        self._refuser.start()

    def close(self) -> None:
        self._refusing.set()
        if self._refuser is not None and self._refuser is not threading.current_thread():
            self._refuser.join(1.0)
        self._sock.close()


class Connection:
    """One GDB connection: events in, packets out, acknowledgements handled here."""

    def __init__(self, sock: socket.socket) -> None:
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self._sock = sock
        self._reader = PacketReader()
        self._events: deque[Event] = deque()
        self._last = b""
        self.ack_mode = True
        self.closed = False

    def send(self, payload: bytes) -> None:
        """Send one packet (kept for a retransmission while acknowledgements are on)."""
        data = frame(payload)
        self._last = data
        self._write(data)

    def receive(self, timeout: float | None = None) -> Packet | Oversized | Interrupt | None:
        """The next packet, oversized packet or interrupt; None if ``timeout`` seconds pass first.

        Raises:
            Disconnected: GDB closed the connection.
        """
        while True:
            while self._events:
                event = self._events.popleft()
                if isinstance(event, Packet | Oversized):
                    if self.ack_mode:
                        self._write(b"+")
                    return event
                if isinstance(event, Interrupt):
                    return event
                if isinstance(event, BadChecksum):
                    if self.ack_mode:
                        self._write(b"-")
                elif isinstance(event, Nack):
                    if self.ack_mode and self._last:
                        self._write(self._last)
                else:
                    assert isinstance(event, Ack)
            if not self._fill(timeout):
                return None

    def _fill(self, timeout: float | None) -> bool:
        if self.closed:
            raise Disconnected("the connection is closed")
        if timeout is not None:
            try:
                ready, _, _ = select.select([self._sock], [], [], timeout)
            except (OSError, ValueError) as exc:
                self.close()
                raise Disconnected(str(exc)) from exc
            if not ready:
                return False
        try:
            data = self._sock.recv(_RECV_BYTES)
        except OSError as exc:
            self.close()
            raise Disconnected(str(exc)) from exc
        if not data:
            self.close()
            raise Disconnected("GDB closed the connection")
        self._events.extend(self._reader.feed(data))
        return True

    def _write(self, data: bytes) -> None:
        if self.closed:
            raise Disconnected("the connection is closed")
        try:
            self._sock.sendall(data)
        except OSError as exc:
            self.close()
            raise Disconnected(str(exc)) from exc

    def close(self) -> None:
        if not self.closed:
            self.closed = True
            with contextlib.suppress(OSError):
                self._sock.shutdown(socket.SHUT_RDWR)
            self._sock.close()
