"""Single-packet latency against the hand-derived formula, and per-port counters of one packet.

Derivation (docs/noc.md): the NI moves flit 0 into the source router in cycle s; it is at the head of
that buffer from s + 1, waits R cycles and crosses to the next router in cycle s + 1 + R. Every router
on the path (hops + 1 of them, the last one ejecting into the receive memory) costs the header R + 1
cycles, and the L - 1 flits behind it follow one per cycle, so the last flit is written into the
receive memory in cycle s + (hops + 1)(R + 1) + L - 1.
"""

import pytest

from robosoc.chip.noc import Mesh
from robosoc.config.chip import ChipConfig, NocConfig


def expected_cycle(start: int, hops: int, rlat: int, length: int) -> int:
    return start + (hops + 1) * (rlat + 1) + length - 1


@pytest.mark.parametrize("rlat", [0, 2, 6])
@pytest.mark.parametrize("depth", [2, 3, 16])
def test_single_packet_latency_formula(rlat, depth):
    cfg = ChipConfig(width=4, height=4, noc=NocConfig(buffer_depth=depth, routing_latency=rlat))
    routes = [
        ((0, 0), (1, 0)),
        ((1, 1), (1, 2)),
        ((0, 0), (2, 1)),
        ((3, 0), (0, 2)),
        ((0, 0), (3, 3)),
        ((3, 3), (0, 0)),
        ((2, 3), (2, 0)),
    ]
    for src, dst in routes:
        hops = abs(src[0] - dst[0]) + abs(src[1] - dst[1])
        for length in (2, 3, 17, 64):
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


def test_default_latency_numbers():
    """Default platform (R = 6): one hop, 10 flits: 2 * 7 + 9 = 23 cycles; six hops: 7 * 7 + 9 = 58."""
    mesh = Mesh(ChipConfig(width=4, height=4))
    mesh.inject((0, 0), (1, 0), list(range(8)), at_cycle=0)
    mesh.inject((0, 0), (3, 3), list(range(8)), at_cycle=100)
    mesh.run(1000)
    assert [d.cycle for d in mesh.deliveries()] == [23, 158]


def test_port_counters_of_one_packet():
    """3x1 mesh, (0,0) -> (2,0), L flits from cycle 0: every buffer on the path sees L flits and holds a
    flit during R + L cycles (header waits R, then L flits leave one per cycle)."""
    rlat, length = 3, 12
    mesh = Mesh(ChipConfig(width=3, height=1, noc=NocConfig(routing_latency=rlat)))
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
