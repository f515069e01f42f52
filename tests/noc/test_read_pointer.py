"""The Hermes buffer's read pointer, against cycles derived by hand (platform.md §4, Hermes_buffer.vhd).

Rules (docs/noc.md, "The buffer's read pointer"), Hermes model only:

* tail credit: the slot of a packet's last flit is given back one cycle late: if the tail leaves in c, the
  upstream may write into that slot from c + 2 (every other freed slot: from the next cycle);
* bubble: when a flit leaves the buffer empty in the middle of a packet, the read pointer stays on its slot
  (still occupied for the upstream) until the next flit has arrived; that flit, arriving in cycle y, is
  presented in y + 2 and leaves then at the earliest (one cycle later than behind another flit), and the
  held slot is given back for y + 2.

Each case is run with the rules (``read_pointer_timing=True``, the default) and without them (the model
before issue 38), so the tests show exactly where the rules change a cycle.

Common facts from platform.md §4 used in the derivations: the NI injects one flit per cycle while the
router's local buffer has room; a header at an idle buffer arriving in a requests from a + 1, one queued
behind a tail that left in c from c + 2; uncontended it crosses 4 cycles after its request (S1 S2 S3 S5
S7); an output is free for a new connection 2 cycles after its tail crossed; the selection order is E, W,
N, S, L after the last input selected.
"""

import pytest

from robosoc.chip.noc import Mesh
from robosoc.config.chip import ChipConfig, NocConfig
from robosoc.kernels import noc as k


def mesh(width: int, height: int, depth: int, rules: bool, **kw) -> Mesh:
    cfg = ChipConfig(width=width, height=height, noc=NocConfig(buffer_depth=depth))
    return Mesh(cfg, read_pointer_timing=rules, **kw)


def cycles_where(m: Mesh, until: int, probe) -> list[int]:
    """The cycles (up to ``until``) in which ``probe(state)`` changed, stepping one cycle at a time."""
    changed = []
    while m.cycle < until:
        before = probe(m.state)
        c = m.cycle
        m.step()
        if probe(m.state) != before:
            changed.append(c)
    return changed


@pytest.mark.parametrize("rules", [True, False])
def test_a_full_buffer_whose_tail_leaves_in_c_accepts_from_c_plus_2(rules):
    """2x1, depth 4; (0,0) sends A (3 flits) then P (10 flits) to (1,0); (1,0)'s receive memory stalls in
    [12, 30).

    Router 0, local buffer: A's flits enter in 0, 1, 2 and P's header in 3: full. A's header requests in 1
    and crosses in 5, its flit 1 leaves in 6, its tail in 7. The NI refills the slots of 5 and 6 in 6 and
    7; at the start of 8 the buffer holds 3 flits of P plus, with the rule, A's tail slot (given back for
    9): full, so the NI waits in 8 and injects again in 9 (without the rule: in 8).
    Router 1, west buffer: A's header arrives in 5, requests 6, crosses into the receive memory in 10, its
    flit 1 in 11; the stall holds A's tail at the head from 12. P's header (request at router 0 from 9,
    the tail having left in 7) crosses router 0 in 13, P's flits 1 and 2 follow in 14 and 15: the buffer
    is full with A's tail, P's header and two flits. In 30 A's tail leaves (c = 30): router 0 writes P's
    next flit into the slot in 32 = c + 2 (without the rule: 31). P's header, queued behind the tail,
    requests from 32 either way and crosses in 36; P's tail reaches the memory in 36 + 9 = 45 in both.
    """
    m = mesh(2, 1, 4, rules)
    m.inject((0, 0), (1, 0), [0xA], at_cycle=0)
    p = m.inject((0, 0), (1, 0), list(range(8)), at_cycle=0)
    m.stall_receive((1, 0), 12, 30)
    ni = cycles_where(m, 12, lambda st: int(st.tile[0, k.T_SEND_POS]) + 100 * int(st.tile[0, k.T_SENT_PKTS]))
    assert ni == ([0, 1, 2, 3, 6, 7, 9] if rules else [0, 1, 2, 3, 6, 7, 8])
    m.run(30)
    assert m.state.port[1, k.WEST, k.P_COUNT] == 4 and m.state.port[1, k.WEST, k.P_FLITS_IN] == 6
    into_west = cycles_where(m, 34, lambda st: int(st.port[1, k.WEST, k.P_FLITS_IN]))
    assert into_west == ([32] if rules else [31])
    m.run(100)
    assert [d.cycle for d in m.deliveries()] == [30, 45]
    assert m.packet(p).start == 3


@pytest.mark.parametrize("rules", [True, False])
def test_a_chain_of_full_buffers_slips_one_cycle_per_hop(rules):
    """4x1, depth 4; (0,0) sends A (3 flits) then P (32 flits) to (3,0), whose receive memory stalls in
    [22, 100).

    A's header crosses routers 0..3 in 5, 10, 15, 20 (into the memory); its flit 1 follows in 21 and its
    tail waits at the head of router 3's west buffer from 22. P follows A (its header at routers 0, 1, 2 in
    13, 18, 23) and fills every buffer: router 3's west buffer holds A's tail, P's header and two flits,
    routers 2 and 1 four flits of P each, router 0's local buffer four more; the NI has injected 15 flits.
    A's tail leaves in c = 100. With the rule its slot is usable from 102: router 2 sends in 102, which
    frees a slot of its own buffer for 103 (an ordinary slot), so router 1 sends in 103, router 0 in 104 and
    the NI injects in 105: the one-cycle slip travels back one hop per cycle. Without it: 101, 102, 103, 104.
    P's header requests from 102 in both (queued behind the tail), crosses in 106, and everything behind it
    is full again by then: P arrives in 106 + 31 = 137 in both.
    """
    m = mesh(4, 1, 4, rules)
    m.inject((0, 0), (3, 0), [0xA], at_cycle=0)
    m.inject((0, 0), (3, 0), list(range(30)), at_cycle=0)
    m.stall_receive((3, 0), 22, 100)
    m.run(100)
    st = m.state
    assert st.port[:, :, k.P_COUNT].tolist() == [[0, 0, 0, 0, 4], [0, 4, 0, 0, 0], [0, 4, 0, 0, 0], [0, 4, 0, 0, 0]]
    assert st.tile[0, k.T_SEND_POS] == 15
    first_move = {}
    for name, probe in [
        ("router 2", lambda st: int(st.port[2, k.EAST, k.P_FLITS_OUT])),
        ("router 1", lambda st: int(st.port[1, k.EAST, k.P_FLITS_OUT])),
        ("router 0", lambda st: int(st.port[0, k.EAST, k.P_FLITS_OUT])),
        ("ni", lambda st: int(st.tile[0, k.T_SEND_POS])),
    ]:
        trial = mesh(4, 1, 4, rules)
        trial.restore(m.snapshot())
        first_move[name] = cycles_where(trial, 106, probe)[0]
    shift = 1 if rules else 0
    assert first_move == {"router 2": 101 + shift, "router 1": 102 + shift, "router 0": 103 + shift, "ni": 104 + shift}
    m.run(300)
    assert [(d.first_cycle, d.cycle) for d in m.deliveries()] == [(20, 100), (106, 137)]


@pytest.mark.parametrize("rules", [True, False])
def test_the_slip_knocks_on_through_one_switch_controller(rules):
    """2x2, depth 4. (0,0) sends A (3 flits), P (4 flits) and Q (3 flits) to (1,0), whose receive memory
    stalls in [12, 30); (0,1) sends R (3 flits) to (0,0) in 29.

    Router 0's local buffer: A's flits enter in 0-2, P's header in 3 (full); A crosses router 0 in 5-7 (its
    tail in 7, with the rule its slot is back for 9), P's flits enter in 6, 7 and, with the rule, 9 (else
    8), then Q's three. P's header requests from 9 (behind A's tail), crosses in 13 (the last input selected
    at router 0 is now LOCAL), its flits 1 and 2 in 14, 15. Router 1's west buffer then holds A's tail
    (stalled since 12), P's header and flits 1, 2: full; router 0's local buffer holds P's tail and Q.
    A's tail leaves in c = 30. P's tail crosses router 0 in c + 2 = 32 with the rule, c + 1 = 31 without,
    so Q's header (queued behind it) requests from 34 (33 without).
    R: injected at (0,1) in 29, crosses router (0,1) in 34, arrives at router 0's north buffer in 34 and
    requests from 35.
    Without the rule: router 0's controller sees Q in 33 [S1], selects in 34 (only Q asks: R asks from
    35), Q crosses in 37; R: S1 38, S2 39, S3 40, S5 41, crosses into (0,0)'s memory in 42, tail 44.
    With the rule: S1 34, S2 35 sees Q and R; after LOCAL the order is E, W, N: R wins, crosses in 38,
    tail 40; Q: S1 39, S2 40, S3 41, S5 42, crosses in 43.
    Router 1: P's header requests from 32 (behind A's tail), crosses in 36, P's tail in 39 in both. Q's
    header arrives in 37 (without) behind P's tail, which leaves in 39: request 41, crosses 45, tail 47;
    with the rule it arrives in 43 at an idle buffer: request 44, crosses 48, tail 50.
    One cycle on P's tail: Q 3 cycles later, R 4 cycles earlier.
    """
    m = mesh(2, 2, 4, rules)
    m.inject((0, 0), (1, 0), [0xA], at_cycle=0)
    m.inject((0, 0), (1, 0), [0xB, 0xB], at_cycle=0)
    m.inject((0, 0), (1, 0), [0xC], at_cycle=0)
    m.inject((0, 1), (0, 0), [0xD], at_cycle=29)
    m.stall_receive((1, 0), 12, 30)
    m.run(200)
    got = [(d.flits[2], d.first_cycle, d.cycle) for d in m.deliveries()]
    if rules:
        assert got == [(0xA, 10, 30), (0xB, 36, 39), (0xD, 38, 40), (0xC, 48, 50)]
    else:
        assert got == [(0xA, 10, 30), (0xB, 36, 39), (0xD, 42, 44), (0xC, 45, 47)]
    assert m.rtl_lost_headers == 0


@pytest.mark.parametrize("rules", [True, False])
def test_a_source_pausing_mid_packet_leaves_one_bubble_per_buffer_that_ran_empty(rules):
    """2x1, depth 4, one 10-flit packet (0,0) -> (1,0) in 0; (0,0)'s NI pauses in [8, 20).

    The NI injects the header and flits 1-3 in 0-3, flits 4 and 5 in 6 and 7 (the slots freed in 5 and 6),
    then nothing until 20. Router 0 sends the header in 5 and flits 1-3 in 6-8; router 1's west buffer is
    then full until its header crosses into the memory in 10, so router 0 sends flit 4 in 11 and flit 5 in
    12, which leaves its buffer empty mid-packet. Router 1 sends flits 1-5 in 11-15; flit 5 leaves it empty.
    Flit 6 enters router 0 in 20. With the rule it leaves router 0 in 22 (one bubble), arrives at router 1
    in 22 and leaves it in 24 (a second bubble); flits 7-9 (injected 21-23) follow one per cycle behind it:
    the tail reaches the memory in 27. Without the rule: 21 and 22, tail in 25.
    """
    m = mesh(2, 1, 4, rules)
    pid = m.inject((0, 0), (1, 0), list(range(8)), at_cycle=0)
    m.pause_send((0, 0), 8, 20)
    m.run(12)
    assert m.state.port[0, k.LOCAL, k.P_COUNT] == 1 and m.state.tile[0, k.T_SEND_POS] == 6
    m.run(100)
    (d,) = m.deliveries()
    assert (d.first_cycle, d.cycle) == ((10, 27) if rules else (10, 25))
    assert d.payload == tuple(range(8)) and m.packet(pid).end == 23


@pytest.mark.parametrize("rules", [True, False])
def test_a_destination_stalling_mid_packet_holds_it_in_place(rules):
    """2x1, depth 4, one 12-flit packet (0,0) -> (1,0) in 0; (1,0)'s receive memory stalls in [12, 20).

    The header crosses router 0 in 5 and router 1 in 10 (into the memory); router 1's west buffer filled
    with flits 1-3 in 6-8 (router 0 then waits), flit 1 enters the memory in 11, flits 4 and 5 cross router
    0 in 11 and 12. From 12 nothing enters the memory: router 1's buffer is full (flits 2-5) and router 0
    waits with its buffer full too. From 20 the flits enter the memory one per cycle, 2..11 in 20..29: no
    buffer ran empty (each refills the cycle after a slot frees), so the rule changes nothing here.
    """
    m = mesh(2, 1, 4, rules)
    m.inject((0, 0), (1, 0), list(range(10)), at_cycle=0)
    m.stall_receive((1, 0), 12, 20)
    writes = cycles_where(m, 40, lambda st: int(st.tile[1, k.T_RX_COUNT]))
    assert writes == [10, 11, *range(20, 30), 30]  # (30: the memory frees itself the cycle after the delivery)
    assert m.state.port[1, k.WEST, k.P_FLITS_IN] == 12


def test_a_destination_can_stall_in_the_middle_of_a_packet_only_once_at_a_time():
    m = mesh(2, 1, 4, True)
    m.stall_receive((1, 0), 5, 9)
    with pytest.raises(ValueError, match=r"tile: \(1, 0\) already has a window until 9"):
        m.stall_receive((1, 0), 10, 12)
    with pytest.raises(ValueError, match=r"window: \[4, 4\) is empty"):
        m.pause_send((0, 0), 4, 4)
    with pytest.raises(ValueError, match=r"tile: \(2, 0\) is outside the 2x1 mesh"):
        m.pause_send((2, 0), 4, 6)
    m.run(10)
    with pytest.raises(ValueError, match="start: 3 is in the past"):
        m.stall_receive((1, 0), 3, 12)
    m.stall_receive((1, 0), 10, 12)  # the first window is over


def test_two_flit_buffers_run_empty_after_every_flit():
    """Depth 2, one hop: the header and flit 1 enter router 0 in s, s + 1 (full); the header crosses in
    s + 5, flit 1 in s + 6. Flit 2 enters in s + 6 (the header's slot) while flit 1 leaves the buffer empty:
    a bubble, it leaves in s + 8 at the earliest. From then on every buffer on the route holds one flit plus
    the slot of the one that just left, so each flit leaves 2 cycles after the previous one, and the first
    two flits reach the memory in s + 10, s + 11: the tail in s + 11 + 2(L - 2) (L = 3: 13, L = 6: 19; the
    RTL timing measured at depths 4, 8 and 16, s + 10 + L - 1, holds from depth 3). Each router adds its 5
    cycles to the header only: s + 5(h + 1) + 1 + 2(L - 2)."""
    cfg = ChipConfig(width=4, height=4, noc=NocConfig(buffer_depth=2))
    for dst in [(1, 0), (2, 0), (3, 3)]:
        hops = dst[0] + dst[1]
        for length in (3, 6, 17, 64):
            m = Mesh(cfg)
            m.inject((0, 0), dst, [1] * (length - 2), at_cycle=7)
            m.run(1000)
            (d,) = m.deliveries()
            assert (d.first_cycle, d.cycle) == (7 + 5 * (hops + 1), 7 + 5 * (hops + 1) + 1 + 2 * (length - 2))
            assert d.cycle - 7 == m.single_packet_latency(hops, length)
            before = Mesh(cfg, read_pointer_timing=False)
            before.inject((0, 0), dst, [1] * (length - 2), at_cycle=7)
            before.run(1000)
            assert before.deliveries()[0].cycle == 7 + 5 * (hops + 1) + length - 1


def test_per_output_routers_have_no_read_pointer_rules():
    """The idealised per-output model keeps every freed slot usable the next cycle: the chain case gives
    the same cycles with and without the option."""
    cfg = ChipConfig(width=2, height=1, noc=NocConfig(buffer_depth=2, arbiter="per-output"))
    got = []
    for rules in (True, False):
        m = Mesh(cfg, read_pointer_timing=rules)
        m.inject((0, 0), (1, 0), list(range(8)), at_cycle=0)
        m.run(100)
        got.append(m.deliveries()[0].cycle)
    assert got[0] == got[1] == 0 + 2 * 5 + 9


def _busy_mesh(reverse: bool, rules: bool = True) -> Mesh:
    """4x3, 2-flit buffers (every flit leaves its buffer empty: the rules act all the time), random
    traffic, a source pausing and a destination stalling mid-packet."""
    import numpy as np

    m = Mesh(
        ChipConfig(width=4, height=3, noc=NocConfig(buffer_depth=2)),
        tag_packets=True,
        reverse_evaluation=reverse,
        read_pointer_timing=rules,
        rx_free_delay=2,
    )
    rng = np.random.default_rng(5)
    for i in range(150):
        a, b = rng.choice(12, size=2, replace=False)
        at = int(rng.integers(0, 600))
        m.inject(m.config.tile_xy(int(a)), m.config.tile_xy(int(b)), [i] * int(rng.integers(0, 20)), at_cycle=at)
    m.pause_send((1, 1), 100, 140)
    m.stall_receive((2, 2), 150, 190)
    return m


def test_the_rules_keep_evaluation_order_and_idle_skipping_exact():
    """The rules add state read across routers (a held slot) and written by the upstream's push: the
    result must not depend on the order routers are evaluated in, nor on skipping idle cycles."""
    import numpy as np

    forward, backward, stepped = _busy_mesh(False), _busy_mesh(True), _busy_mesh(False)
    forward.run_until_idle(limit=100_000)
    backward.run_until_idle(limit=100_000)
    while stepped.cycle < forward.cycle:
        stepped.step()
    assert len(forward.deliveries()) == 150
    assert forward.deliveries() == backward.deliveries() == stepped.deliveries()
    for name in k.NocState._fields:
        if name not in ("cfg", "ev"):  # cfg holds the order flag; ev rows are drained copies
            assert np.array_equal(getattr(forward.state, name), getattr(backward.state, name)), name
            assert np.array_equal(getattr(forward.state, name), getattr(stepped.state, name)), name
    before = _busy_mesh(False, rules=False)
    before.run_until_idle(limit=100_000)
    assert {d.packet_id: d.cycle for d in before.deliveries()} != {d.packet_id: d.cycle for d in forward.deliveries()}
