"""The chip side of the decoupled mode against a hostile physics side (issue 34, item 7): a valid
datagram whose reading lies far past the flight, a trickle of garbage, then silence.  The chip drops
the reading (counted), answers the garbage with no extra hellos, keeps its log bounded, and ends
on --peer-timeout."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from robosoc.cli import exit_codes
from robosoc.control.flight import ROW_FIELDS
from robosoc.cosim.datagram import Reading, SensorBatch
from robosoc.cosim.link import MAX_LINES_PER_KIND, Address, LinkLog, UdpLink
from robosoc.cosim.replay import sensor_packet

HANG_GUARD_S = 300
HEARTBEAT_S = 0.02  # the chip's hello interval (LinkConfig.heartbeat_s)


def robosoc(*args: str) -> subprocess.Popen:
    env = {**os.environ, "PYTHONPATH": str(Path(__file__).parents[2] / "src"), "COLUMNS": "200"}
    return subprocess.Popen(
        [sys.executable, "-m", "robosoc", *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env
    )


def test_a_reading_past_the_flight_is_dropped_and_the_peer_timeout_holds(tmp_path: Path) -> None:
    physics = UdpLink(Address("127.0.0.1", 0), "physics")
    out = tmp_path / "chip"
    peer = f"127.0.0.1:{physics.address.port}"
    chip = robosoc("serve", "chip", "--seconds", "0.3", "--peer", peer, "--peer-timeout", "1", "--out", str(out))
    try:
        while not physics.receive(5.0):  # the first hello: the chip is booted and waiting
            assert chip.poll() is None, chip.stderr.read()  # type: ignore[union-attr]
        # garbage, one datagram a millisecond for a second: hellos still come once a heartbeat
        hellos, sent, end = 0, 0, time.monotonic() + 1.0
        while time.monotonic() < end:
            physics.sock.sendto(b"\x00garbage" + bytes([sent % 256]), physics.peer)
            sent += 1
            time.sleep(0.001)
            hellos += len(physics.receive(0.0))
        assert sent > 200
        assert hellos <= 1.0 / HEARTBEAT_S + 10, f"{hellos} hellos for {sent} garbage datagrams"
        # a valid batch: reading 0 at t = 0, reading 1 at t = 2**63 ns (the end of time, for a 0.3 s flight)
        row = np.zeros(len(ROW_FIELDS))
        far = Reading(1, 2**63, sensor_packet(row, 1, 10_000))
        physics.send_data(SensorBatch(0, (Reading(0, 0, sensor_packet(row, 0, 10_000)), far)))
        sent_at = time.monotonic()
        assert chip.wait(timeout=HANG_GUARD_S) == exit_codes.PEER_LOST
        assert time.monotonic() - sent_at < 30  # --peer-timeout 1, not a simulation of 292 years
        stderr = chip.stderr.read()  # type: ignore[union-attr]
        assert "no datagram from the physics for" in stderr and "Traceback" not in stderr
        record = json.loads((out / "chip.json").read_text())
        assert record["readings"]["outside"] == 1 and record["readings"]["injected"] == 1
        assert record["simulated_s"] <= 0.3
        lines = (out / "link-chip.log").read_text().splitlines()
        assert len(lines) < 4 * MAX_LINES_PER_KIND, len(lines)
        assert any("dropped: outside the flight" in line for line in lines)
        assert any(line.endswith("more not logged") and "rejected" in line for line in lines)
    finally:
        if chip.poll() is None:
            chip.kill()
            chip.wait()
        physics.close()


def test_the_link_log_keeps_a_bounded_number_of_lines_per_kind(tmp_path: Path) -> None:
    log = LinkLog(tmp_path / "link.log", per_kind=5)
    for k in range(10_000):
        log.write(f"rejected {k}", "rejected")
        if k % 1000 == 0:
            log.write(f"event {k}")  # events without a kind are always written
    log.close()
    lines = (tmp_path / "link.log").read_text().splitlines()
    assert sum("rejected" in line for line in lines) == 5 + 1  # five, then the count
    assert lines[-1].endswith("rejected: 9995 more not logged")
    assert sum(" event " in line for line in lines) == 10
    assert "further ones are counted" in next(line for line in lines if "rejected 4" in line)
