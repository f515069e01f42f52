"""Single-packet latency against the hand-derived formula, and per-port counters of one packet.

Derivation (docs/noc.md): the NI moves flit 0 into the source router in cycle s; it is at the head of
that buffer from s + 1.

* Hermes (platform.md §4, measured on the RTL): the buffer raises its request in s + 1, the idle switch
  controller sees it in s + 1 [S1], selects in s + 2 [S2], routes and checks in s + 3 [S3], connects in
  s + 4 [S5], and the header crosses in s + 5 [S7]: 5 cycles per router, R = 4.
* Per-output: the header waits R cycles at the head and crosses in s + 1 + R.

Every router on the path (hops + 1 of them, the last one ejecting into the receive memory) costs the
header R + 1 cycles, and the L - 1 flits behind it follow one per cycle, so the last flit is written into
the receive memory in cycle s + (hops + 1)(R + 1) + L - 1; on the RTL: s + 5(h + 1) + L - 1. (Hermes with
2-flit buffers is slower, every flit running its buffer empty: tests/noc/test_read_pointer.py.)
"""

import pytest

from robosoc.chip.noc import Mesh, NocError
from robosoc.config.chip import ChipConfig, NocConfig
from robosoc.kernels import noc as k

ROUTES = [  # 1 to 6 hops on a 4x4 (0 hops would be a packet to its own tile: an error, see below)
    ((0, 0), (1, 0)),
    ((1, 1), (1, 2)),
    ((0, 0), (2, 1)),
    ((3, 0), (0, 2)),
    ((3, 2), (0, 0)),
    ((0, 0), (3, 3)),
    ((3, 3), (0, 0)),
    ((2, 3), (2, 0)),
]


def expected_cycle(start: int, hops: int, rlat: int, length: int) -> int:
    return start + (hops + 1) * (rlat + 1) + length - 1


MODES = [("hermes", 4, depth) for depth in (3, 4, 8, 16)] + [
    ("per-output", rlat, depth) for rlat in (0, 2, 6) for depth in (2, 3, 16)
]


@pytest.mark.parametrize(("arbiter", "rlat", "depth"), MODES)
def test_single_packet_latency_formula(arbiter, rlat, depth):
    cfg = ChipConfig(width=4, height=4, noc=NocConfig(buffer_depth=depth, routing_latency=rlat, arbiter=arbiter))
    for src, dst in ROUTES:
        hops = abs(src[0] - dst[0]) + abs(src[1] - dst[1])
        for length in (3, 4, 17, 64):
            for start in (0, 37):
                mesh = Mesh(cfg)
                payload = [(7 * i + length) & 0xFFFF for i in range(length - 2)]
                pid = mesh.inject(src, dst, payload, at_cycle=start)
                mesh.run_until_idle(limit=2000)
                (d,) = mesh.deliveries()
                assert d.dst == dst and d.flits == ((dst[0] << 4) | dst[1], length - 2, *payload)
                assert mesh.packet(pid).start == start
                assert d.cycle == expected_cycle(start, hops, rlat, length), (src, dst, length, start)
                assert d.cycle - start == mesh.single_packet_latency(hops, length)
                # the header reaches the receive memory L - 1 cycles before the tail
                assert d.first_cycle == d.cycle - (length - 1)
                assert mesh.rtl_lost_headers == 0


def test_hermes_idle_latency_over_0_to_6_hops_by_hand():
    """RTL formula s + 5(h + 1) + L - 1 written out for s = 10 on a 4x4, L from 3 to 64.

    h = 0 is a packet to its own tile: on the RTL it locks the local output for good, here an error.
    """
    cfg = ChipConfig(width=4, height=4)
    cases = {  # (dst, L): last flit cycle
        ((1, 0), 3): 10 + 10 + 2,  # 1 hop
        ((1, 1), 10): 10 + 15 + 9,  # 2 hops
        ((2, 1), 64): 10 + 20 + 63,  # 3 hops
        ((2, 2), 33): 10 + 25 + 32,  # 4 hops
        ((3, 2), 5): 10 + 30 + 4,  # 5 hops
        ((3, 3), 64): 10 + 35 + 63,  # 6 hops
    }
    for (dst, length), cycle in cases.items():
        mesh = Mesh(cfg)
        mesh.inject((0, 0), dst, [1] * (length - 2), at_cycle=10)
        mesh.run_until_idle(limit=1000)
        assert [d.cycle for d in mesh.deliveries()] == [cycle], (dst, length)
    mesh = Mesh(cfg)
    with pytest.raises(ValueError, match="own tile"):
        mesh.inject((2, 2), (2, 2), [1], at_cycle=0)


def test_packets_shorter_than_3_flits_are_errors():
    """On the RTL a packet of size 0 keeps its connection open and swallows the next packet."""
    mesh = Mesh(ChipConfig(width=3, height=1))
    with pytest.raises(ValueError, match=r"packet from \(0, 0\) of 2 flits; at least 3"):
        mesh.inject((0, 0), (1, 0), [], at_cycle=0)
    # a 2-flit packet smuggled into the queue is reported by the kernel, naming the tile
    pid = mesh.inject((1, 0), (2, 0), [5], at_cycle=3)
    mesh.state.queue[pid, k.Q_LEN] = 2
    mesh.state.queue[pid, k.Q_FLITS + 1] = 0  # size flit
    with pytest.raises(NocError, match=r"cycle 3, tile \(1, 0\): packet shorter than 3 flits"):
        mesh.run(100)


def test_default_latency_numbers():
    """Default platform (Hermes, 5 cycles per router): one hop, 10 flits: 2 * 5 + 9 = 19 cycles; six hops:
    7 * 5 + 9 = 44."""
    mesh = Mesh(ChipConfig(width=4, height=4))
    mesh.inject((0, 0), (1, 0), list(range(8)), at_cycle=0)
    mesh.inject((0, 0), (3, 3), list(range(8)), at_cycle=100)
    mesh.run(1000)
    assert [d.cycle for d in mesh.deliveries()] == [19, 144]


@pytest.mark.parametrize(("arbiter", "rlat"), [("hermes", 4), ("per-output", 3)])
def test_port_counters_of_one_packet(arbiter, rlat):
    """3x1 mesh, (0,0) -> (2,0), L flits from cycle 0: every buffer on the path sees L flits and holds a
    flit during R + L cycles (header waits R, then L flits leave one per cycle)."""
    length = 12
    mesh = Mesh(ChipConfig(width=3, height=1, noc=NocConfig(routing_latency=rlat, arbiter=arbiter)))
    mesh.inject((0, 0), (2, 0), list(range(length - 2)), at_cycle=0)
    mesh.run(100)
    c = mesh.counters()
    east, west, local = 0, 1, 4
    assert c.cycles == 100
    assert c.flits_in[0, 0, local] == c.flits_in[1, 0, west] == c.flits_in[2, 0, west] == length
    assert c.flits_out[0, 0, east] == c.flits_out[1, 0, east] == c.flits_out[2, 0, local] == length
    assert c.flits_in.sum() == 3 * length and c.flits_out.sum() == 3 * length
    busy = [c.busy_cycles[0, 0, local], c.busy_cycles[1, 0, west], c.busy_cycles[2, 0, west]]
    assert busy == [rlat + length] * 3
    assert c.busy_cycles.sum() == 3 * (rlat + length)
    assert c.idle_cycles[1, 0, west] == 100 - (rlat + length) and c.idle_cycles[1, 0, east] == 100
    assert c.router_busy_cycles[:, 0].tolist() == [rlat + length] * 3
    assert c.rtl_lost_headers.sum() == 0
