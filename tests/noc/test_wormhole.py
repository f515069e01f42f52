"""Per-output arbiters (the idealised router): wormhole switching, round-robin arbitration and
back-pressure against hand-derived cycle counts; the credit invariant in both router models.

(The Hermes switch controller under contention: test_hermes.py.)
"""

import numpy as np
import pytest

from robosoc.chip.noc import Mesh
from robosoc.config.chip import ChipConfig, NocConfig
from robosoc.kernels import noc as k


@pytest.mark.parametrize("rlat", [1, 2, 6])
@pytest.mark.parametrize("depth", [4, 16])
def test_held_output_blocks_until_the_tail_passes(rlat, depth):
    """3x1 mesh. A: (0,0) -> (2,0), 20 flits from cycle 0; B: (1,0) -> (2,0), 6 flits from cycle 2R + 2.

    A's header leaves router 1 through EAST in cycle 2 + 2R and its tail in 21 + 2R, so A holds that
    output until then. B's header (requesting from cycle 3R + 3) gets EAST in cycle 22 + 2R. In
    router 2 it queues behind A's flits; A's tail leaves router 2 in cycle 22 + 3R, so B's header is at
    the head from 23 + 3R, waits R cycles, enters the receive memory in 23 + 4R and B's tail 5 cycles
    later. A itself is untouched: 3(R + 1) + 19.
    """
    noc = NocConfig(routing_latency=rlat, buffer_depth=depth, arbiter="per-output")
    cfg = ChipConfig(width=3, height=1, noc=noc)
    mesh = Mesh(cfg)
    a = mesh.inject((0, 0), (2, 0), [1] * 18, at_cycle=0)
    b = mesh.inject((1, 0), (2, 0), [2] * 4, at_cycle=2 * rlat + 2)
    mesh.run(500)
    got = {d.flits[2]: d.cycle for d in mesh.deliveries()}
    assert got == {1: 3 * (rlat + 1) + 19, 2: 28 + 4 * rlat}
    assert mesh.packet(a).start == 0 and mesh.packet(b).start == 2 * rlat + 2

    alone = Mesh(cfg)
    alone.inject((1, 0), (2, 0), [2] * 4, at_cycle=2 * rlat + 2)
    alone.run(500)
    assert [d.cycle for d in alone.deliveries()] == [2 * rlat + 2 + 2 * (rlat + 1) + 5]


def test_round_robin_per_output():
    """Four headers request NORTH of router (1,1) in the same cycle 2R + 2: from EAST (sent by (2,1)),
    WEST ((0,1)), SOUTH ((1,0)), each one hop away and sent at cycle 0, and LOCAL ((1,1) itself, sent
    at R + 1). The arbiter starts at input 0 and then continues after each winner, so the order is
    EAST, WEST, SOUTH, LOCAL. The first tail reaches (1,2)'s receive memory at 3R + 2 + L; each next
    header must reach the head of (1,2)'s SOUTH buffer and wait R there, so deliveries are L + R apart.
    """
    rlat, length = 2, 8
    cfg = ChipConfig(width=3, height=3, noc=NocConfig(routing_latency=rlat, arbiter="per-output"))
    mesh = Mesh(cfg, tag_packets=True)
    dst = (1, 2)
    payload = [0] * (length - 5)
    for src in [(2, 1), (0, 1), (1, 0)]:
        mesh.inject(src, dst, payload, at_cycle=0)
    mesh.inject((1, 1), dst, payload, at_cycle=rlat + 1)
    mesh.run(500)
    got = [(d.src, d.cycle) for d in mesh.deliveries()]
    first = 3 * rlat + 2 + length
    assert got == [
        ((2, 1), first),
        ((0, 1), first + (length + rlat)),
        ((1, 0), first + 2 * (length + rlat)),
        ((1, 1), first + 3 * (length + rlat)),
    ]


def test_back_pressure_stops_the_source_and_resumes_exactly():
    """3x1 mesh, buffers of 4, R = 2, receive memories freed by software only.

    P1 (5 flits, cycle 0) arrives at cycle 3 * 3 + 4 = 13 and stays in (2,0)'s receive memory. P2
    (40 flits) follows from cycle 5; with the receive memory held, its flits fill the three buffers of
    the path (local input of (0,0), WEST of (1,0) and of (2,0)): exactly 12 flits leave the NI and then
    everything stops. Freed before cycle 200, the waiting header moves in cycle 200 and the other 39
    flits follow one per cycle: delivered in cycle 239, intact. The freed slot travels back one hop per
    cycle as a credit (router 1 sends in 201, router 0 in 202), so the NI resumes in cycle 203 and injects
    the last of the remaining 28 flits in cycle 230. P2's header crosses router 0 in 10 and router 1 in
    13 (each time at the head 1 cycle after P1's tail left, plus R), reaches the head of router 2's buffer
    in 14 and is granted the LOCAL output in 16 with the receive memory held: it would cross in its grant
    cycle and the RTL would lose it (counted once).
    """
    cfg = ChipConfig(width=3, height=1, noc=NocConfig(routing_latency=2, buffer_depth=4, arbiter="per-output"))
    mesh = Mesh(cfg, rx_free_delay=None)
    mesh.inject((0, 0), (2, 0), [11, 12, 13], at_cycle=0)
    p2_payload = list(range(100, 138))
    p2 = mesh.inject((0, 0), (2, 0), p2_payload, at_cycle=0)
    mesh.run(16)
    assert mesh.rtl_lost_headers == 0
    mesh.run(17)
    assert mesh.rtl_lost_headers == 1
    mesh.run(200)
    (d1,) = mesh.deliveries()
    assert d1.cycle == 13 and d1.payload == (11, 12, 13) and mesh.rx_held((2, 0))
    st = mesh.state
    src = cfg.tile_index((0, 0))
    assert mesh.packet(p2).start == 5 and mesh.packet(p2).end is None
    assert st.tile[src, k.T_SEND_POS] == 12
    assert st.glob[k.G_INFLIGHT] == 12
    assert st.port[:, :, k.P_COUNT].tolist() == [[0, 0, 0, 0, 4], [0, 4, 0, 0, 0], [0, 4, 0, 0, 0]]
    assert st.port[0, k.EAST, k.P_CREDIT] == 0 and st.port[1, k.EAST, k.P_CREDIT] == 0
    assert not mesh.idle

    mesh.free_rx((2, 0))
    mesh.run(400)
    d2 = mesh.deliveries()[1]
    assert d2.cycle == 239 and d2.first_cycle == 200 and d2.payload == tuple(p2_payload)
    assert mesh.packet(p2).end == 230
    assert mesh.rtl_lost_headers == 1


@pytest.mark.parametrize(
    "noc", [NocConfig(buffer_depth=3), NocConfig(buffer_depth=3, routing_latency=1, arbiter="per-output")]
)
def test_credits_equal_free_downstream_space_after_traffic(noc):
    cfg = ChipConfig(width=3, height=3, noc=noc)
    mesh = Mesh(cfg)
    rng = np.random.default_rng(5)
    for i in range(60):
        src, dst = rng.choice(9, size=2, replace=False)
        mesh.inject(cfg.tile_xy(int(src)), cfg.tile_xy(int(dst)), [i] * int(rng.integers(1, 20)), at_cycle=i)
    # check the credit invariant at many intermediate points
    for until in range(5, 400, 7):
        mesh.run(until)
        st = mesh.state
        for t in range(9):
            x, y = cfg.tile_xy(t)
            for o, (dx, dy) in enumerate([(1, 0), (-1, 0), (0, 1), (0, -1)]):
                if cfg.contains((x + dx, y + dy)):
                    n = cfg.tile_index((x + dx, y + dy))
                    assert st.port[t, o, k.P_CREDIT] == 3 - st.port[n, o ^ 1, k.P_COUNT]
            assert st.tile[t, k.T_NI_CREDIT] == 3 - st.port[t, k.LOCAL, k.P_COUNT]
    mesh.run_until_idle(limit=5000)
    assert len(mesh.deliveries()) == 60
