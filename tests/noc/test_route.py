"""Which routers a packet crosses: XY routing (first along x, then along y), seen in per-router counters.

Latency does not tell XY from YX (both take |dx| + |dy| hops), so each packet's path is read off the
flit counters of every input and output port of every router and compared with the XY path computed
here from the definition (docs/noc.md, "Routing"): east/west until the column matches, then
north (y + 1) / south until the row matches, then the local port.
"""

from __future__ import annotations

import numpy as np
import pytest

from robosoc.chip.noc import PORT_NAMES, Mesh
from robosoc.config.chip import ChipConfig, NocConfig

EAST, WEST, NORTH, SOUTH, LOCAL = (PORT_NAMES.index(p) for p in ("east", "west", "north", "south", "local"))
STEP = {EAST: (1, 0), WEST: (-1, 0), NORTH: (0, 1), SOUTH: (0, -1)}
OPPOSITE = {EAST: WEST, WEST: EAST, NORTH: SOUTH, SOUTH: NORTH}


def xy_path(src: tuple[int, int], dst: tuple[int, int]) -> list[tuple[tuple[int, int], int, int]]:
    """(router, input port, output port) of every router on the XY route."""
    hops = []
    (x, y), entry = src, LOCAL
    while (x, y) != dst:
        along_x = EAST if dst[0] > x else WEST
        along_y = NORTH if dst[1] > y else SOUTH
        out = along_x if x != dst[0] else along_y  # x first
        hops.append(((x, y), entry, out))
        dx, dy = STEP[out]
        (x, y), entry = (x + dx, y + dy), OPPOSITE[out]
    hops.append((dst, entry, LOCAL))
    return hops


ROUTES = [
    ((0, 0), (3, 3)),  # XY: along y = 0, then up column 3; YX would go up column 0
    ((3, 3), (0, 0)),
    ((0, 3), (3, 0)),
    ((3, 0), (0, 3)),
    ((1, 2), (3, 0)),
    ((2, 0), (0, 2)),
    ((2, 1), (2, 3)),  # same column: only y moves
    ((3, 2), (1, 2)),  # same row: only x moves
]


def test_the_xy_paths_differ_from_yx() -> None:
    # the test would not notice YX on routes where both orders cross the same routers
    for src, dst in ROUTES[:6]:
        yx = [(r[1], r[0]) for r, _, _ in xy_path((src[1], src[0]), (dst[1], dst[0]))]
        assert {r for r, _, _ in xy_path(src, dst)} != set(yx), (src, dst)


@pytest.mark.parametrize("arbiter", ["hermes", "per-output"])
@pytest.mark.parametrize(("src", "dst"), ROUTES)
def test_a_packet_crosses_exactly_the_routers_and_ports_of_its_xy_route(
    arbiter: str, src: tuple[int, int], dst: tuple[int, int]
) -> None:
    length = 9
    mesh = Mesh(ChipConfig(width=4, height=4, noc=NocConfig(arbiter=arbiter, routing_latency=4)))
    mesh.inject(src, dst, list(range(length - 2)), at_cycle=0)
    mesh.run_until_idle(limit=1000)
    (delivery,) = mesh.deliveries()
    assert delivery.dst == dst
    c = mesh.counters()
    want_in = np.zeros_like(c.flits_in)
    want_out = np.zeros_like(c.flits_out)
    for (x, y), port_in, port_out in xy_path(src, dst):
        want_in[x, y, port_in] = length
        want_out[x, y, port_out] = length
    np.testing.assert_array_equal(c.flits_in, want_in)
    np.testing.assert_array_equal(c.flits_out, want_out)
    on_path = {router for router, _, _ in xy_path(src, dst)}
    busy = {(x, y) for x in range(4) for y in range(4) if c.router_busy_cycles[x, y] > 0}
    assert busy == on_path
    assert mesh.counters().flits_in.sum() == length * len(on_path)


def test_crossing_packets_keep_their_own_xy_routes() -> None:
    """Two packets at once on opposite corners: the counters add up path by path."""
    mesh = Mesh(ChipConfig(width=4, height=4))
    mesh.inject((0, 0), (3, 3), [1, 2, 3], at_cycle=0)
    mesh.inject((3, 0), (0, 3), [4, 5, 6, 7], at_cycle=2)
    mesh.run_until_idle(limit=1000)
    assert sorted(d.dst for d in mesh.deliveries()) == [(0, 3), (3, 3)]
    c = mesh.counters()
    want = np.zeros_like(c.flits_out)
    for (src, dst), length in ((((0, 0), (3, 3)), 5), (((3, 0), (0, 3)), 6)):
        for (x, y), _, port_out in xy_path(src, dst):
            want[x, y, port_out] += length
    np.testing.assert_array_equal(c.flits_out, want)
