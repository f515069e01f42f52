"""Every total the chip reports is the sum of its parts, and the parts are what the state arrays hold.

A 3x3 chip (I/O tile at (0, 0)) runs ``programs/all_to_all.c``: every core tile sends one packet
to every other core tile and one to the I/O tile, and the host injects one packet from the I/O
tile into every core tile, so that flits cross every router, the four corners included, in three
tasks per tile.  The packets are worked out here in Python from the program's generator, which
gives by hand the flits through every port of every router, the flit hops, the flits injected,
the packets delivered and each tile's DMA cycles; the idle terms are cycles x routers x ports.

Checked against those and against the state arrays read directly (``chip.noc.port``/``tile``/``glob``,
``chip.cores.ctr``/``opc``/``st``, ``chip.acc``, ``chip.cst``): :meth:`MPSoC.noc_counters`,
:meth:`EnergyModel.noc_pj`, :meth:`MPSoC.counters`, :meth:`MPSoC.task_counters` and the stats of
``robosoc run --mesh``; as properties: busy + idle = cycles x units for ports, routers and cores,
tasks add up to their tile, tiles and NoC to the chip, under every engine and both router models.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

import rv32_asm as A
from core_harness import exit_with
from robosoc.chip.energy import INSTRUCTION_CLASSES, STALL_KINDS, EnergyModel
from robosoc.chip.mpsoc import ChipResult, MPSoC, account_counter_map, account_counters
from robosoc.cli import app
from robosoc.config.chip import ChipConfig, NocConfig
from robosoc.kernels import chip as kc
from robosoc.kernels import noc as nk
from robosoc.kernels.core_layout import CTR_SIZE, OPC_SIZE, PIPELINE_FILL, S_CYCLE
from robosoc.program.elf import Program, load_elf
from robosoc.toolchain import build_elf

# the program's random generator meets receive interrupts now and then: the erratum report is expected
pytestmark = pytest.mark.filterwarnings("ignore::robosoc.chip.single.IrqDuringMulErratum")

PROGRAM = Path(__file__).parent / "programs" / "all_to_all.c"
MODEL = EnergyModel.load()
W, H = 3, 3
IO = (0, 0)
LAST_TASK = kc.NTASKS - 1  # the program sends in task 15
INJECT_AT = 300  # the host's packet to the k-th core tile leaves the I/O tile in INJECT_AT + 50 k
CORNERS = ((0, 0), (W - 1, 0), (0, H - 1), (W - 1, H - 1))
ARBITERS = ("hermes", "per-output")
ENGINES = ("interp", "jit", "auto")
CASES = [(a, e) for a in ARBITERS for e in ENGINES]
M32 = 0xFFFFFFFF


# --- the packets, worked out by hand -------------------------------------------------------------


@dataclass(frozen=True)
class Packet:
    src: tuple[int, int]
    dst: tuple[int, int]
    flits: int  # on the wire: destination, size, payload

    @property
    def hops(self) -> int:
        return abs(self.src[0] - self.dst[0]) + abs(self.src[1] - self.dst[1])


def index(xy: tuple[int, int]) -> int:
    return xy[1] * W + xy[0]


def core_tiles() -> list[tuple[int, int]]:
    """In tile order (x fastest), as the program's core_peers() lists them."""
    return [(x, y) for y in range(H) for x in range(W) if (x, y) != IO]


def own_task(xy: tuple[int, int]) -> int:
    return 1 + (xy[0] + xy[1] * W) % 14


def program_packets() -> list[Packet]:
    """What each core sends: every other core in tile order, then the I/O tile, each packet of
    1 + (seed >> 16) % 40 payload flits from the program's generator."""
    out = []
    for me in core_tiles():
        seed = ((me[0] << 4 | me[1]) * 2654435761 + 1) & M32
        for dst in [*(xy for xy in core_tiles() if xy != me), IO]:
            seed = (seed * 1103515245 + 12345) & M32
            out.append(Packet(me, dst, 2 + 1 + (seed >> 16) % 40))
    return out


def injected_packets() -> list[Packet]:
    """The host's: k + 1 payload flits to the k-th core tile."""
    return [Packet(IO, xy, 2 + k + 1) for k, xy in enumerate(core_tiles())]


STEP = {nk.EAST: (1, 0, nk.WEST), nk.WEST: (-1, 0, nk.EAST), nk.NORTH: (0, 1, nk.SOUTH), nk.SOUTH: (0, -1, nk.NORTH)}


def route(src: tuple[int, int], dst: tuple[int, int]) -> list[tuple[tuple[int, int], int, int]]:
    """(router, input port, output port) of every router on the XY route: x first, then y."""
    out = []
    (x, y), port_in = src, nk.LOCAL
    while (x, y) != dst:
        port_out = (nk.EAST if dst[0] > x else nk.WEST) if x != dst[0] else (nk.NORTH if dst[1] > y else nk.SOUTH)
        out.append(((x, y), port_in, port_out))
        dx, dy, port_in = STEP[port_out]
        x, y = x + dx, y + dy
    out.append(((x, y), port_in, nk.LOCAL))
    return out


def port_flits_by_hand(packets: list[Packet]) -> tuple[np.ndarray, np.ndarray]:
    """Flits written into each input buffer and sent through each output, per router and port."""
    flits_in = np.zeros((W * H, nk.NPORTS), dtype=np.int64)
    flits_out = np.zeros((W * H, nk.NPORTS), dtype=np.int64)
    for p in packets:
        for xy, port_in, port_out in route(p.src, p.dst):
            flits_in[index(xy), port_in] += p.flits
            flits_out[index(xy), port_out] += p.flits
    return flits_in, flits_out


def dma_by_hand(xy: tuple[int, int], packets: list[Packet]) -> int:
    """A SEND and a RECV each stall the core one cycle per flit of the packet."""
    return sum(p.flits for p in packets if xy in (p.src, p.dst))


# --- energy, written out here -------------------------------------------------------------------


def core_pj(counts: dict[str, int]) -> float:
    """Σ instructions × class pJ + stall cycles × kind pJ."""
    return math.fsum(counts.get(k, 0) * MODEL.instruction[k].pj for k in INSTRUCTION_CLASSES) + math.fsum(
        counts.get(k, 0) * MODEL.stall[k].pj for k in STALL_KINDS
    )


def router_pj(cycles: int, port_busy: int, router_busy: int) -> dict[str, float]:
    """One router over ``cycles``: its five buffers active or idle, its switch control active or idle, leakage."""
    c = {k: v.pj for k, v in MODEL.noc.items()}
    return {
        "buffers": port_busy * c["buffer_active"] + (cycles * nk.NPORTS - port_busy) * c["buffer_idle"],
        "control": router_busy * c["control_active"] + (cycles - router_busy) * c["control_idle"],
        "leakage": cycles * c["leakage"],
    }


@dataclass(frozen=True)
class Router:
    """One router's own counts, read from the NoC's state arrays."""

    xy: tuple[int, int]
    port_busy: int
    router_busy: int
    rtl_lost: int
    flits_in: np.ndarray
    flits_out: np.ndarray
    delivered: int


def routers(chip: MPSoC) -> list[Router]:
    port, tile = chip.noc.port, chip.noc.tile
    out = []
    for y in range(H):
        for x in range(W):
            t = index((x, y))
            out.append(
                Router(
                    (x, y), int(port[t, :, nk.P_BUSY].sum()), int(tile[t, nk.T_BUSY]), int(tile[t, nk.T_RTL_LOST]),
                    port[t, :, nk.P_FLITS_IN].copy(), port[t, :, nk.P_FLITS_OUT].copy(), int(tile[t, nk.T_RECV_PKTS]),
                )
            )  # fmt: skip
    return out


# --- the runs -------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def elf() -> Path:
    return build_elf([PROGRAM], mul=True)


@pytest.fixture(scope="module")
def runs(elf: Path):
    """(arbiter, engine) -> (chip, result) of the all-to-all run, each made once."""
    made: dict[tuple[str, str], tuple[MPSoC, ChipResult]] = {}

    def get(arbiter: str, engine: str) -> tuple[MPSoC, ChipResult]:
        if (arbiter, engine) not in made:
            chip = MPSoC(ChipConfig(width=W, height=H, noc=NocConfig(arbiter=arbiter)), engine=engine)
            chip.load_all(load_elf(elf, chip.regions()))
            for k, p in enumerate(injected_packets()):
                chip.inject(p.dst, list(range(p.flits - 2)), at_cycle=INJECT_AT + 50 * k)
            result = chip.run(max_cycles=1_000_000)
            assert all(f"got {len(core_tiles())} " in result.output[xy].decode() for xy in core_tiles())
            made[(arbiter, engine)] = chip, result
        return made[(arbiter, engine)]

    return get


@pytest.fixture(scope="module", params=CASES, ids=[f"{a}-{e}" for a, e in CASES])
def case(request, runs) -> tuple[MPSoC, ChipResult]:
    return runs(*request.param)


# --- the NoC --------------------------------------------------------------------------------------


def test_noc_counters_are_the_sums_over_every_router_corners_included(case) -> None:
    chip, result = case
    noc = chip.noc_counters()
    parts = routers(chip)
    assert len(parts) == W * H
    for r in parts:  # every router carried flits, so that leaving any one out changes a total
        assert r.port_busy > 0 and r.router_busy > 0 and r.flits_in.sum() > 0, r.xy
    cycles = result.cycles
    assert int(chip.noc.glob[nk.G_CYCLE]) - int(chip.noc.glob[nk.G_CYCLE0]) == cycles  # the NoC ran with the chip
    assert noc["router_cycles"] == cycles * W * H
    assert noc["router_busy_cycles"] == sum(r.router_busy for r in parts)
    assert noc["port_busy_cycles"] == sum(r.port_busy for r in parts)
    assert noc["port_idle_cycles"] == cycles * W * H * nk.NPORTS - sum(r.port_busy for r in parts)
    assert noc["rtl_lost_headers"] == sum(r.rtl_lost for r in parts)
    # a hop is a flit leaving a router by a port other than LOCAL; an injected flit enters a LOCAL input
    assert noc["flit_hops"] == sum(int(r.flits_out[: nk.LOCAL].sum()) for r in parts)
    assert noc["flit_hops"] == sum(int(r.flits_in[: nk.LOCAL].sum()) for r in parts)
    assert noc["flits_injected"] == sum(int(r.flits_in[nk.LOCAL]) for r in parts)
    assert noc["packets_delivered"] == sum(r.delivered for r in parts)


def test_noc_flit_counts_are_the_packets_worked_out_by_hand(case) -> None:
    chip, _ = case
    packets = program_packets() + injected_packets()
    flits_in, flits_out = port_flits_by_hand(packets)
    assert all(flits_in[index(xy)].sum() > 0 for xy in CORNERS)
    assert np.array_equal(chip.noc.port[:, :, nk.P_FLITS_IN], flits_in)
    assert np.array_equal(chip.noc.port[:, :, nk.P_FLITS_OUT], flits_out)
    noc = chip.noc_counters()
    assert noc["flit_hops"] == sum(p.flits * p.hops for p in packets)
    assert noc["flits_injected"] == sum(p.flits for p in packets)
    n = len(core_tiles())
    assert noc["packets_delivered"] == len(packets) == n * (n - 1) + n + n
    # the I/O tile received one packet from each core, of the length worked out for it
    got = sorted(len(flits) for _, flits in case[1].io_received)
    assert got == sorted(p.flits for p in packets if p.dst == IO)


def test_busy_plus_idle_is_cycles_times_units_for_ports_routers_and_cores(case) -> None:
    chip, result = case
    cycles = result.cycles
    noc = chip.noc_counters()
    assert noc["port_busy_cycles"] + noc["port_idle_cycles"] == cycles * W * H * nk.NPORTS
    assert noc["router_busy_cycles"] <= noc["router_cycles"] == cycles * W * H
    for r in routers(chip):
        busy = chip.noc.port[index(r.xy), :, nk.P_BUSY]
        # the router is busy while any of its buffers holds a flit: no less than its busiest, no more than all
        assert busy.max() <= r.router_busy <= min(cycles, int(busy.sum())), r.xy
    for xy in core_tiles():
        t = index(xy)
        c = chip.counters(xy)
        # a core cycle executes an instruction, stalls (of some kind, DMA and sleep included) or fills the pipeline
        assert c["cycles"] == int(chip.cores.st[t, S_CYCLE]) <= cycles
        assert c["cycles"] == c["instructions"] + sum(c[k] for k in STALL_KINDS) + PIPELINE_FILL, xy
        for task, tc in chip.task_counters(xy).items():
            fill = PIPELINE_FILL if task == 0 else 0  # a core starts in task 0
            assert tc["cycles"] == tc["instructions"] + sum(tc[k] for k in STALL_KINDS) + fill, (xy, task)


def test_noc_energy_is_every_routers_energy_summed(case) -> None:
    chip, result = case
    got = MODEL.noc_pj(chip.noc_counters())
    parts = [router_pj(result.cycles, r.port_busy, r.router_busy) for r in routers(chip)]
    assert set(got) == {"buffers", "control", "leakage"}
    for term in got:
        assert got[term] == pytest.approx(math.fsum(p[term] for p in parts), rel=1e-12), term
    # the idle terms by hand: every one of the W x H routers' five buffers idles when not busy
    c = {k: v.pj for k, v in MODEL.noc.items()}
    busy = sum(r.port_busy for r in routers(chip))
    idle_buffers = (result.cycles * W * H * nk.NPORTS - busy) * c["buffer_idle"]
    assert got["buffers"] - busy * c["buffer_active"] == pytest.approx(idle_buffers, rel=1e-12)
    assert got["leakage"] == pytest.approx(result.cycles * W * H * c["leakage"], rel=1e-12)


SPIN = 500


def spinner() -> Program:
    t1 = 6
    words = [A.i("addi", t1, 0, SPIN), A.i("addi", t1, t1, -1), A.branch("bne", t1, 0, -4), *exit_with(0)]
    return Program(path=Path("<asm>"), entry=0x40000000, segments=[(0x40000000, A.words_to_bytes(words))])


@pytest.mark.parametrize(
    "noc,router_cycles",
    [(NocConfig(), 5), (NocConfig(arbiter="per-output", routing_latency=2), 3)],
    ids=["hermes", "per-output"],
)
def test_one_packets_noc_energy_and_flit_hops_by_hand(noc: NocConfig, router_cycles: int) -> None:
    """One packet of L = 6 flits from the I/O tile (0, 0) to (1, 1) over (1, 0) on a 2x2 chip whose
    only core, (1, 0), counts down from 500 and exits.  The header waits ``router_cycles`` in each
    of the three routers' input buffers (Hermes: 5, docs/noc.md; per-output: routing latency + 1),
    the other flits follow one a cycle: each buffer on the way holds a flit at the start of
    router_cycles + L - 1 cycles, and so is its router busy; every other buffer and router idles.
    The chip's cycles: the first instruction in cycle 3, addi 1, 500 decrements of 1 and 499
    taken branches of 3 and a last one of 1, li 2 and the exit store 3."""
    chip = MPSoC(ChipConfig(noc=noc))
    chip.load((1, 0), spinner())
    payload = [7, 8, 9, 10]
    chip.inject((1, 1), payload, at_cycle=100)
    result = chip.run(max_cycles=100_000)
    length, hops, on_route = len(payload) + 2, 2, 3
    cycles = PIPELINE_FILL + 1 + SPIN + 3 * (SPIN - 1) + 1 + 2 + 3
    assert result.cycles == cycles == 2007
    busy = router_cycles + length - 1
    noc = chip.noc_counters()
    assert noc == {
        "router_cycles": cycles * 4,
        "router_busy_cycles": on_route * busy,
        "port_busy_cycles": on_route * busy,
        "port_idle_cycles": cycles * 4 * 5 - on_route * busy,
        "flit_hops": length * hops,
        "flits_injected": length,
        "packets_delivered": 1,
        "rtl_lost_headers": 0,
        "router_gated_cycles": 0,  # no clock gating
        "router_wakeups": 0,
    }
    c = {k: v.pj for k, v in MODEL.noc.items()}
    want = {
        "buffers": 3 * busy * c["buffer_active"] + (cycles * 4 * 5 - 3 * busy) * c["buffer_idle"],
        "control": 3 * busy * c["control_active"] + (cycles * 4 - 3 * busy) * c["control_idle"],
        "leakage": cycles * 4 * c["leakage"],
    }
    got = MODEL.noc_pj(noc)
    assert got.keys() == want.keys()
    for term, value in want.items():
        assert got[term] == pytest.approx(value, rel=1e-12), term


# --- the cores and their tasks -------------------------------------------------------------------


def test_tile_counters_are_the_state_arrays_and_the_packets_by_hand(case) -> None:
    chip, _ = case
    packets = program_packets() + injected_packets()
    n = len(core_tiles())
    assert chip.core_tiles() == core_tiles()
    for xy in core_tiles():
        t = index(xy)
        c = chip.counters(xy)
        assert c["cycles"] == int(chip.cores.st[t, S_CYCLE])
        assert c["instructions"] == int(chip.cores.opc[t, :OPC_SIZE].sum()) > 0  # every operation counted is one
        assert c["sleep_cycle"] == int(chip.cst[t, kc.K_SLEEP_CYCLES])
        assert c["dma_cycle"] == int(chip.cst[t, kc.K_DMA_CYCLES]) == dma_by_hand(xy, packets), xy
        assert c["packets_sent"] == int(chip.cst[t, kc.K_SENT]) == n  # every other core and the I/O tile
        assert c["packets_received"] == int(chip.cst[t, kc.K_RECEIVED]) == n  # every other core and the I/O tile
    # packets: every one sent by a core or the I/O tile was delivered to a core or the I/O tile
    sent = sum(chip.counters(xy)["packets_sent"] for xy in core_tiles()) + len(injected_packets())
    received = sum(chip.counters(xy)["packets_received"] for xy in core_tiles()) + len(case[1].io_received)
    assert sent == received == chip.noc_counters()["packets_delivered"]
    assert sum(chip.counters(xy)["sleep_cycle"] for xy in core_tiles()) > 0


def test_task_counters_add_up_to_their_tile_and_the_accounting_arrays(case) -> None:
    chip, _ = case
    packets = program_packets()
    for xy in core_tiles():
        t = index(xy)
        tasks = chip.task_counters(xy)
        own = own_task(xy)
        assert set(tasks) == {0, own, LAST_TASK}, xy
        assert set(np.flatnonzero(chip.acc[t].any(axis=1)).tolist()) == {0, own, LAST_TASK}
        total = chip.counters(xy)
        for name in tasks[0]:
            assert sum(tc[name] for tc in tasks.values()) == total[name], (xy, name)
        # the accounting rows, summed over every task id, are the core's own counters
        acc = chip.acc[t].sum(axis=0)
        assert np.array_equal(acc[:OPC_SIZE], chip.cores.opc[t, :OPC_SIZE])
        assert np.array_equal(acc[kc.A_CTR : kc.A_CTR + CTR_SIZE], chip.cores.ctr[t, :CTR_SIZE])
        assert acc[kc.A_CYCLES] == chip.cores.st[t, S_CYCLE]
        assert acc[kc.A_SLEEP] == chip.cst[t, kc.K_SLEEP_CYCLES]
        assert acc[kc.A_DMA] == chip.cst[t, kc.K_DMA_CYCLES]
        # by hand: only task 0 sleeps; every SEND's DMA is task 15's
        assert tasks[0]["sleep_cycle"] == total["sleep_cycle"]
        assert tasks[LAST_TASK]["dma_cycle"] >= sum(p.flits for p in packets if p.src == xy)
        assert tasks[own]["instructions"] > 0 and tasks[LAST_TASK]["instructions"] > 0


def test_the_counter_matrix_gives_every_tasks_counters_and_their_differences(case) -> None:
    chip, _ = case
    names, matrix = account_counter_map()
    rng = np.random.default_rng(5)
    for xy in core_tiles():
        for task, counters in chip.task_counters(xy).items():
            row = chip.acc[index(xy), task]
            assert dict(zip(names, (int(v) for v in matrix @ row), strict=True)) == counters
            # a flight's period: counters of the difference of two rows are the difference of counters
            earlier = row - rng.integers(0, np.maximum(row, 1), dtype=np.int64) * (row > 0)
            before = account_counters(earlier)
            assert dict(zip(names, (int(v) for v in matrix @ (row - earlier)), strict=True)) == {
                name: counters[name] - before[name] for name in names
            }


def test_task_energies_add_up_to_their_tiles(case) -> None:
    chip, _ = case
    for xy in core_tiles():
        tile = core_pj(chip.counters(xy))
        tasks = [core_pj(tc) for tc in chip.task_counters(xy).values()]
        assert all(pj > 0 for pj in tasks)
        assert math.fsum(tasks) == pytest.approx(tile, rel=1e-12), xy
        assert MODEL.total_nj(chip.counters(xy)) * 1000 == pytest.approx(tile, rel=1e-12)


@pytest.mark.parametrize("arbiter,engine", [c for c in CASES if c[1] != "interp"])
def test_every_engine_gives_the_interpreters_totals(runs, arbiter: str, engine: str) -> None:
    reference, _ = runs(arbiter, "interp")
    chip, _ = runs(arbiter, engine)
    for xy in core_tiles():
        assert chip.counters(xy) == reference.counters(xy), xy
        assert chip.task_counters(xy) == reference.task_counters(xy), xy
    assert chip.noc_counters() == reference.noc_counters()
    assert np.array_equal(chip.acc, reference.acc)
    for col in (nk.P_BUSY, nk.P_FLITS_IN, nk.P_FLITS_OUT):
        assert np.array_equal(chip.noc.port[:, :, col], reference.noc.port[:, :, col])
    assert np.array_equal(chip.noc.tile[:, nk.T_BUSY], reference.noc.tile[:, nk.T_BUSY])


def test_both_router_models_carry_the_same_flits(runs) -> None:
    hermes, per_output = (runs(a, "interp")[0] for a in ARBITERS)
    for key in ("flit_hops", "flits_injected", "packets_delivered"):
        assert hermes.noc_counters()[key] == per_output.noc_counters()[key], key
    assert np.array_equal(hermes.noc.port[:, :, nk.P_FLITS_IN], per_output.noc.port[:, :, nk.P_FLITS_IN])


# --- robosoc run --mesh ---------------------------------------------------------------------------


def test_run_mesh_stats_are_the_chips_totals(tmp_path: Path) -> None:
    """``robosoc run --mesh 3x3 --stats``: each tile's counters, tasks and energy, the NoC's and the
    chip's, against the same program run here on an MPSoC whose arrays are read directly."""
    elf = build_elf([PROGRAM], mul=True, defines={"FROM_IO": 0})
    stats_path = tmp_path / "stats.json"
    ran = CliRunner().invoke(app, ["run", str(elf), "--mesh", f"{W}x{H}", "--stats", str(stats_path)])
    assert ran.exit_code == 0, ran.output
    stats = json.loads(stats_path.read_text())
    chip = MPSoC(ChipConfig(width=W, height=H))
    chip.load_all(load_elf(elf, chip.regions()))
    result = chip.run(max_cycles=1_000_000)
    assert stats["cycles"] == result.cycles
    assert set(stats["tiles"]) == {f"{x},{y}" for x, y in core_tiles()}
    tiles_nj = []
    for xy in core_tiles():
        got = stats["tiles"][f"{xy[0]},{xy[1]}"]
        assert got["counters"] == chip.counters(xy)
        tile_pj = core_pj(chip.counters(xy))
        tiles_nj.append(tile_pj / 1000)
        assert got["energy_nj"] == pytest.approx(tile_pj / 1000, rel=1e-12)
        assert set(got["tasks"]) == {"0", str(own_task(xy)), str(LAST_TASK)}
        for task, tc in chip.task_counters(xy).items():
            assert got["tasks"][str(task)]["counters"] == tc
            assert got["tasks"][str(task)]["energy_nj"] == pytest.approx(core_pj(tc) / 1000, rel=1e-12)
        assert math.fsum(t["energy_nj"] for t in got["tasks"].values()) == pytest.approx(got["energy_nj"], rel=1e-12)
    n = len(core_tiles())
    assert stats["noc"]["counters"] == chip.noc_counters()
    assert stats["noc"]["counters"]["packets_delivered"] == n * n  # every other core and the I/O tile
    assert stats["noc"]["counters"]["flit_hops"] == sum(p.flits * p.hops for p in program_packets())
    noc_pj = [router_pj(result.cycles, r.port_busy, r.router_busy) for r in routers(chip)]
    noc_nj = math.fsum(sum(p.values()) for p in noc_pj) / 1000
    assert stats["noc"]["energy_nj"] == pytest.approx(noc_nj, rel=1e-12)
    assert stats["energy_nj"] == pytest.approx(math.fsum(tiles_nj) + noc_nj, rel=1e-12)
