"""The decoupled link's settings: defaults, every bound on both sides, every message exactly."""

from __future__ import annotations

import math

import pytest

from robosoc.config.link import FAULT_NAMES, MAX_RESEND, LinkConfig, LinkFaults, parse_faults


def test_defaults_are_the_documented_ones():
    link = LinkConfig()
    assert (link.pace, link.hold, link.peer_timeout_s, link.connect_timeout_s, link.resend, link.heartbeat_s) == (
        "realtime",
        "zoh",
        5.0,
        300.0,
        2,
        0.02,
    )
    assert link.faults == LinkFaults() and not link.faults.any
    assert FAULT_NAMES == ("loss", "duplicate", "reorder", "truncate", "garbage")


def test_every_bound_is_inclusive():
    LinkConfig(pace="fast", hold="linear", peer_timeout_s=3600, connect_timeout_s=0.05, resend=0, heartbeat_s=0.001)
    LinkConfig(peer_timeout_s=0.05, connect_timeout_s=3600.0, resend=MAX_RESEND, heartbeat_s=0.049)
    LinkConfig(peer_timeout_s=2.0, heartbeat_s=1.0)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"pace": "slow"}, "pace: must be one of realtime, fast, got 'slow'"),
        ({"hold": "cubic"}, "hold: must be one of zoh, linear, got 'cubic'"),
        ({"peer_timeout_s": 0.049}, "peer_timeout_s: must be between 0.05 and 3600 s, got 0.049"),
        ({"peer_timeout_s": 3600.5}, "peer_timeout_s: must be between 0.05 and 3600 s, got 3600.5"),
        ({"peer_timeout_s": math.nan}, "peer_timeout_s: must be between 0.05 and 3600 s, got nan"),
        ({"peer_timeout_s": "5"}, "peer_timeout_s: must be between 0.05 and 3600 s, got '5'"),
        ({"connect_timeout_s": 0.01}, "connect_timeout_s: must be between 0.05 and 3600 s, got 0.01"),
        ({"connect_timeout_s": 4000}, "connect_timeout_s: must be between 0.05 and 3600 s, got 4000"),
        ({"connect_timeout_s": math.inf}, "connect_timeout_s: must be between 0.05 and 3600 s, got inf"),
        ({"heartbeat_s": 0.0009}, "heartbeat_s: must be between 0.001 and 1 s, got 0.0009"),
        ({"heartbeat_s": 1.5, "peer_timeout_s": 10.0}, "heartbeat_s: must be between 0.001 and 1 s, got 1.5"),
        ({"heartbeat_s": "0.1"}, "heartbeat_s: must be between 0.001 and 1 s, got '0.1'"),
        (
            {"heartbeat_s": 0.5, "peer_timeout_s": 0.5},
            "heartbeat_s: must be shorter than peer_timeout_s (0.5 s), got 0.5",
        ),
        ({"resend": -1}, f"resend: must be between 0 and {MAX_RESEND}, got -1"),
        ({"resend": MAX_RESEND + 1}, f"resend: must be between 0 and {MAX_RESEND}, got {MAX_RESEND + 1}"),
        ({"resend": True}, f"resend: must be between 0 and {MAX_RESEND}, got True"),
        ({"resend": 2.0}, f"resend: must be between 0 and {MAX_RESEND}, got 2.0"),
    ],
)
def test_bad_settings_are_refused_with_the_field_and_the_range(kwargs, message):
    with pytest.raises(ValueError) as info:
        LinkConfig(**kwargs)
    assert str(info.value) == message


def test_fault_rates_are_checked_one_by_one_and_the_exclusive_ones_together():
    assert LinkFaults(loss=0.25, duplicate=0.25, reorder=0.25, truncate=0.25, garbage=1.0).any
    assert LinkFaults(garbage=0.5).as_dict() == {
        "loss": 0.0,
        "duplicate": 0.0,
        "reorder": 0.0,
        "truncate": 0.0,
        "garbage": 0.5,
    }
    for name in FAULT_NAMES:
        assert LinkFaults(**{name: 0.5}).any
        with pytest.raises(ValueError) as info:
            LinkFaults(**{name: 1.5})
        assert str(info.value) == f"{name}: must be a rate between 0 and 1, got 1.5"
        with pytest.raises(ValueError) as info:
            LinkFaults(**{name: -0.1})
        assert str(info.value) == f"{name}: must be a rate between 0 and 1, got -0.1"
    with pytest.raises(ValueError) as info:
        LinkFaults(loss=0.5, truncate=0.6, garbage=0.9)
    assert str(info.value) == (
        "loss: loss + duplicate + reorder + truncate must be at most 1 (one fault per datagram), got 1.1"
    )


def test_parse_faults_reads_names_and_rates_and_names_what_is_wrong():
    assert parse_faults(" loss = 0.1 ,garbage=1") == LinkFaults(loss=0.1, garbage=1.0)
    cases = {
        "loss": "expected NAME=RATE[,NAME=RATE...] with NAME one of loss, duplicate, reorder, truncate, garbage, "
        "got 'loss'",
        "drop=0.1": "expected NAME=RATE[,NAME=RATE...] with NAME one of loss, duplicate, reorder, truncate, garbage, "
        "got 'drop=0.1'",
        "loss=0.1,loss=0.2": "loss given twice in 'loss=0.1,loss=0.2'",
        "reorder= lots": "reorder: must be a rate between 0 and 1, got 'lots'",
        "truncate=2": "truncate: must be a rate between 0 and 1, got 2.0",
    }
    for text, message in cases.items():
        with pytest.raises(ValueError) as info:
            parse_faults(text)
        assert str(info.value) == message
