"""A flight served live over Foxglove's WebSocket protocol (``robosoc fly --foxglove PORT``).

The same topics and ROS 2 messages as ``flight.mcap`` (:mod:`robosoc.outputs.ros2_flight`),
CDR-encoded, through the ``foxglove-sdk`` server on loopback: in Foxglove, *Open connection* →
``ws://127.0.0.1:PORT``.  Message times are the flight's simulated time after the start time, as
in the file (:data:`robosoc.outputs.ros2_flight.START_NS`).  A flight faster than real time is
held back to real time (``pace``) so that it can be watched; a slower one (the chip) goes at its
own pace.

The firmware's telemetry under names of its own is published as in the file, on
``/telemetry/<name>`` (``std_msgs/msg/Float64``): a channel per value, advertised with the first
row that carries the value's name, a message per row from its first read on.

Besides the file's topics the server publishes ``/clock`` (``rosgraph_msgs/msg/Clock``, the row's
time) and tells clients the time (the protocol's *time* capability), so Foxglove's clock follows
the flight.  Clients must speak the protocol ``foxglove.sdk.v1`` (Foxglove's app does): the
library refuses the older ``foxglove.websocket.v1`` and a handshake without a subprotocol with HTTP
400.  :meth:`LiveFlight.hold` keeps serving after the flight until Ctrl-C
(``robosoc fly --foxglove PORT --foxglove-keep``).
"""

from __future__ import annotations

import itertools
import time
from collections.abc import Callable, Mapping

import foxglove
import numpy as np
from foxglove.websocket import Capability

from robosoc.control.flight import ROW_FIELDS
from robosoc.outputs.ros2_flight import (
    START_NS,
    TOPICS,
    Topic,
    cdr_encoder,
    message_definition,
    row_messages,
    stamp_ns,
    telemetry_messages,
    telemetry_topic,
)

HOST = "127.0.0.1"
SERVER_NAME = "robosoc"
SUBPROTOCOL = "foxglove.sdk.v1"
"""The WebSocket subprotocol the server speaks (the only one the foxglove-sdk server accepts)."""
CLOCK_TOPIC = "/clock"
CLOCK_TYPE = "rosgraph_msgs/msg/Clock"
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
            self._server = foxglove.start_server(
                name=SERVER_NAME, host=HOST, port=port, context=self._context, capabilities=[Capability.Time]
            )
        except Exception as exc:  # the SDK raises its own error types for a taken or bad port
            raise LiveFlightError(f"cannot serve on {HOST}:{port}: {exc}") from exc
        self.pace = pace
        self.start_ns = start_ns
        self._channels: dict[str, foxglove.Channel] = {}
        self._encoders: dict[str, Callable[[Mapping[str, object]], bytes]] = {}
        for name, datatype in [(t.name, t.datatype) for t in TOPICS] + [(CLOCK_TOPIC, CLOCK_TYPE)]:
            self._channel(name, datatype)
        self._telemetry: dict[str, Topic] = {}  # the telemetry topics advertised, by value name
        self._start: float | None = None
        self.published = 0

    @property
    def port(self) -> int:
        return int(self._server.port)

    @property
    def url(self) -> str:
        return f"ws://{HOST}:{self.port}"

    def _channel(self, name: str, datatype: str) -> None:
        text = message_definition(datatype)
        schema = foxglove.Schema(name=datatype, encoding=ROS2_SCHEMA_ENCODING, data=text.encode())
        self._channels[name] = foxglove.Channel(name, schema=schema, message_encoding=CDR, context=self._context)
        if datatype not in self._encoders:
            self._encoders[datatype] = cdr_encoder(datatype)

    def publish(self, row: np.ndarray, telemetry: Mapping[str, float] | None = None) -> None:
        """Send one flight row (columns ``ROW_FIELDS``) and the firmware's telemetry values of its
        own names at that row (name -> value, NaN: none read yet) to every subscribed client."""
        if self.pace > 0:
            self._wait(float(row[_T]))
        ns = stamp_ns(float(row[_T]), self.start_ns)
        clock = {"clock": {"sec": ns // 1_000_000_000, "nanosec": ns % 1_000_000_000}}
        self._channels[CLOCK_TOPIC].log(self._encoders[CLOCK_TYPE](clock), log_time=ns)
        self._server.broadcast_time(ns)
        messages = row_messages(row, self.start_ns)
        if telemetry:
            for name in telemetry:
                if name not in self._telemetry:
                    self._telemetry[name] = topic = telemetry_topic(name)
                    self._channel(topic.name, topic.datatype)
            topics = [self._telemetry[name] for name in telemetry]
            messages = itertools.chain(messages, telemetry_messages(topics, list(telemetry.values()), ns))
        for topic, message, log_ns in messages:
            self._channels[topic.name].log(self._encoders[topic.datatype](message), log_time=log_ns)
            self.published += 1

    def hold(self, poll_s: float = 0.2) -> None:
        """Keep serving (clients stay connected, new ones may come) until Ctrl-C, which it takes."""
        try:
            while True:
                time.sleep(poll_s)
        except KeyboardInterrupt:
            return

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


__all__ = ["CLOCK_TOPIC", "CLOCK_TYPE", "HOST", "SUBPROTOCOL", "LiveFlight", "LiveFlightError"]
