"""The Hermes switch controller under contention, against cycle numbers derived by hand from platform.md §4.

Facts used (measured on the RTL): a buffer raises its request the cycle after it is idle and holds or
receives a header (a header that arrives in cycle a at an idle buffer requests from a + 1; one queued
behind the previous tail, which left in cycle c, requests from c + 2). One state machine per router:
S1 (sees a request) -> S2 (selects among the requests up in that cycle, in cyclic order E, W, N, S, L
after the last selected input; after reset after E) -> S3 (routes, checks the output is free; if not,
back to S1: 3 cycles) -> S5 (connects) -> S7 (the header crosses) -> S1. An output whose tail crossed
in cycle c is free from c + 2. Body flits follow at one per cycle.

So, uncontended: a packet injected in cycle s requests in s + 1, [S1 s+1, S2 s+2, S3 s+3, S5 s+4] and its
header crosses in s + 5; at the next router it arrives in s + 5 and requests in s + 6, and so on.
"""

import pytest

from robosoc.chip.noc import Mesh
from robosoc.config.chip import ChipConfig, NocConfig
from robosoc.kernels import noc as k


def line(depth: int = 16) -> ChipConfig:
    return ChipConfig(width=3, height=1, noc=NocConfig(buffer_depth=depth))


def deliveries(mesh: Mesh) -> list[tuple[tuple[int, int], int]]:
    return [(d.src, d.cycle) for d in mesh.deliveries()]


def test_two_inputs_to_one_output_in_the_same_cycle():
    """A: (0,0) -> (2,0), 6 flits at 0; B: (1,0) -> (2,0), 4 flits at 5. Router 1's WEST (A) and LOCAL (B)
    both request EAST from cycle 6.

    Router 1: S1 6, S2 7 picks WEST (first after E), S3 8, S5 9, A's header crosses in 10, its tail in 15,
    so EAST is free from 17. S1 11, S2 12 picks LOCAL, S3 13 fails (held); S1 14, S2 15, S3 16 fails
    (the tail crossed in 15: free only from 17); S1 17, S2 18, S3 19 succeeds, S5 20, B crosses in 21.
    Router 2: A arrives 10, requests 11, crosses into the receive memory 15, tail 20 (= 0 + 5*3 + 5).
    A's tail leaves router 2's WEST buffer in 20, B's header arrives in 21 at an idle buffer: request 22,
    S3 24 (LOCAL free from 22), crosses 26, tail 29.
    """
    mesh = Mesh(line())
    mesh.inject((0, 0), (2, 0), [1, 1, 1, 1], at_cycle=0)  # 6 flits
    mesh.inject((1, 0), (2, 0), [2, 2], at_cycle=5)  # 4 flits
    mesh.run(12)  # through cycle 11: the last selection (in 7) was WEST
    assert mesh.state.tile[1, k.T_SC_SEL] == k.WEST
    mesh.run(13)  # the selection in 12 picked LOCAL
    assert mesh.state.tile[1, k.T_SC_SEL] == k.LOCAL
    mesh.run(200)
    assert [(d.flits[2], d.cycle) for d in mesh.deliveries()] == [(1, 20), (2, 29)]


def test_the_later_request_wins_when_the_pointer_says_so():
    """Router 1 after reset (pointer at E: order W, N, S, L, E).

    Case 1: B at (1,0) injected in 4 requests LOCAL -> EAST from 5; A from (0,0) injected in 0 requests
    WEST -> EAST from 6. S1 5 (B), S2 6 sees both and picks WEST: A, which asked a cycle later, wins.
    S3 7, S5 8, A crosses in 9 (4 cycles after it arrived) and its tail (6 flits) in 14, EAST free from 16.
    Router 2: A arrives 9, requests 10, crosses 14, tail 19. B: S1 10, S2 11, S3 12 fails, S1 13, S2 14,
    S3 15 fails (free from 16), S1 16, S2 17, S3 18, S5 19, crosses 20. Router 2's WEST buffer was left
    by A's tail in 19, B arrives 20 at an idle buffer: requests 21, crosses 25, tail (4 flits) 28.

    Case 2 (mirrored on the pointer): B at (1,0) to (0,0) requests LOCAL -> WEST from 5, A from (2,0)
    to (0,0) requests EAST -> WEST from 6: S2 6 picks LOCAL (before E), the earlier request wins. B
    crosses 9, tail (4 flits) 12; router 0: arrives 9, crosses 14, tail 17. A: S1 10, S2 11, S3 12 fails
    (tail crossing), S1 13, S2 14, S3 15 (free from 14), S5 16, crosses 17. Router 0's EAST buffer: B's
    tail leaves it in 17, the cycle A's header arrives: queued behind the tail, A requests only from 19;
    S1 19, S2 20, S3 21, S5 22, crosses 23, tail (6 flits) 28.
    """
    mesh = Mesh(line())
    mesh.inject((0, 0), (2, 0), [1] * 4, at_cycle=0)
    mesh.inject((1, 0), (2, 0), [2] * 2, at_cycle=4)
    mesh.run(200)
    assert [(d.flits[2], d.cycle) for d in mesh.deliveries()] == [(1, 19), (2, 28)]

    mesh = Mesh(line())
    mesh.inject((2, 0), (0, 0), [1] * 4, at_cycle=0)
    mesh.inject((1, 0), (0, 0), [2] * 2, at_cycle=4)
    mesh.run(200)
    assert [(d.flits[2], d.cycle) for d in mesh.deliveries()] == [(2, 17), (1, 28)]


def test_four_inputs_to_one_output_after_reset():
    """3x3 mesh, destination (1,2): router (1,1)'s EAST (sent by (2,1)), WEST ((0,1)), SOUTH ((1,0)), all
    injected in 0, and LOCAL (injected in 5) all request NORTH from cycle 6; 7-flit packets.

    Router (1,1): S2 7 picks W (first after E), crosses 10, tail 16, NORTH free from 18. Then S2 12 S
    (fails S3 13), S2 15 L (fails 16), S2 18 E: S3 19 succeeds, crosses 21, tail 27, free from 29.
    S2 23 S (fails 24), S2 26 L (fails 27), S2 29 S (L was last; E has no request any more): S3 30,
    crosses 32, tail 38, free from 40. L: S3 35 and 38 fail, S3 41 succeeds, crosses 43.
    Order W, E, S, L.

    Router (1,2), all through its SOUTH buffer: W arrives 10, requests 11, crosses 15, tail 21. E arrives
    21, the cycle W's tail leaves: requests from 23, crosses 27, tail 33. S arrives 32, queued behind E's
    tail (leaves 33): requests 35, crosses 39, tail 45. L arrives 43, behind S's tail (45): requests 47,
    crosses 51, tail 57.
    """
    cfg = ChipConfig(width=3, height=3)
    mesh = Mesh(cfg, tag_packets=True)
    payload = [0, 0]  # 7 flits with the tag
    for src in [(2, 1), (0, 1), (1, 0)]:
        mesh.inject(src, (1, 2), payload, at_cycle=0)
    mesh.inject((1, 1), (1, 2), payload, at_cycle=5)
    mesh.run(500)
    assert deliveries(mesh) == [((0, 1), 21), ((2, 1), 33), ((1, 0), 45), ((1, 1), 57)]


def test_per_output_arbiters_serve_the_same_four_inputs_differently():
    """The same traffic with per-output arbiters and the same per-hop timing (R = 4): all four request
    NORTH in 10 (head from 6, 4 cycles of routing); the arbiter of NORTH starts at input 0 (EAST) and
    continues after each winner: E, W, S, L. E crosses 10, tail 16, NORTH released at the edge; W crosses
    17, S 24, L 31 (the output is busy L = 7 cycles). At (1,2) the first header arrives 10, crosses 15,
    tail 21; each next one has arrived before the previous tail leaves (in t), is at the head in t + 1,
    waits 4 cycles and crosses in t + 5: tails 21, 32, 43, 54."""
    cfg = ChipConfig(width=3, height=3, noc=NocConfig(arbiter="per-output"))
    mesh = Mesh(cfg, tag_packets=True)
    for src in [(2, 1), (0, 1), (1, 0)]:
        mesh.inject(src, (1, 2), [0, 0], at_cycle=0)
    mesh.inject((1, 1), (1, 2), [0, 0], at_cycle=5)
    mesh.run(500)
    assert deliveries(mesh) == [((2, 1), 21), ((0, 1), 32), ((1, 0), 43), ((1, 1), 54)]


def test_four_inputs_to_four_outputs_are_served_5_cycles_apart():
    """Router (1,1) of a 3x3, 7-flit packets, all requesting from 6: WEST input -> EAST (to (2,1)), SOUTH ->
    NORTH ((1,2)), LOCAL -> SOUTH ((1,0)), EAST -> WEST ((0,1)). One connection per 5 cycles in the order
    W, S, L, E: headers cross in 10, 15, 20, 25; each destination router adds 5 and the tail 6: tails in
    21, 26, 31, 36 (+0, +5, +10, +15). Per-output arbiters connect all four in 10: tails all in 21."""
    hermes = [((0, 1), 21), ((1, 0), 26), ((1, 1), 31), ((2, 1), 36)]  # order W, S, L, E
    per_output = [((0, 1), 21), ((1, 0), 21), ((1, 1), 21), ((2, 1), 21)]
    for arbiter, expected in [("hermes", hermes), ("per-output", per_output)]:
        mesh = Mesh(ChipConfig(width=3, height=3, noc=NocConfig(arbiter=arbiter)), tag_packets=True)
        mesh.inject((0, 1), (2, 1), [0, 0], at_cycle=0)
        mesh.inject((1, 0), (1, 2), [0, 0], at_cycle=0)
        mesh.inject((1, 1), (1, 0), [0, 0], at_cycle=5)
        mesh.inject((2, 1), (0, 1), [0, 0], at_cycle=0)
        mesh.run(500)
        assert sorted(deliveries(mesh), key=lambda d: (d[1], d[0])) == expected, arbiter


def test_two_inputs_to_two_outputs_are_served_5_cycles_apart():
    """3x1, (0,0) -> (2,0) and (2,0) -> (0,0), 7 flits, both injected in 0: router 1's WEST and EAST
    request in 6; S2 7 picks WEST (crosses 10), then S1 11, S2 12 EAST (crosses 15). Tails 10 + 5 + 6 = 21
    and 26. Per-output: both cross in 10, both tails in 21."""
    for arbiter, expected in [("hermes", [(2, 21), (1, 26)]), ("per-output", [(2, 21), (1, 21)])]:
        mesh = Mesh(ChipConfig(width=3, height=1, noc=NocConfig(arbiter=arbiter)))
        mesh.inject((0, 0), (2, 0), [2] * 5, at_cycle=0)
        mesh.inject((2, 0), (0, 0), [1] * 5, at_cycle=0)
        mesh.run(200)
        got = sorted(((d.flits[2], d.cycle) for d in mesh.deliveries()), key=lambda x: (x[1], -x[0]))
        assert got == expected, arbiter


def test_three_back_to_back_packets_from_one_interface():
    """(0,0) -> (1,0), three 4-flit packets ready in 0: the NI injects them in 0-3, 4-7 and 8-11.

    Router 0: P1 requests 1, crosses 5, tail 8 (free from 10). P2's header waits behind P1's tail, which
    leaves in 8: request from 10, S1 10, S2 11, S3 12, S5 13, crosses 14, tail 17. P3 likewise: P2's tail
    leaves 17, request 19, crosses 23, tail 26.
    Router 1: P1 arrives 5, crosses 10, tail 13. P2 arrives 14 at an idle buffer (P1's tail left in 13):
    request 15, crosses 19, tail 22. P3 arrives 23 (P2's tail left 22): request 24, crosses 28, tail 31.
    Per-output (R = 4): P2 is at the head in 9, waits 9..12, crosses 13; at router 1 it arrives 13, the
    cycle P1's tail leaves: head 14, crosses 18, tail 21; P3 crosses router 0 in 21, router 1 in 26: 29.
    """
    for arbiter, expected in [("hermes", [13, 22, 31]), ("per-output", [13, 21, 29])]:
        mesh = Mesh(ChipConfig(width=2, height=1, noc=NocConfig(arbiter=arbiter)))
        ids = [mesh.inject((0, 0), (1, 0), [n, n], at_cycle=0) for n in (1, 2, 3)]
        mesh.run(200)
        assert [(mesh.packet(i).start, mesh.packet(i).end) for i in ids] == [(0, 3), (4, 7), (8, 11)]
        assert [(d.flits[2], d.cycle) for d in mesh.deliveries()] == list(zip((1, 2, 3), expected, strict=True))


def test_stalled_destination_restart_and_the_header_the_rtl_would_lose():
    """3x1, buffers of 4, receive memories freed by software only.

    P1 (5 flits, (0,0) -> (2,0), cycle 0): 0 + 3 * 5 + 4 = 19, and the receive memory stays held. The
    full 4-flit buffers stall nothing before: every header waits 4 cycles, exactly as long as its
    buffer takes to fill. P2 (40 flits) follows in the same NI. Router 0's local buffer: P1's flits 0-3
    enter in 0-3, its tail (flit 4) in 6 after the header left in 5; it leaves in 11 (router 1's buffer
    full until its header left in 10). P2's header entered in 7 behind it: request 13, crosses 17.
    Router 1: P1's tail left in 16 (router 2's header left in 15); P2 arrives 17 at an idle buffer,
    request 18, S3 20 (EAST free from 18), crosses 22. Router 2: P1's tail left 19, P2 arrives 22,
    request 23, S3 25 (LOCAL free from 21), S5 26, and in 27 the header should cross into the receive
    memory, still held: the RTL would lose it; robosoc keeps it waiting and counts it.
    P2 fills the three buffers: 12 flits left the NI. Freed before cycle 200, the waiting header (still
    connected) moves in 200, the other 39 flits follow one per cycle (delivered 239, intact); the freed
    slot travels back one hop per cycle (router 1 sends in 201, router 0 in 202), the NI resumes in 203
    and injects the last of the remaining 28 flits in 230.
    """
    cfg = line(depth=4)
    mesh = Mesh(cfg, rx_free_delay=None)
    mesh.inject((0, 0), (2, 0), [11, 12, 13], at_cycle=0)
    p2_payload = list(range(100, 138))
    p2 = mesh.inject((0, 0), (2, 0), p2_payload, at_cycle=0)
    mesh.run(27)
    assert mesh.rtl_lost_headers == 0
    mesh.run(28)
    assert mesh.rtl_lost_headers == 1
    mesh.run(200)
    (d1,) = mesh.deliveries()
    assert d1.cycle == 19 and d1.payload == (11, 12, 13) and mesh.rx_held((2, 0))
    st = mesh.state
    assert mesh.packet(p2).start == 7 and mesh.packet(p2).end is None
    assert st.tile[0, k.T_SEND_POS] == 12 and st.glob[k.G_INFLIGHT] == 12
    assert st.port[:, :, k.P_COUNT].tolist() == [[0, 0, 0, 0, 4], [0, 4, 0, 0, 0], [0, 4, 0, 0, 0]]
    assert mesh.counters().rtl_lost_headers[:, 0].tolist() == [0, 0, 1]

    mesh.free_rx((2, 0))
    mesh.run(400)
    d2 = mesh.deliveries()[1]
    assert d2.cycle == 239 and d2.first_cycle == 200 and d2.payload == tuple(p2_payload)
    assert mesh.packet(p2).end == 230
    assert mesh.rtl_lost_headers == 1


def test_header_meeting_a_full_buffer_is_counted():
    """3x1, buffers of 4, receive memories freed by software only.

    P1: (1,0) -> (2,0), 3 flits in 0-2: crosses router 1 in 5, router 2 in 10, tail 12; memory held.
    P2: (1,0) -> (2,0), 4 flits, enters router 1 in 3, 6, 7, 8 (credits); P1's tail leaves in 7, so P2
    requests in 9, S3 11 (EAST free from 9), crosses 13, tail 16 (EAST free from 18). At router 2 it
    arrives 13 (P1's tail left in 12): request 14, crosses in 18 into the held memory: lost #1. Its 4
    flits fill router 2's WEST buffer.
    P3: (0,0) -> (2,0), 3 flits in 20: crosses router 0 in 25, requests at router 1 in 26, S3 28, S5 29,
    crosses in 30 into router 2's full buffer: lost #2 (the RTL buffer would drop it).
    Freed before 100: P2's header moves in 100, tail 103. Router 1 gets a credit back and P3's header
    crosses in 101. Freed again before 104. P3 waited behind P2's tail, which left router 2's buffer in
    103: request 105, S3 107 (LOCAL free from 105), crosses 109, tail 111.
    """
    mesh = Mesh(line(depth=4), rx_free_delay=None)
    mesh.inject((1, 0), (2, 0), [1], at_cycle=0)
    mesh.inject((1, 0), (2, 0), [2, 2], at_cycle=0)
    mesh.inject((0, 0), (2, 0), [3], at_cycle=20)
    mesh.run(18)
    assert mesh.rtl_lost_headers == 0
    mesh.run(19)
    assert mesh.rtl_lost_headers == 1
    mesh.run(30)
    assert mesh.rtl_lost_headers == 1
    mesh.run(31)
    assert mesh.rtl_lost_headers == 2
    assert mesh.counters().rtl_lost_headers[:, 0].tolist() == [0, 1, 1]
    mesh.run(100)
    mesh.free_rx((2, 0))
    mesh.run(104)
    mesh.free_rx((2, 0))
    mesh.run(200)
    assert [(d.flits[2], d.first_cycle, d.cycle) for d in mesh.deliveries()] == [
        (1, 10, 12),
        (2, 100, 103),
        (3, 109, 111),
    ]
    assert mesh.rtl_lost_headers == 2


@pytest.mark.parametrize("arbiter", ["hermes", "per-output"])
def test_switch_control_is_idle_and_clean_after_traffic(arbiter):
    """After any traffic has drained, every router is back in its idle state with no request pending."""
    mesh = Mesh(ChipConfig(width=4, height=3, noc=NocConfig(buffer_depth=4, arbiter=arbiter)))
    for i in range(40):
        mesh.inject(((i * 3) % 4, i % 3), ((i * 5 + 1) % 4, (i + 1) % 3), [i] * (i % 9 + 1), at_cycle=2 * i)
    mesh.run_until_idle(limit=20_000)
    st = mesh.state
    assert (st.tile[:, k.T_SC_STATE] == k.SC_IDLE).all()
    assert (st.port[:, :, k.P_HREQ] == k.BIG).all()
    assert (st.port[:, :, k.P_OWNER] == k.NONE).all() and (st.port[:, :, k.P_CONN] == k.NONE).all()
    assert len(mesh.deliveries()) == 40
