"""Test helpers for the GDB stub: a minimal remote-protocol client (every read bounded in time), a
simulation running in a thread, and finding gdb-multiarch."""

from __future__ import annotations

import os
import shutil
import socket
import threading
from collections.abc import Callable

import pytest

TIMEOUT = 30.0  # seconds: only keeps a broken server from hanging the suite


def frame(payload: bytes) -> bytes:
    return b"$" + payload + b"#" + f"{sum(payload) & 0xFF:02x}".encode()


class Client:
    def __init__(self, port: int) -> None:
        self.sock = socket.create_connection(("127.0.0.1", port), timeout=TIMEOUT)
        self.buf = b""
        self.ack_mode = True

    def close(self) -> None:
        self.sock.close()

    def send_raw(self, data: bytes) -> None:
        self.sock.sendall(data)

    def _byte(self) -> int:
        if not self.buf:
            data = self.sock.recv(65536)
            if not data:
                raise ConnectionError("the server closed the connection")
            self.buf = data
        b, self.buf = self.buf[0], self.buf[1:]
        return b

    def read_ack(self) -> bytes:
        """The next acknowledgement byte (+ or -)."""
        b = self._byte()
        assert b in b"+-", f"expected an acknowledgement, got {bytes([b])!r}"
        return bytes([b])

    def read_packet(self) -> bytes:
        """The next packet's payload (checksum verified, acknowledged in ack mode)."""
        while (b := self._byte()) != ord("$"):
            assert b in b"+", f"unexpected byte {bytes([b])!r} before a packet"
        payload = bytearray()
        while (b := self._byte()) != ord("#"):
            payload.append(b)
        digits = bytes([self._byte(), self._byte()])
        assert int(digits, 16) == sum(payload) & 0xFF, "bad checksum from the server"
        if self.ack_mode:
            self.send_raw(b"+")
        return bytes(payload)

    def send(self, payload: bytes) -> None:
        """Send a packet and take the server's acknowledgement."""
        self.send_raw(frame(payload))
        if self.ack_mode:
            assert self.read_ack() == b"+"

    def ask(self, payload: bytes) -> bytes:
        """Send a packet and return the reply's payload."""
        self.send(payload)
        return self.read_packet()


class Background:
    """A function running in a thread (a simulation served to a test client); join() gives its result."""

    def __init__(self, fn: Callable[[], object]) -> None:
        self.result: object = None
        self.error: BaseException | None = None

        def body() -> None:
            try:
                self.result = fn()
            except BaseException as exc:  # the test looks at it
                self.error = exc

        self._thread = threading.Thread(target=body, daemon=True)
        self._thread.start()

    def join(self, timeout: float) -> object:
        self._thread.join(timeout)
        assert not self._thread.is_alive(), f"the simulation did not finish within {timeout} s"
        return self.result


def gdb_multiarch() -> str:
    """The gdb-multiarch executable; skip without it, except on CI (CI=true), where it must be there."""
    path = shutil.which("gdb-multiarch")
    if path is not None:
        return path
    if os.environ.get("CI", "").lower() == "true":
        pytest.fail("gdb-multiarch is missing on CI: .ci/run installs it (apt-get install gdb-multiarch)")
    pytest.skip("gdb-multiarch is not installed (apt-get install gdb-multiarch); these tests run on CI")
