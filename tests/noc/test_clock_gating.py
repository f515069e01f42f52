"""Router clock gating (``noc.clock_gating``): packet timing against hand-derived cycles, the gated
cycles counted for energy, and determinism (docs/noc.md, "Clock gating").

Derivation.  A router's clock stops once it has held no flit for N = ``gate_after_cycles`` cycles:
a flit present at the start of cycle c finds it stopped if the router's last cycle with a flit was
at most c - 1 - N.  It then wakes and acts from c + W (W = ``wake_cycles``): every decision it
would have taken from c on comes exactly W cycles later.  For one packet in an idle network
(test_latency.py's formula) every router on the path is asleep when the header arrives (if it has
been idle long enough), so each of the h + 1 routers costs the header W more:
``s + (h + 1)(R + 1 + W) + L - 1``.

For a later packet the routers' idle stretches follow from the earlier packet's delivery cycle D:
the router k hops before the destination last held a flit in cycle D - k (the tail streams one hop
per cycle), and the header of a packet entering the source router in cycle r is present at router k
(from the source) from r + 1 + Σ (per-router cost of the routers before it).
"""

import dataclasses

import numpy as np
import pytest

from robosoc.chip.energy import EnergyModel
from robosoc.chip.noc import Mesh
from robosoc.config.chip import ChipConfig, NocConfig

N, W = 20, 3
ROUTES = [((0, 0), (1, 0)), ((1, 1), (1, 2)), ((0, 0), (2, 1)), ((3, 2), (0, 0)), ((0, 0), (3, 3)), ((2, 3), (2, 0))]


def _mesh(width: int = 4, height: int = 4, **noc: object) -> Mesh:
    return Mesh(ChipConfig(width=width, height=height, noc=NocConfig(**noc)))


@pytest.mark.parametrize(("arbiter", "rlat"), [("hermes", 4), ("per-output", 0), ("per-output", 3)])
@pytest.mark.parametrize("wake", [0, 1, 3])
def test_one_packet_in_an_idle_network_pays_the_wake_up_at_every_router(arbiter: str, rlat: int, wake: int) -> None:
    for src, dst in ROUTES:
        hops = abs(src[0] - dst[0]) + abs(src[1] - dst[1])
        for length in (3, 17):
            start = 40  # every router has been idle for more than N cycles
            mesh = _mesh(arbiter=arbiter, routing_latency=rlat, clock_gating=True, gate_after_cycles=N,
                         wake_cycles=wake)  # fmt: skip
            mesh.inject(src, dst, list(range(length - 2)), at_cycle=start)
            mesh.run_until_idle(limit=5000)
            (d,) = mesh.deliveries()
            assert d.cycle == start + (hops + 1) * (rlat + 1 + wake) + length - 1, (src, dst, length)
            assert int(mesh.counters().wakeups.sum()) == hops + 1


def test_a_router_not_idle_long_enough_is_not_asleep() -> None:
    mesh = _mesh(clock_gating=True, gate_after_cycles=N, wake_cycles=W)
    mesh.inject((0, 0), (3, 3), [1, 2, 3], at_cycle=N - 2)  # present from N - 1: idle N - 1 cycles at the source
    mesh.run_until_idle(limit=5000)
    (d,) = mesh.deliveries()
    # the source router is awake; the six others were idle long enough
    assert d.cycle == (N - 2) + 5 + 6 * (5 + W) + 5 - 1
    assert int(mesh.counters().wakeups.sum()) == 6


def test_later_packets_wake_exactly_the_routers_idle_for_n_cycles() -> None:
    """Hand-derived on a 2x2 mesh (L = 5), N = 20, W = 3.  A router's flits stream out one per cycle
    from the header's crossing: a woken router's header crosses at (arrival + W + 4)."""
    mesh = _mesh(2, 2, clock_gating=True, gate_after_cycles=N, wake_cycles=W)
    payload = [7, 8, 9]

    def send(dst: tuple[int, int], ready: int) -> int:
        pid = mesh.inject((0, 0), dst, payload, at_cycle=ready)
        while not mesh.idle:
            mesh.run(mesh.cycle + 1)
        assert mesh.packet(pid).start == ready
        return mesh.deliveries()[-1].cycle

    # X to (0, 1) at 50: both routers asleep: 50 + 2 (5 + 3) + 4 = 70.  Router (0, 0): header present
    # from 51, awake from 54, crosses at 58, its last flit at 62.
    assert send((0, 1), 50) == 70
    # B to (1, 0) at 62 + N - 1 = 81: router (0, 0) idle 19 cycles (awake); router (1, 0) never used
    # (asleep): 81 + 5 + 8 + 4 = 98.  Router (0, 0) last flit 90, router (1, 0) 98.
    assert send((1, 0), 81) == 98
    # C to (1, 0) at 90 + N = 110: router (0, 0) idle exactly N (asleep): crosses at 118; router (1, 0)
    # present from 119, idle 119 - 1 - 98 = 20 (asleep): 110 + 16 + 4 = 130.  Last flits 122 and 130.
    assert send((1, 0), 110) == 130
    # D to (1, 0) at 132: idle 132 - 122 = 10 and 137 - 130 = 7: nobody sleeps: 132 + 10 + 4
    assert send((1, 0), 132) == 146
    assert int(mesh.counters().wakeups.sum()) == 2 + 1 + 2 + 0


def test_gated_cycles_are_the_idle_cycles_after_the_first_n() -> None:
    mesh = _mesh(2, 1, clock_gating=True, gate_after_cycles=N, wake_cycles=W)
    mesh.inject((0, 0), (1, 0), [7, 8, 9], at_cycle=50)
    mesh.run(200)
    c = mesh.counters()
    assert mesh.deliveries()[0].cycle == 70
    # source: idle in cycles 0..50 (51 cycles: 31 gated); awake from 54, flits cross 58..62; idle
    # 63..199 (137: 117 gated).  Destination: header present from 59 (idle 59: 39 gated), awake from
    # 62, flits leave 66..70; idle 71..199 (129: 109 gated).
    assert int(c.gated_cycles[0, 0]) == 31 + 117
    assert int(c.gated_cycles[1, 0]) == 39 + 109
    assert c.wakeups.tolist() == [[1], [1]]
    # without gating nothing is gated
    plain = _mesh(2, 1)
    plain.inject((0, 0), (1, 0), [7, 8, 9], at_cycle=50)
    plain.run(200)
    assert int(plain.counters().gated_cycles.sum()) == 0
    assert plain.deliveries()[0].cycle == 50 + 10 + 4


def test_a_stopped_router_costs_only_its_leakage() -> None:
    model = EnergyModel.load()
    one_gated = {"router_cycles": 1, "router_busy_cycles": 0, "router_gated_cycles": 1,
                 "port_busy_cycles": 0, "port_idle_cycles": 5}  # fmt: skip
    assert sum(model.noc_pj(one_gated).values()) == pytest.approx(model.noc["leakage"].pj)
    one_idle = {**one_gated, "router_gated_cycles": 0}
    idle = 5 * model.noc["buffer_idle"].pj + model.noc["control_idle"].pj + model.noc["leakage"].pj
    assert sum(model.noc_pj(one_idle).values()) == pytest.approx(idle)
    assert sum(model.noc_pj({k: v for k, v in one_idle.items() if k != "router_gated_cycles"}).values()) == (
        pytest.approx(idle)
    )


def test_gated_traffic_is_deterministic_and_independent_of_evaluation_order() -> None:
    rng = np.random.default_rng(3)
    plan = [(int(rng.integers(16)), int(rng.integers(15)), int(c)) for c in np.sort(rng.integers(0, 3000, 120))]
    runs = []
    for reverse in (False, True, False):
        cfg = ChipConfig(width=4, height=4, noc=NocConfig(clock_gating=True, gate_after_cycles=4, wake_cycles=2))
        mesh = Mesh(cfg, tag_packets=True, reverse_evaluation=reverse)
        for src, d, at in plan:
            dst = d if d < src else d + 1
            mesh.inject(cfg.tile_xy(src), cfg.tile_xy(dst), [src, dst], at_cycle=at)
        mesh.run_until_idle(limit=100_000)
        c = mesh.counters()
        runs.append(([(x.dst, x.cycle, x.packet_id) for x in mesh.deliveries()], c.gated_cycles.tolist(),
                     c.busy_cycles.tolist()))  # fmt: skip
    assert runs[0] == runs[1] == runs[2]
    assert len(runs[0][0]) == len(plan)


def test_gating_settings_are_checked() -> None:
    with pytest.raises(ValueError, match="gate_after_cycles"):
        NocConfig(clock_gating=True, gate_after_cycles=0)
    with pytest.raises(ValueError, match="wake_cycles"):
        NocConfig(wake_cycles=-1)
    assert dataclasses.replace(NocConfig(), clock_gating=True).gate_after_cycles >= 1
