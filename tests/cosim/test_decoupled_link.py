"""The decoupled mode's UDP link: counters against known fault sequences, addresses, actuator hold."""

from __future__ import annotations

import socket

import numpy as np
import pytest

from robosoc.config.link import LinkConfig, LinkFaults, parse_faults
from robosoc.cosim.actuator_hold import ActuatorHold
from robosoc.cosim.datagram import Bye, ByeReason, Command, CommandBatch, Datagram, Hello, decode, encode
from robosoc.cosim.link import Address, LinkError, LinkLog, UdpLink, parse_address
from robosoc.cosim.link_faults import FaultInjector

LOOPBACK = Address("127.0.0.1", 0)


def data(seq: int) -> bytes:
    return encode(CommandBatch(seq * 1000, (Command(seq, seq * 1000, (seq % 256, 1, 2, 3)),)), seq)


def drain(link: UdpLink, until_bye: bool = True) -> list[Datagram]:
    got: list[Datagram] = []
    for _ in range(200):
        batch = link.receive(0.05)
        got += batch
        if until_bye and any(isinstance(d.body, Bye) for d in got):
            return got
        if not until_bye and not batch:
            return got
    raise AssertionError("no bye")


def test_counters_of_a_hand_made_sequence(tmp_path) -> None:
    sender = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sender.bind(("127.0.0.1", 0))
    stranger = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    host, port = sender.getsockname()
    receiver = UdpLink(LOOPBACK, "chip", log=LinkLog(tmp_path / "link.log"), peer=Address(host, port))
    to = ("127.0.0.1", receiver.address.port)
    wire = [data(0), data(1), data(1), data(3), data(2), b"xyz", data(4)[:30], data(6)]
    for d in wire:
        sender.sendto(d, to)
    stranger.sendto(data(5), to)  # from a third address: not the peer
    sender.sendto(encode(Bye(ByeReason.DONE, 8, 0)), to)
    got = drain(receiver)
    assert [d.seq for d in got if not isinstance(d.body, Bye)] == [0, 1, 3, 2, 6]
    c = receiver.counts
    # numbers 0..7 announced; 0, 1, 2, 3, 6 arrived; 4 truncated, 5 and 7 lost
    assert (c.received, c.duplicated, c.reordered, c.truncated, c.garbage, c.lost) == (5, 1, 1, 1, 1, 3)
    assert c.rejected == {"truncated": 1, "bad_magic": 1}
    assert receiver.foreign == 1
    receiver.close()
    log = (tmp_path / "link.log").read_text()
    for event in ("duplicate #1", "#2 arrived late", "rejected 3 bytes: bad_magic", "truncated", "not the peer",
                  "lost 2 datagram(s): #4..#5", "bye done data_sent=8",
                  "lost 1 datagram(s) at the end: #7..#7"):  # fmt: skip
        assert event in log, event
    sender.close()
    stranger.close()


FAULTS = LinkFaults(loss=0.1, duplicate=0.1, reorder=0.1, truncate=0.1, garbage=0.1)


def test_injected_faults_are_counted_by_the_receiver(tmp_path) -> None:
    receiver = UdpLink(LOOPBACK, "physics", log=LinkLog(tmp_path / "physics.log"))
    sender = UdpLink(LOOPBACK, "chip", FAULTS, seed=11, peer=receiver.address)
    sender.send_control(Hello(b"8 bytes!", 1))  # the physics side takes its peer from the hello
    assert [d.body for d in receiver.receive(1.0)] == [Hello(b"8 bytes!", 1)]
    for k in range(400):
        sender.send_data(CommandBatch(k, ()))
        if k % 10 == 9:
            drain(receiver, until_bye=False)
    sender.send_control(Bye(ByeReason.DONE, sender.sent, 0))  # sends the datagram still held back first
    drain(receiver)
    injected = sender.injector.injected
    assert min(injected.values()) > 0, injected  # every kind of fault happened
    c = receiver.counts
    assert c.duplicated == injected["duplicated"]
    assert c.reordered == injected["reordered"]
    assert c.truncated == injected["truncated"]
    assert c.garbage == injected["garbage"]
    assert c.lost == injected["lost"] + injected["truncated"]  # a truncated datagram's number is missing too
    assert c.received == 400 - c.lost
    assert receiver.foreign == 0
    sender.close()
    receiver.close()


def test_faults_follow_the_seed() -> None:
    def wire(seed: int) -> list[bytes]:
        injector = FaultInjector(FAULTS, np.random.default_rng(seed))
        return [w for k in range(200) for w in injector.plan(data(k))] + injector.flush()

    assert wire(3) == wire(3)
    assert wire(3) != wire(4)
    clean = FaultInjector(LinkFaults(), np.random.default_rng(0))
    assert [clean.plan(data(k)) for k in range(5)] == [[data(k)] for k in range(5)]


def test_garbage_is_never_mistaken_for_a_datagram() -> None:
    injector = FaultInjector(LinkFaults(garbage=1.0), np.random.default_rng(0))
    for k in range(300):
        garbage, real = injector.plan(data(k))
        assert decode(garbage).reason.counter == "garbage"  # type: ignore[union-attr]
        assert real == data(k)


def test_fault_rates_are_checked() -> None:
    assert parse_faults("loss=0.1, reorder=0.05") == LinkFaults(loss=0.1, reorder=0.05)
    for text, message in (
        ("loss=1.5", "loss: must be a rate between 0 and 1"),
        ("loss=nan", "loss: must be a rate"),
        ("lose=0.1", "NAME one of loss"),
        ("loss", "expected NAME=RATE"),
        ("loss=0.1,loss=0.2", "loss given twice"),
        ("loss=0.6,duplicate=0.6", "at most 1"),
    ):
        with pytest.raises(ValueError, match=message):
            parse_faults(text)
    with pytest.raises(ValueError, match="heartbeat_s: must be shorter than peer_timeout_s"):
        LinkConfig(peer_timeout_s=0.05, heartbeat_s=0.1)


def test_addresses() -> None:
    assert parse_address("127.0.0.1:5600", any_port=False) == Address("127.0.0.1", 5600)
    assert parse_address("[::1]:0", any_port=True) == Address("::1", 0)
    assert str(Address("::1", 7)) == "[::1]:7"
    for text, message in (
        ("127.0.0.1", "expected HOST:PORT"),
        ("127.0.0.1:0", "between 1 and 65535"),
        ("127.0.0.1:65536", "between 1 and 65535"),
        ("127.0.0.1:http", "must be a number"),
        ("::1:5600", "in brackets"),
        (":5600", "expected HOST:PORT"),
    ):
        with pytest.raises(ValueError, match=message):
            parse_address(text, any_port=False)


def test_an_address_in_use_or_not_of_this_machine() -> None:
    taken = UdpLink(LOOPBACK, "physics")
    with pytest.raises(LinkError, match="in use"):
        UdpLink(taken.address, "physics")
    taken.close()
    with pytest.raises(LinkError, match="not an address of this machine"):
        UdpLink(Address("192.0.2.1", 0), "physics")  # TEST-NET-1: never local
    with pytest.raises(LinkError, match="cannot resolve"):
        UdpLink(LOOPBACK, "chip", peer=Address("no-such-host.invalid", 5))


def test_zero_order_hold() -> None:
    hold = ActuatorHold("zoh", (0, 0, 0, 0))
    hold.schedule(3, (10, 20, 30, 40))
    hold.schedule(13, (50, 60, 70, 80))
    assert [hold.at(s)[0] for s in range(16)] == [0] * 3 + [10] * 10 + [50] * 3


def test_linear_hold_ramps_over_the_command_interval() -> None:
    hold = ActuatorHold("linear", (0, 0, 0, 0))
    hold.schedule(0, (100, 100, 100, 100))  # the first command: no interval yet, a step
    hold.schedule(10, (200, 0, 100, 255))  # 10 steps after it: a 10-step ramp
    hold.schedule(30, (0, 0, 0, 0))  # 20 steps later, from wherever the ramp is
    values = [hold.at(s) for s in range(32)]
    assert values[0] == values[9] == (100, 100, 100, 100)
    assert values[10] == (110, 90, 100, 116)  # 1/10 of the way (115.5 rounds to even)
    assert values[14] == (150, 50, 100, 178)  # 5/10: 177.5 -> 178
    assert values[19] == values[29] == (200, 0, 100, 255)
    assert values[30] == (190, 0, 95, 242)  # 1/20 of the way down from (200, 0, 100, 255)
    with pytest.raises(ValueError, match="after one for step 30"):
        hold.schedule(20, (1, 2, 3, 4))
