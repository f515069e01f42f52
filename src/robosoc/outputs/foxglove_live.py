"""A flight served live over Foxglove's WebSocket protocol (``robosoc fly --foxglove PORT``).

The same topics and ROS 2 messages as ``flight.mcap`` (:mod:`robosoc.outputs.ros2_flight`),
CDR-encoded, through the ``foxglove-sdk`` server on loopback: in Foxglove, *Open connection* →
``ws://127.0.0.1:PORT``.  Message times are the flight's simulated time after the start time, as
in the file (:data:`robosoc.outputs.ros2_flight.START_NS`).  A flight faster than real time is
held back to real time (``pace``) so that it can be watched; a slower one (the chip) goes at its
own pace.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping

import foxglove
import numpy as np

from robosoc.control.flight import ROW_FIELDS
from robosoc.outputs.ros2_flight import START_NS, TOPICS, cdr_encoder, message_definition, row_messages

HOST = "127.0.0.1"
SERVER_NAME = "robosoc"
ROS2_SCHEMA_ENCODING = "ros2msg"
CDR = "cdr"
_T = ROW_FIELDS.index("t")


class LiveFlightError(RuntimeError):
    """The server could not start (the port is taken, for example)."""


class LiveFlight:
    """A Foxglove WebSocket server on loopback publishing flight rows as they come.

    Args:
        port: the TCP port (0: any free port; :attr:`port` tells which).
        pace: simulated seconds per wall-clock second at most (0: as fast as the flight goes).
        start_ns: the time of the flight's start (ns since the Unix epoch).

    Raises:
        LiveFlightError: the server could not listen on the port.
    """

    def __init__(self, port: int, pace: float = 1.0, start_ns: int = START_NS) -> None:
        self._context = foxglove.Context()
        try:
            self._server = foxglove.start_server(name=SERVER_NAME, host=HOST, port=port, context=self._context)
        except Exception as exc:  # the SDK raises its own error types for a taken or bad port
            raise LiveFlightError(f"cannot serve on {HOST}:{port}: {exc}") from exc
        self.pace = pace
        self.start_ns = start_ns
        self._channels: dict[str, foxglove.Channel] = {}
        self._encoders: dict[str, Callable[[Mapping[str, object]], bytes]] = {}
        for topic in TOPICS:
            text = message_definition(topic.datatype)
            schema = foxglove.Schema(name=topic.datatype, encoding=ROS2_SCHEMA_ENCODING, data=text.encode())
            self._channels[topic.name] = foxglove.Channel(
                topic.name, schema=schema, message_encoding=CDR, context=self._context
            )
            if topic.datatype not in self._encoders:
                self._encoders[topic.datatype] = cdr_encoder(topic.datatype)
        self._start: float | None = None
        self.published = 0

    @property
    def port(self) -> int:
        return int(self._server.port)

    @property
    def url(self) -> str:
        return f"ws://{HOST}:{self.port}"

    def publish(self, row: np.ndarray) -> None:
        """Send one flight row (columns ``ROW_FIELDS``) to every subscribed client."""
        if self.pace > 0:
            self._wait(float(row[_T]))
        for topic, message, ns in row_messages(row, self.start_ns):
            self._channels[topic.name].log(self._encoders[topic.datatype](message), log_time=ns)
            self.published += 1

    def _wait(self, simulated_s: float) -> None:
        now = time.monotonic()
        if self._start is None:
            self._start = now - simulated_s / self.pace
        ahead = self._start + simulated_s / self.pace - now
        if ahead > 0:
            time.sleep(ahead)

    def close(self) -> None:
        """Stop the server (clients see the connection close)."""
        for channel in self._channels.values():
            channel.close()
        self._server.stop()

    def __enter__(self) -> LiveFlight:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


__all__ = ["HOST", "LiveFlight", "LiveFlightError"]
