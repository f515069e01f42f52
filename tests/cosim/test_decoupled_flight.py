"""The decoupled mode end to end: both sides as processes over loopback, peers that vanish, bad addresses.

Short flights paced ``fast``; the scenario takes off at 0.3 s so that the commands matter.  With
``fast`` pacing every command is known before the physics steps past it, so the decoupled flight
must be the lockstep flight row for row, whatever the link loses, repeats or reorders.
"""

from __future__ import annotations

import dataclasses
import json
import math
import os
import queue
import signal
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from robosoc.cli import app, exit_codes
from robosoc.config.chip import TileConfig
from robosoc.config.link import LinkConfig
from robosoc.config.scenario import FlightPlan, ScenarioConfig
from robosoc.config.vehicle import vehicle_preset
from robosoc.control.flight import ROW_FIELDS
from robosoc.control.flight_log import read_flight_log
from robosoc.cosim.datagram import Hello, Reading, SensorBatch
from robosoc.cosim.decoupled_physics import scenario_digest
from robosoc.cosim.link import Address, UdpLink
from robosoc.cosim.lockstep import ChipController, fly_chip, fly_lockstep_fleet
from robosoc.cosim.replay import sensor_packet
from robosoc.host.telemetry import declared_names
from robosoc.outputs.decoupled_flight import SideFailed, fly_decoupled
from robosoc.outputs.flight_session import fleet_vehicles
from robosoc.physics.clock import FlightClock

SCENARIO_TOML = "duration_s = 1.2\n[flight]\ntakeoff_s = 0.3\nsteps = []\n"
FAULTS = "loss=0.1,duplicate=0.05,reorder=0.05,truncate=0.05,garbage=0.05"
HANG_GUARD_S = 300  # a side that never ends fails the test instead of hanging the suite


def test_fly_decoupled_survives_every_fault_and_equals_lockstep(tmp_path: Path) -> None:
    scenario = tmp_path / "short.toml"
    scenario.write_text(SCENARIO_TOML)
    out = tmp_path / "run"
    args = ["fly", "--decoupled", "--pace", "fast", "--faults", FAULTS, "--scenario", str(scenario)]
    result = CliRunner().invoke(app, [*args, "--seed", "5", "--out", str(out)])
    assert result.exit_code == 0, result.output
    assert "decoupled: two processes over UDP, pace fast" in result.output and "to physics" in result.output
    summary = json.loads((out / "summary.json").read_text())
    assert (summary["mode"], summary["controller"], summary["complete"]) == ("decoupled", "chip", True)
    assert summary["firmware"]["build"] == "fixed+mul" and summary["deadline_misses"] == 0
    link = summary["link"]
    for direction in ("to_chip", "to_physics"):
        d, injected = link[direction], link[direction]["injected"]
        assert min(injected.values()) > 0, (direction, injected)  # every fault happened in each direction
        for name in ("duplicated", "reordered", "truncated", "garbage"):
            assert d[name] == injected[name], (direction, name, d)
        assert d["lost"] == injected["lost"] + injected["truncated"], (direction, d)
        assert d["received"] == d["sent"] - d["lost"]
    assert link["readings"]["injected"] == 120 and link["readings"]["late"] == 0
    assert link["commands"] == {"received": 120, "late": 0, "missed": 0}
    rows = read_flight_log(out / "flight.csv")
    config = ScenarioConfig(duration_s=1.2, flight=FlightPlan(takeoff_s=0.3, steps=()))
    reference = fly_chip(dataclasses.replace(config, seed=5), vehicle_preset(config.vehicle)).rows
    pwm = [ROW_FIELDS.index(f"pwm{i}") for i in range(4)]
    assert reference[-1, pwm].min() > 0, "the reference flight has taken off"
    # every column but the estimate's equal; the estimate (sent back by the chip, not waited for by
    # the physics) too wherever its datagram was not lost or held back past the row
    kept = [i for i, name in enumerate(ROW_FIELDS) if not name.startswith("est_")]
    assert np.array_equal(rows[:, kept], reference[:, kept], equal_nan=True)
    est = [i for i, name in enumerate(ROW_FIELDS) if name.startswith("est_")]
    same = [np.array_equal(a, b, equal_nan=True) for a, b in zip(rows[:, est], reference[:, est], strict=True)]
    assert sum(same) >= 0.75 * len(rows), sum(same)  # 10 % loss, 5 % held back: about one row in ten differs
    for name in ("jobs.csv", "chip.json", "physics.json", "link-chip.log", "link-physics.log", "flight.png"):
        assert (out / name).stat().st_size > 0, name


def test_fly_decoupled_carries_the_chip_estimate_back(tmp_path: Path) -> None:
    """Without faults the decoupled flight paced fast is the lockstep flight in every column, the
    chip's estimate too (the chip sends it back; lockstep reads the same state from the chip)."""
    scenario = tmp_path / "short.toml"
    scenario.write_text(SCENARIO_TOML)
    out = tmp_path / "run"
    result = CliRunner().invoke(app, ["fly", "--decoupled", "--pace", "fast", "--scenario", str(scenario),
                                      "--duration", "0.6", "--out", str(out)])  # fmt: skip
    assert result.exit_code == 0, result.output
    rows = read_flight_log(out / "flight.csv")
    config = ScenarioConfig(duration_s=0.6, flight=FlightPlan(takeoff_s=0.3, steps=()))
    reference = fly_chip(config, vehicle_preset(config.vehicle)).rows
    assert np.array_equal(rows, reference, equal_nan=True)
    assert np.isfinite(rows[1:, ROW_FIELDS.index("est_height")]).all()  # an estimate from the second row on
    summary = json.loads((out / "summary.json").read_text())
    assert math.isfinite(summary["flight"]["attitude_estimate_rms_deg"])


def test_fly_decoupled_flies_two_vehicles(tmp_path: Path) -> None:
    """--vehicles 2: one physics process, one chip process per vehicle on its own UDP link; each
    vehicle's flight is the lockstep fleet's in every column, its files in vehicle-N/."""
    scenario = tmp_path / "short.toml"
    scenario.write_text(SCENARIO_TOML)
    out = tmp_path / "run"
    args = ["fly", "--decoupled", "--pace", "fast", "--scenario", str(scenario), "--duration", "0.6"]
    result = CliRunner().invoke(app, [*args, "--vehicles", "2", "--out", str(out)])
    assert result.exit_code == 0, result.output
    assert "vehicle 2: hover height error" in result.output
    config = ScenarioConfig(duration_s=0.6, vehicles=2, flight=FlightPlan(takeoff_s=0.3, steps=()))
    canonical = vehicle_preset(config.vehicle)
    vehicles = fleet_vehicles(config)
    expected = fly_lockstep_fleet(config, vehicles, [ChipController(config, canonical) for _ in vehicles])
    for i in (1, 2):
        rows = read_flight_log(out / f"vehicle-{i}" / "flight.csv")
        assert np.array_equal(rows, expected[i - 1], equal_nan=True), i
        summary = json.loads((out / f"vehicle-{i}" / "summary.json").read_text())
        assert summary["complete"] and summary["link"]["commands"]["received"] == 60
    top = json.loads((out / "summary.json").read_text())
    assert top["complete"] and top["mode"] == "decoupled" and len(top["vehicles"]) == 2
    assert top["min_separation_m"] == pytest.approx(3.0, abs=0.2)
    assert not np.array_equal(expected[0][:, 1:4], expected[1][:, 1:4])


# --- one side against a hand-driven peer -----------------------------------------------------------


def robosoc(*args: str) -> subprocess.Popen:
    env = {**os.environ, "PYTHONPATH": str(Path(__file__).parents[2] / "src"), "COLUMNS": "200"}
    return subprocess.Popen(
        [sys.executable, "-m", "robosoc", *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env
    )


def lines_of(process: subprocess.Popen) -> queue.Queue:
    lines: queue.Queue = queue.Queue()

    def read() -> None:
        for line in process.stdout:  # type: ignore[union-attr]
            lines.put(line)

    threading.Thread(target=read, daemon=True).start()
    return lines


def wait_for(lines: queue.Queue, text: str) -> str:
    while True:
        line = lines.get(timeout=HANG_GUARD_S)
        if text in line:
            return line


def test_the_physics_side_ends_when_the_chip_goes_silent(tmp_path: Path) -> None:
    out = tmp_path / "physics"
    args = ["--seconds", "3", "--bind", "127.0.0.1:0", "--peer-timeout", "1", "--out", str(out)]
    physics = robosoc("serve", "physics", *args)
    line = wait_for(lines_of(physics), "listening on")
    port = int(line.rsplit(":", 1)[1])
    config = ScenarioConfig(duration_s=3.0)
    chip = UdpLink(Address("127.0.0.1", 0), "chip", peer=Address("127.0.0.1", port))
    digest = scenario_digest(config, vehicle_preset(config.vehicle))
    chip.send_control(Hello(digest, FlightClock.of(config).sample_period_ns, declared_names(config.firmware)))
    got = []
    while not got:
        got = chip.receive(5.0)
    chip.close()  # the chip vanishes after its first sensor batch
    assert physics.wait(timeout=HANG_GUARD_S) == exit_codes.PEER_LOST
    stderr = physics.stderr.read()  # type: ignore[union-attr]
    assert "robosoc serve physics: no datagram from the chip for" in stderr and "--peer-timeout 1" in stderr
    record = json.loads((out / "physics.json").read_text())
    assert record["ended"] == "peer_lost" and not record["complete"]
    assert len(read_flight_log(out / "flight.csv")) == record["rows"] > 0


def test_the_chip_side_ends_when_the_physics_goes_silent(tmp_path: Path) -> None:
    config = ScenarioConfig(duration_s=2.0)
    physics = UdpLink(Address("127.0.0.1", 0), "physics")
    out = tmp_path / "chip"
    peer = f"127.0.0.1:{physics.address.port}"
    chip = robosoc("serve", "chip", "--seconds", "2", "--peer", peer, "--peer-timeout", "1", "--out", str(out))
    hello = []
    while not hello:
        assert chip.poll() is None, chip.stderr.read()  # type: ignore[union-attr]
        hello = physics.receive(5.0)
    assert hello[0].body == Hello(
        scenario_digest(config, vehicle_preset(config.vehicle)),
        FlightClock.of(config).sample_period_ns,
        ("est_qw", "est_qx", "est_qy", "est_qz", "est_height", "est_vz"),  # the quadrotor project's telemetry
    )
    row = np.zeros(len(ROW_FIELDS))
    readings = []
    for k in range(3):
        row[0] = k / 100
        readings.append(Reading(k, k * 10_000_000, sensor_packet(row, k, 10_000)))
    physics.send_data(SensorBatch(20_000_000, tuple(readings)))
    # the physics vanishes: the chip runs to one period past the last reading, then waits in vain
    assert chip.wait(timeout=HANG_GUARD_S) == exit_codes.PEER_LOST
    stderr = chip.stderr.read()  # type: ignore[union-attr]
    assert "robosoc serve chip: no datagram from the physics for" in stderr
    record = json.loads((out / "chip.json").read_text())
    assert record["ended"] == "peer_lost" and record["readings"]["injected"] == 3
    assert record["tasks"]["estimator"]["jobs"] == 3
    physics.close()


def test_ctrl_c_ends_fly_decoupled_with_what_was_done(tmp_path: Path) -> None:
    out = tmp_path / "run"
    # a shell's background job ignores Ctrl-C, and a child inherits that: this test's child must
    # take it as a terminal's user's would (an exec'd child gets a handler's signal as SIG_DFL)
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        fly = robosoc("fly", "--decoupled", "--seconds", "20", "--out", str(out))
    finally:
        signal.signal(signal.SIGINT, previous)
    wait_for(lines_of(fly), "the chip said hello; flying")
    while not (out / "flight.csv").exists() or len((out / "flight.csv").read_text().splitlines()) < 3:
        assert fly.poll() is None, fly.stderr.read()  # type: ignore[union-attr]
        time.sleep(0.05)  # until a few rows are flown
    fly.send_signal(signal.SIGINT)  # to the parent only: it passes it on to both sides
    assert fly.wait(timeout=HANG_GUARD_S) == exit_codes.INTERRUPTED
    summary = json.loads((out / "summary.json").read_text())
    assert summary["mode"] == "decoupled" and summary["complete"] is False
    assert summary["link"]["physics_ended"] == "interrupted" and summary["link"]["chip_ended"] in (
        "interrupted",
        "peer_ended",
    )
    assert len(read_flight_log(out / "flight.csv")) >= 2


@pytest.mark.parametrize("side", ["chip", "physics"])
def test_a_side_whose_flight_ended_writes_its_record_through_its_ctrl_c(tmp_path: Path, monkeypatch, side: str) -> None:
    """A side ended because its peer said bye first (the peer took its Ctrl-C first), then takes
    its own Ctrl-C while it makes its record: its ``.json`` still comes out whole, and the handler
    is back afterwards."""
    import types

    from robosoc.outputs import decoupled_flight as decoupled

    class Interrupted(Exception):  # the test's own handler: a KeyboardInterrupt would stop pytest
        pass

    def handler(signum: int, frame: object) -> None:
        raise Interrupted

    def record(*args: object) -> dict:
        os.kill(os.getpid(), signal.SIGINT)
        time.sleep(0.05)  # the handler runs at the next bytecode, well within this
        return {"ended": "peer_ended"}

    monkeypatch.setattr(decoupled, f"serve_{side}", lambda *args, **kwargs: types.SimpleNamespace(result=None))
    monkeypatch.setattr(decoupled, f"{side}_record", record)
    config = ScenarioConfig()
    vehicle = vehicle_preset(config.vehicle)
    local = Address("127.0.0.1", 9)
    previous = signal.signal(signal.SIGINT, handler)
    try:
        if side == "chip":
            _, got = decoupled.run_chip_side(config, vehicle, LinkConfig(), local, None, tmp_path)
        else:
            _, got = decoupled.run_physics_side(config, vehicle, LinkConfig(), local, tmp_path)
        assert signal.getsignal(signal.SIGINT) is handler
    finally:
        signal.signal(signal.SIGINT, previous)
    assert got == json.loads((tmp_path / f"{side}.json").read_text()) == {"ended": "peer_ended"}


# --- clear errors ----------------------------------------------------------------------------------


def test_addresses_in_use_and_bad_addresses_are_usage_errors(tmp_path: Path) -> None:
    taken = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    taken.bind(("127.0.0.1", 0))
    port = taken.getsockname()[1]
    runner = CliRunner()
    cases = [
        (
            ["serve", "physics", "--bind", f"127.0.0.1:{port}", "--no-out"],
            f"--bind: 127.0.0.1:{port}: the address is in use",
        ),
        (["serve", "physics", "--bind", "localhost", "--no-out"], "--bind: expected HOST:PORT"),
        (
            ["serve", "physics", "--bind", "192.0.2.1:5000", "--no-out"],
            "--bind: 192.0.2.1:5000: not an address of this machine",
        ),
        (
            ["serve", "chip", "--peer", "no-such-host.invalid:5", "--no-out"],
            "--peer: no-such-host.invalid:5: cannot resolve",
        ),
        (["serve", "chip", "--peer", "127.0.0.1:0", "--no-out"], "--peer: the port must be between 1 and 65535"),
        (["fly", "--pace", "fast", "--no-out"], "--pace: only with --decoupled"),
        (
            ["fly", "--decoupled", "--controller", "host", "--no-out"],
            "--decoupled: the decoupled mode flies the firmware",
        ),
        (
            ["fly", "--decoupled", "--bind", f"127.0.0.1:{port}", "--seconds", "0.1", "--no-out"],
            f"--bind: 127.0.0.1:{port}: the address is in use",
        ),
    ]
    # the scenario as fly takes it: SCENARIO or --scenario, --duration or --seconds, never both
    bad = tmp_path / "bad.toml"
    bad.write_text("duration_s = -1\n")
    good = tmp_path / "good.toml"
    good.write_text(SCENARIO_TOML)
    for side in ("physics", "chip"):
        cases += [
            (["serve", side, str(bad), "--no-out"], f"{bad}"),
            (["serve", side, str(good), "--scenario", str(good), "--no-out"], "--scenario: cannot be combined"),
            (["serve", side, "--duration", "1", "--seconds", "1", "--no-out"], "--duration: cannot be combined"),
            (["serve", side, str(good), "--duration", "0.001", "--no-out"], "--duration: a flight lasts at least"),
            (["serve", side, "--seconds", "0.001", "--no-out"], "--seconds: a flight lasts at least"),
        ]
    for args, message in cases:
        result = runner.invoke(app, args)
        assert result.exit_code == exit_codes.USAGE, (args, result.output)
        assert message in result.output and "Traceback" not in result.output, (args, result.output)
    taken.close()


def test_a_side_that_fails_to_start_stops_the_other(tmp_path: Path) -> None:
    """The chip side cannot build its firmware (its tiles' SRAM is too small for it): the physics
    side, waiting for a hello that will never come, is interrupted instead of waiting out
    --connect-timeout."""
    config = ScenarioConfig(duration_s=0.5)
    chip = dataclasses.replace(config.chip, tile=TileConfig(sram_bytes=4096))
    with pytest.raises(SideFailed, match="does not fit in SRAM of 4096 bytes") as failure:
        fly_decoupled(dataclasses.replace(config, chip=chip), vehicle_preset(config.vehicle), LinkConfig(), tmp_path)
    assert failure.value.side == "chip" and "Traceback" not in str(failure.value)
    physics = json.loads((tmp_path / "physics.json").read_text())
    assert physics["ended"] == "interrupted" and physics["rows"] == 0
    assert json.loads((tmp_path / "summary.json").read_text())["complete"] is False
