"""The live server: a WebSocket client on loopback speaks Foxglove's protocol with it."""

from __future__ import annotations

import contextlib
import json
import math
import os
import signal
import socket
import struct
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest
from mcap.records import Schema
from mcap_ros2.decoder import DecoderFactory
from websockets.sync.client import connect

from robosoc.control.flight import ROW_FIELDS
from robosoc.outputs.foxglove_live import CLOCK_TOPIC, LiveFlight, LiveFlightError
from robosoc.outputs.ros2_flight import START_NS, TOPICS

SUBPROTOCOL = "foxglove.sdk.v1"
MESSAGE_DATA = 0x01  # binary opcode of a message (Foxglove WebSocket protocol)
WAIT_S = 30


def _advertised(ws) -> list[dict]:
    """Read JSON frames up to the advertisement of every topic."""
    channels: dict[str, dict] = {}
    while len(channels) < len(TOPICS) + 1:  # and /clock
        frame = json.loads(ws.recv(timeout=WAIT_S))
        if frame["op"] == "advertise":
            channels.update({c["topic"]: c for c in frame["channels"]})
    return list(channels.values())


def _subscribe(ws, channels: list[dict]) -> dict[int, dict]:
    subscriptions = {k + 1: c for k, c in enumerate(channels)}
    ws.send(
        json.dumps(
            {"op": "subscribe", "subscriptions": [{"id": k, "channelId": c["id"]} for k, c in subscriptions.items()]}
        )
    )
    return subscriptions


def _first_message(ws, failed: list[BaseException] | None = None) -> tuple[int, int, bytes]:
    """The first message frame; fails at once when a publishing thread has failed (``failed``)."""
    deadline = time.monotonic() + WAIT_S
    while True:
        if failed:  # (None or empty: nobody failed)
            raise AssertionError("publishing failed") from failed[0]
        try:
            frame = ws.recv(timeout=0.2)
        except TimeoutError:
            if time.monotonic() > deadline:
                raise
            continue
        if isinstance(frame, bytes) and frame[0] == MESSAGE_DATA:
            subscription, ns = struct.unpack_from("<IQ", frame, 1)
            return subscription, ns, frame[13:]


def test_a_client_gets_the_channels_and_messages_equal_to_the_rows(host_flight: np.ndarray) -> None:
    rows = host_flight[:50]
    with LiveFlight(0, pace=0) as live:
        assert live.port > 0
        stop = threading.Event()
        with connect(live.url, subprotocols=[SUBPROTOCOL], open_timeout=WAIT_S) as ws:
            assert ws.subprotocol == SUBPROTOCOL
            channels = _advertised(ws)
            expected = {t.name: t.datatype for t in TOPICS} | {CLOCK_TOPIC: "rosgraph_msgs/msg/Clock"}
            assert {c["topic"]: c["schemaName"] for c in channels} == expected
            assert {(c["encoding"], c["schemaEncoding"]) for c in channels} == {("cdr", "ros2msg")}
            subscriptions = _subscribe(ws, [c for c in channels if c["topic"] != CLOCK_TOPIC])

            failed: list[BaseException] = []

            def publish() -> None:  # until the subscription has reached the server
                try:
                    while not stop.is_set():
                        for row in rows:
                            live.publish(row)
                except BaseException as exc:  # shown by the test, not lost in the thread
                    failed.append(exc)

            publisher = threading.Thread(target=publish, daemon=True)
            publisher.start()
            try:
                subscription, ns, payload = _first_message(ws, failed)
            finally:
                stop.set()
                publisher.join(WAIT_S)
    channel = subscriptions[subscription]
    schema = Schema(id=1, name=channel["schemaName"], encoding=channel["schemaEncoding"],
                    data=channel["schema"].encode())  # fmt: skip
    decoder = DecoderFactory().decoder_for(channel["encoding"], schema)
    assert decoder is not None
    decoded = decoder(payload)
    # a row's simulated time after the start time, 2026-01-01T00:00:00Z, as in flight.mcap
    times = 1_767_225_600 * 10**9 + np.round(rows[:, ROW_FIELDS.index("t")] * 1e9).astype(np.int64)
    assert ns in times
    row = dict(zip(ROW_FIELDS, rows[list(times).index(ns)], strict=True))
    headers = [t.header for t in getattr(decoded, "transforms", [])] or [getattr(decoded, "header", None)]
    for header in filter(None, headers):
        assert header.stamp.sec * 10**9 + header.stamp.nanosec == ns
    topic = next(t for t in TOPICS if t.name == channel["topic"])
    if topic.name == "/tf":  # the true pose first
        translation = decoded.transforms[0].transform.translation
        assert (translation.x, translation.y, translation.z) == (row["x"], row["y"], row["z"])
    for path, (column, factor) in topic.columns.items():
        node = decoded
        for key in path.split("."):
            node = node[int(key)] if key.isdigit() else getattr(node, key)
        assert node == (row[column] > 0.5 if column == "armed" else row[column] * factor), (topic.name, path)


def test_a_taken_port_is_an_error_naming_it() -> None:
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        with pytest.raises(LiveFlightError, match=f"127.0.0.1:{port}"):
            LiveFlight(port)


def test_fly_foxglove_serves_the_flight_and_writes_its_logs(tmp_path: Path) -> None:
    env = {**os.environ, "PYTHONUNBUFFERED": "1", "COLUMNS": "200"}
    args = [sys.executable, "-m", "robosoc", "fly", "--seconds", "3", "--foxglove", "0", "--out", str(tmp_path / "run")]
    with subprocess.Popen(args, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env) as fly:
        assert fly.stdout is not None
        url = None
        for line in fly.stdout:
            if line.startswith("foxglove: ws://"):
                url = line.split()[1]
                break
        assert url is not None, "fly printed no foxglove URL"
        with connect(url, subprotocols=[SUBPROTOCOL], open_timeout=WAIT_S) as ws:
            _subscribe(ws, _advertised(ws))
            _, ns, payload = _first_message(ws)  # the flight goes at real-time pace: 3 s to catch it
            assert payload and START_NS <= ns <= START_NS + 3 * 10**9
        rest = fly.stdout.read()
        assert fly.wait(timeout=120) == 0, rest
    for name in ("flight.csv", "flight.mcap", "report.html"):
        assert (tmp_path / "run" / name).is_file(), name


class _Clock:
    """A monotonic clock that only moves when the code under test sleeps."""

    def __init__(self) -> None:
        self.now = 1000.0
        self.slept: list[float] = []

    def monotonic(self) -> float:
        return self.now

    def sleep(self, seconds: float) -> None:
        self.slept.append(seconds)
        self.now += seconds


@pytest.mark.parametrize(("pace", "slept"), [(1.0, 1.0), (2.0, 0.5), (0.5, 2.0), (0.0, 0.0)])
def test_publishing_is_held_back_to_the_pace(monkeypatch, host_flight: np.ndarray, pace: float, slept: float) -> None:
    """Rows 1 s apart in simulated time take 1/pace s of wall time; the first row is not held back."""
    import robosoc.outputs.foxglove_live as live_module

    clock = _Clock()
    monkeypatch.setattr(live_module.time, "monotonic", clock.monotonic)
    monkeypatch.setattr(live_module.time, "sleep", clock.sleep)
    t = host_flight[:, ROW_FIELDS.index("t")]
    first = host_flight[0].copy()
    first[ROW_FIELDS.index("t")] = 2.0  # a live view joined at 2 s: the pace counts from there
    later = host_flight[int(np.argmin(np.abs(t - (t[0] + 1.0))))].copy()
    later[ROW_FIELDS.index("t")] = 3.0
    with LiveFlight(0, pace=pace) as live:
        live.publish(first)
        assert clock.slept == []
        live.publish(later)
        assert sum(clock.slept) == pytest.approx(slept, abs=1e-9)


TIME = 0x02  # binary opcode of the server's time (Foxglove WebSocket protocol)


def test_subprotocols_clock_and_server_time(host_flight: np.ndarray) -> None:
    """Only foxglove.sdk.v1 connects (the older foxglove.websocket.v1 and no subprotocol get HTTP
    400); the server has the time capability, sends each row's time, and /clock decodes to it."""
    from websockets.exceptions import InvalidStatus

    rows = host_flight[:20]
    with LiveFlight(0, pace=0) as live:
        for refused in (["foxglove.websocket.v1"], None):
            with pytest.raises(InvalidStatus, match="400"):
                connect(live.url, subprotocols=refused, open_timeout=WAIT_S)
        with connect(live.url, subprotocols=[SUBPROTOCOL], open_timeout=WAIT_S) as ws:
            info = json.loads(ws.recv(timeout=WAIT_S))
            assert info["op"] == "serverInfo" and "time" in info["capabilities"]
            clock = next(c for c in _advertised(ws) if c["topic"] == CLOCK_TOPIC)
            ws.send(json.dumps({"op": "subscribe", "subscriptions": [{"id": 7, "channelId": clock["id"]}]}))
            times = [START_NS + round(float(t) * 1e9) for t in rows[:, ROW_FIELDS.index("t")]]
            clocks: list[int] = []
            server_times: list[int] = []
            deadline = time.monotonic() + WAIT_S
            while not (clocks and server_times) and time.monotonic() < deadline:
                for row in rows:
                    live.publish(row)
                with contextlib.suppress(TimeoutError):
                    while True:
                        frame = ws.recv(timeout=0.1)
                        if isinstance(frame, bytes) and frame[0] == TIME:
                            server_times.append(struct.unpack_from("<Q", frame, 1)[0])
                        elif isinstance(frame, bytes) and frame[0] == MESSAGE_DATA:
                            _, ns = struct.unpack_from("<IQ", frame, 1)
                            schema = Schema(id=1, name=clock["schemaName"], encoding=clock["schemaEncoding"],
                                            data=clock["schema"].encode())  # fmt: skip
                            decoded = DecoderFactory().decoder_for("cdr", schema)(frame[13:])
                            assert decoded.clock.sec * 10**9 + decoded.clock.nanosec == ns
                            clocks.append(ns)
    assert clocks and set(clocks) <= set(times)
    assert server_times and set(server_times) <= set(times)


def test_fly_foxglove_keep_serves_until_ctrl_c(tmp_path: Path) -> None:
    """--foxglove-keep: the flight's files are written, the server still takes clients, Ctrl-C ends
    the command with 0; without --foxglove it is refused."""
    env = {**os.environ, "PYTHONUNBUFFERED": "1", "COLUMNS": "200"}
    out = tmp_path / "run"
    args = [sys.executable, "-m", "robosoc", "fly", "--seconds", "0.3", "--foxglove", "0", "--foxglove-keep",
            "--out", str(out)]  # fmt: skip
    with subprocess.Popen(args, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env) as fly:
        assert fly.stdout is not None
        url = None
        for line in fly.stdout:
            if "still serving on" in line:
                url = line.split("still serving on ")[1].split()[0]
                break
        assert url is not None, "fly did not say it keeps serving"
        assert (out / "summary.json").is_file() and json.loads((out / "summary.json").read_text())["complete"]
        with connect(url, subprotocols=[SUBPROTOCOL], open_timeout=WAIT_S) as ws:
            assert {c["topic"] for c in _advertised(ws)} >= {t.name for t in TOPICS}
        fly.send_signal(signal.SIGINT)
        assert fly.wait(timeout=60) == 0, fly.stdout.read()
    bad = subprocess.run([sys.executable, "-m", "robosoc", "fly", "--foxglove-keep", "--no-out"], env=env,
                         capture_output=True, text=True, timeout=60, check=False)  # fmt: skip
    assert bad.returncode == 2 and "--foxglove-keep: only with --foxglove PORT" in bad.stderr


def test_the_firmware_telemetry_is_published_live_as_in_the_file(host_flight: np.ndarray) -> None:
    """Telemetry values under names of their own get the MCAP file's topics, /telemetry/<name>
    (std_msgs/msg/Float64), advertised with the first row that names them; a message per row that
    has a value (row k carries k here), none while a value is NaN (no read yet: row 0, and a
    value never read)."""
    rows = host_flight[:20]
    times = [START_NS + round(float(t) * 1e9) for t in rows[:, ROW_FIELDS.index("t")]]

    def told(k: int) -> dict[str, float]:
        return {"jobs_counted": float(k) if k else math.nan, "never_read": math.nan}

    with LiveFlight(0, pace=0) as live:
        live.publish(rows[0], told(0))  # advertises the telemetry's channels
        with connect(live.url, subprotocols=[SUBPROTOCOL], open_timeout=WAIT_S) as ws:
            channels: dict[str, dict] = {}
            while not {"/telemetry/jobs_counted", "/telemetry/never_read"} <= channels.keys():
                frame = json.loads(ws.recv(timeout=WAIT_S))
                if frame["op"] == "advertise":
                    channels.update({c["topic"]: c for c in frame["channels"]})
            telemetry = [channels["/telemetry/jobs_counted"], channels["/telemetry/never_read"]]
            assert {c["schemaName"] for c in telemetry} == {"std_msgs/msg/Float64"}
            subscriptions = _subscribe(ws, telemetry)
            stop = threading.Event()

            def publish() -> None:
                while not stop.is_set():
                    for k, row in enumerate(rows):
                        live.publish(row, told(k))

            publisher = threading.Thread(target=publish, daemon=True)
            publisher.start()
            got: dict[int, float] = {}
            try:
                deadline = time.monotonic() + WAIT_S
                while len(got) < len(rows) - 1 and time.monotonic() < deadline:
                    with contextlib.suppress(TimeoutError):
                        frame = ws.recv(timeout=0.5)
                        if isinstance(frame, bytes) and frame[0] == MESSAGE_DATA:
                            subscription, ns = struct.unpack_from("<IQ", frame, 1)
                            channel = subscriptions[subscription]
                            assert channel["topic"] == "/telemetry/jobs_counted"  # never_read: no message
                            schema = Schema(id=1, name=channel["schemaName"], encoding=channel["schemaEncoding"],
                                            data=channel["schema"].encode())  # fmt: skip
                            got[ns] = DecoderFactory().decoder_for("cdr", schema)(frame[13:]).data
            finally:
                stop.set()
                publisher.join(WAIT_S)
    assert got == {ns: float(k) for k, ns in enumerate(times) if k}
