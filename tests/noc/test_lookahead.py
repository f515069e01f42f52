"""Lookahead: a packet entering its router in cycle s changes nothing elsewhere before s + R + 1.

Its header is at the head of the local input buffer from s + 1, waits R cycles and can first compete for
an output in cycle s + 1 + R. With one round-robin arbiter per output, that request touches only the
output it wants, so every other flit move, every receive-memory write and every delivery event of
cycles s .. s + R is the same as without the packet (docs/noc.md, "Lookahead").
"""

import numpy as np
import pytest

from robosoc.chip.noc import Mesh
from robosoc.config.chip import ChipConfig, NocConfig
from robosoc.kernels import noc as k


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


@pytest.mark.parametrize(("rlat", "quiet", "dst", "s"), [(6, 5, (3, 3), 200), (2, 9, (3, 0), 250), (0, 6, (0, 3), 300)])
def test_injection_cannot_change_anything_else_within_lookahead(rlat, quiet, dst, s):
    cfg = ChipConfig(width=4, height=4, noc=NocConfig(buffer_depth=4, routing_latency=rlat))
    lookahead = rlat + 1
    base = build(cfg, quiet, None)
    more = build(cfg, quiet, (dst, s))
    assert more.lookahead == lookahead
    base.run(s + lookahead)
    more.run(s + lookahead)
    extra_id = 400
    assert more.packet(extra_id).start == s  # the NI was idle: the first flit entered in cycle s

    # every state except the injecting tile's NI and local input buffer is identical after cycle s + R
    a, b = base.state, more.state
    others = [t for t in range(cfg.n_tiles) if t != quiet]
    assert np.array_equal(a.buf[others], b.buf[others])
    assert np.array_equal(a.buf[quiet, : k.LOCAL], b.buf[quiet, : k.LOCAL])
    assert np.array_equal(a.port[others], b.port[others])
    assert np.array_equal(a.port[quiet, : k.LOCAL], b.port[quiet, : k.LOCAL])
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
