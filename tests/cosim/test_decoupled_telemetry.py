"""The physics side of the decoupled mode and the chip's telemetry (issue 32, item 4), against a
chip written here: the hello must name the project's telemetry, row k shows the newest entry of a
sample before k (the estimate's names in the estimate columns, the others as columns of their
own), and a telemetry datagram that does not hold a value per name is counted and refused.

Flights of five samples paced ``fast``: the physics steps a period once the chip has reported
reaching its end, so every entry sent before that report is in its row."""

from __future__ import annotations

import math
import threading
from pathlib import Path

import numpy as np

from robosoc.config.link import LinkConfig
from robosoc.config.scenario import ScenarioConfig
from robosoc.config.vehicle import vehicle_preset
from robosoc.control.flight import ROW_FIELDS
from robosoc.cosim.datagram import (
    Bye,
    ByeReason,
    Command,
    CommandBatch,
    Hello,
    SensorBatch,
    TelemetryBatch,
    TelemetryEntry,
    encode,
)
from robosoc.cosim.decoupled_physics import Ended, PhysicsOutcome, scenario_digest, serve_physics
from robosoc.cosim.link import Address, UdpLink
from robosoc.physics.clock import FlightClock

SCENARIO = ScenarioConfig(duration_s=0.05)
PERIOD_NS = FlightClock.of(SCENARIO).sample_period_ns
DIGEST = scenario_digest(SCENARIO, vehicle_preset(SCENARIO.vehicle))
NAMES = ("est_height", "jobs")
WAIT_S = 60


def _physics(tmp_path: Path, config: LinkConfig) -> tuple[threading.Thread, list[PhysicsOutcome], Address]:
    """The physics side in a thread, flying SCENARIO for a chip that must publish NAMES."""
    outcomes: list[PhysicsOutcome] = []
    listening = threading.Event()
    where: list[Address] = []

    def on_listen(address: Address) -> None:
        where.append(address)
        listening.set()

    def side() -> None:
        outcome = serve_physics(
            SCENARIO, vehicle_preset(SCENARIO.vehicle), config, Address("127.0.0.1", 0),
            log_path=tmp_path / "link-physics.log", telemetry=NAMES, on_listen=on_listen,
        )  # fmt: skip
        outcomes.append(outcome)

    thread = threading.Thread(target=side, daemon=True)
    thread.start()
    assert listening.wait(WAIT_S)
    return thread, outcomes, where[0]


def test_a_chip_naming_other_telemetry_or_of_another_version_is_refused(tmp_path: Path) -> None:
    thread, outcomes, address = _physics(tmp_path, LinkConfig(pace="fast", peer_timeout_s=2.0))
    chip = UdpLink(Address("127.0.0.1", 0), "chip", peer=address)
    chip.send_control(Hello(DIGEST, PERIOD_NS, ("est_height", "other")))
    thread.join(WAIT_S)
    chip.close()
    (outcome,) = outcomes
    assert outcome.ended == Ended.MISMATCH and len(outcome.rows) == 0
    assert outcome.message == (
        "the chip's firmware publishes the telemetry (est_height, other), the scenario's project declares "
        "(est_height, jobs) (give both sides the same project)"
    )

    thread, outcomes, address = _physics(tmp_path, LinkConfig(pace="fast", connect_timeout_s=1.0))
    chip = UdpLink(Address("127.0.0.1", 0), "chip", peer=address)
    old = bytearray(encode(Hello(DIGEST, PERIOD_NS, NAMES)))
    old[4] = 1  # a robosoc of version 1 (before telemetry) says hello
    chip.sock.sendto(bytes(old), chip.peer)
    thread.join(WAIT_S)
    chip.close()
    (outcome,) = outcomes
    assert outcome.ended == Ended.PEER_LOST
    assert outcome.message == (
        "no hello from a chip within --connect-timeout 1 s (1 datagrams of another robosoc version came: "
        "give both sides the same version)"
    )
    assert "bad_version: version 1, expected 2" in (tmp_path / "link-physics.log").read_text()


def test_entries_fill_the_rows_and_a_malformed_datagram_is_counted(tmp_path: Path) -> None:
    """At reading k the chip sends the entry of sample k-1 (height k-1 / 2, k-1 jobs) and a
    telemetry datagram of one value per entry (refused), then reports reaching t_k+1."""
    thread, outcomes, address = _physics(tmp_path, LinkConfig(pace="fast", peer_timeout_s=2.0))
    chip = UdpLink(Address("127.0.0.1", 0), "chip", peer=address)
    chip.send_control(Hello(DIGEST, PERIOD_NS, NAMES))
    answered = -1
    while thread.is_alive():
        for d in chip.receive(0.05):
            if isinstance(d.body, SensorBatch):
                for r in d.body.readings:
                    if r.k <= answered:
                        continue
                    answered = r.k
                    if r.k:
                        j = r.k - 1
                        entry = TelemetryEntry(j, j * PERIOD_NS, (j / 2, float(j)))
                        chip.send_data(TelemetryBatch(r.t_ns, (entry,)))
                    chip.send_data(TelemetryBatch(r.t_ns, (TelemetryEntry(r.k, r.t_ns, (1.0,)),)))
                    command = Command(r.k, r.t_ns + 1000, (10, 10, 10, 10))
                    chip.send_data(CommandBatch(r.t_ns + PERIOD_NS, (command,)))
            elif isinstance(d.body, Bye):
                chip.send_control(Bye(ByeReason.DONE, chip.sent, 5 * PERIOD_NS))
    thread.join(WAIT_S)
    chip.close()
    (outcome,) = outcomes
    assert outcome.ended == Ended.DONE, outcome.message
    assert len(outcome.rows) == 5
    nan = math.nan
    np.testing.assert_array_equal(outcome.telemetry["jobs"], [nan, 0.0, 1.0, 2.0, 3.0])
    np.testing.assert_array_equal(outcome.rows[:, ROW_FIELDS.index("est_height")], [nan, 0.0, 0.5, 1.0, 1.5])
    assert np.isnan(outcome.rows[:, ROW_FIELDS.index("est_qw")]).all()  # not published: unknown
    assert list(outcome.telemetry) == ["jobs"]  # the estimate's names are no columns of their own
    assert outcome.telemetry_counts == {"received": 4, "refused": 5}
    log = (tmp_path / "link-physics.log").read_text()
    assert "refused: entries of 1 values, the hello named 2" in log
