"""Lookahead: a packet entering its router A in cycle s changes no flit move elsewhere before s + m.

m = fewest cycles a header spends in a router (docs/noc.md, "Lookahead"):

* per-output arbiters: the header is at the head from s + 1, waits R cycles and can first compete for an
  output in s + 1 + R; that request touches only the output it wants, so m = R + 1;
* Hermes: the request is up in s + 1; if A's switch controller is in its select state [S2] then (another
  input asked a cycle earlier), the new header may be selected at once and cross in s + 4 [S7] instead
  of the header that would have crossed then: m = 4, one less than an uncontended router's 5. Until
  then only A's switch-control state (state, pointer, the connection made in s + 3) can differ.
"""

import numpy as np
import pytest

from robosoc.chip.noc import Mesh
from robosoc.config.chip import ChipConfig, NocConfig
from robosoc.kernels import noc as k

CONTROL = [k.P_OWNER, k.P_CONN, k.P_REQ, k.P_RR, k.P_WAIT, k.P_HREQ, k.P_FREE_AT, k.P_MOVE]
DATA = [c for c in range(k.PORT_COLS) if c not in CONTROL]


def build(cfg: ChipConfig, quiet: int, extra: tuple | None) -> Mesh:
    mesh = Mesh(cfg, tag_packets=True)
    rng = np.random.default_rng(11)
    others = [t for t in range(cfg.n_tiles) if t != quiet]
    for i in range(400):
        t = int(rng.choice(others))
        d = int(rng.integers(cfg.n_tiles - 1))
        d = d if d < t else d + 1
        length = int(rng.integers(0, 25))
        mesh.inject(cfg.tile_xy(t), cfg.tile_xy(d), [i] * length, at_cycle=int(rng.integers(0, 500)))
    if extra is not None:
        dst, s = extra
        mesh.inject(cfg.tile_xy(quiet), dst, [0xBEEF] * 20, at_cycle=s)
    return mesh


@pytest.mark.parametrize(
    ("arbiter", "rlat", "lookahead", "quiet", "dst", "s"),
    [
        ("per-output", 6, 7, 5, (3, 3), 200),
        ("per-output", 2, 3, 9, (3, 0), 250),
        ("per-output", 0, 1, 6, (0, 3), 300),
        ("hermes", 4, 4, 5, (3, 3), 200),
        ("hermes", 4, 4, 9, (3, 0), 250),
        ("hermes", 4, 4, 6, (0, 3), 300),
    ],
)
def test_injection_cannot_change_anything_else_within_lookahead(arbiter, rlat, lookahead, quiet, dst, s):
    cfg = ChipConfig(width=4, height=4, noc=NocConfig(buffer_depth=4, routing_latency=rlat, arbiter=arbiter))
    base = build(cfg, quiet, None)
    more = build(cfg, quiet, (dst, s))
    assert more.lookahead == lookahead
    base.run(s + lookahead)
    more.run(s + lookahead)
    extra_id = 400
    assert more.packet(extra_id).start == s  # the NI was idle: the first flit entered in cycle s

    # every state except the injecting tile's NI, local input buffer and (Hermes) switch control is
    # identical after cycle s + m - 1
    a, b = base.state, more.state
    others = [t for t in range(cfg.n_tiles) if t != quiet]
    assert np.array_equal(a.buf[others], b.buf[others])
    assert np.array_equal(a.buf[quiet, : k.LOCAL], b.buf[quiet, : k.LOCAL])
    assert np.array_equal(a.port[others], b.port[others])
    same = slice(None) if arbiter == "per-output" else DATA
    assert np.array_equal(a.port[quiet, : k.LOCAL][:, same], b.port[quiet, : k.LOCAL][:, same])
    assert np.array_equal(a.tile[others], b.tile[others])
    rx_cols = [k.T_RX_STATE, k.T_RX_COUNT, k.T_RX_TOTAL, k.T_RX_FIRST, k.T_RX_FREE_AT, k.T_RECV_PKTS]
    assert np.array_equal(a.tile[quiet, rx_cols], b.tile[quiet, rx_cols])
    assert np.array_equal(a.mem[:, k.RECV], b.mem[:, k.RECV])
    for g in (k.G_DELIVERED, k.G_HOPS, k.G_EJECTED):
        assert a.glob[g] == b.glob[g]

    # hence the delivery events before s + lookahead are the same; later ones may differ
    base.run_until_idle(limit=100_000)
    more.run_until_idle(limit=100_000)
    early = [d for d in base.deliveries() if d.cycle < s + lookahead]
    assert early and [d for d in more.deliveries() if d.cycle < s + lookahead] == early
    later_base = {d.packet_id: d.cycle for d in base.deliveries()}
    later_more = {d.packet_id: d.cycle for d in more.deliveries() if d.packet_id != extra_id}
    assert later_base.keys() == later_more.keys()
    assert any(later_base[p] != later_more[p] for p in later_base)  # the extra packet did interfere


def test_hermes_lookahead_is_tight():
    """3x1. X: (2,0) -> (0,0) in 0 requests EAST -> WEST at router 1 from 6: S1 6, S2 7. B: (1,0) -> (0,0)
    enters router 1 in s = 6, requests from 7, which the select state [S2] of 7 sees; LOCAL comes before
    EAST after reset, so B is selected and crosses in 10 = s + 4, the cycle X would have crossed alone
    (S3 8, S5 9, S7 10). Through cycle 9 every buffer but router 1's local one is the same; in 10 B's
    header crosses instead of X's, and in 11 its size flit (3, X's is 4)."""
    cfg = ChipConfig(width=3, height=1)
    alone, with_b = Mesh(cfg), Mesh(cfg)
    for mesh in (alone, with_b):
        mesh.inject((2, 0), (0, 0), [1] * 4, at_cycle=0)
    with_b.inject((1, 0), (0, 0), [2] * 3, at_cycle=6)
    for mesh in (alone, with_b):
        mesh.run(10)
    counts = [m.state.port[:, :, k.P_COUNT].copy() for m in (alone, with_b)]
    assert counts[1][1, k.LOCAL] == 4  # B's flits that entered in 6..9
    counts[1][1, k.LOCAL] = 0
    assert counts[0].tolist() == counts[1].tolist() == [[0, 0, 0, 0, 0], [5, 0, 0, 0, 0], [0, 0, 0, 0, 1]]
    for mesh in (alone, with_b):
        mesh.run(12)
    router0_east = [m.state.buf[0, k.EAST, :2].tolist() for m in (alone, with_b)]
    assert router0_east == [[0x00, 4], [0x00, 3]]


@pytest.mark.parametrize(("arbiter", "rlat"), [("hermes", 4), ("per-output", 2)])
def test_no_packet_beats_the_fewest_cycles_per_router(arbiter, rlat):
    """The chip's time quanta rest on this (docs/noc.md): under any traffic a packet whose first flit
    enters its router in s has its last flit in the receive memory no earlier than s + (h + 1)m + L - 1.
    With the Hermes controller some packets do beat the uncontended 5 cycles per router, so m = 5 would
    be wrong."""
    cfg = ChipConfig(width=4, height=4, noc=NocConfig(buffer_depth=4, routing_latency=rlat, arbiter=arbiter))
    mesh = build(cfg, quiet=0, extra=None)
    mesh.run_until_idle(limit=100_000)
    m = mesh.lookahead
    faster = 0
    for d in mesh.deliveries():
        info = mesh.packet(d.packet_id)
        hops = mesh.hops(info.src, info.dst)
        assert d.cycle - info.start >= (hops + 1) * m + d.length - 1
        faster += d.cycle - info.start < mesh.single_packet_latency(hops, d.length)
    assert (faster > 0) == (arbiter == "hermes")
