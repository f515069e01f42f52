"""A tile's core on its own clock: the chip's (NoC) clock divided by d (``[[chip.tiles]]``
``clock_period_ns`` a whole multiple of ``chip.tile.clock_period_ns``; docs/power.md, "Per-tile clock").

The core executes one of its cycles every d chip cycles; its timers, counters and energy are in its
own cycles; the network interface and the routers keep the chip's clock.  Checked by hand-derived
cycles (a known sequence takes exactly d times the chip cycles, a packet crosses the network in the
same cycles whatever the sender's clock), energy against the counters times the V²-scaled
coefficients, and the quantum scheme and the engines against lockstep and the interpreter on a chip
whose tiles run at three different clocks.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest

import rv32_asm as A
from core_harness import exit_with
from robosoc.chip.energy import EnergyModel
from robosoc.chip.mpsoc import MPSoC
from robosoc.config.chip import ChipConfig, DvfsConfig, NocConfig, TileOverride
from robosoc.kernels import chip as kc
from robosoc.kernels.core_layout import PIPELINE_FILL
from robosoc.program.elf import Program, load_elf
from robosoc.toolchain import build_elf

TRAFFIC = Path(__file__).parent / "programs" / "traffic.c"
SRAM = 0x40000000
NI = 0xE1040000
T0, T1, T2, A0 = 5, 6, 7, 10
MODEL = EnergyModel.load()
POINTS = ((62.5, 0.7), (125.0, 0.8), (250.0, 1.0))

pytestmark = pytest.mark.filterwarnings("ignore::robosoc.chip.single.IrqDuringMulErratum")


def divided(d: int, xy: tuple[int, int] = (1, 0), **kw: object) -> ChipConfig:
    """The seed's 2x2 at 4 ns with tile ``xy``'s core at 4·d ns."""
    tiles = () if d == 1 else (TileOverride(x=xy[0], y=xy[1], clock_period_ns=4.0 * d),)
    return ChipConfig(tiles=tiles, **kw)  # type: ignore[arg-type]


def program(words: list[int], data: dict[int, bytes] | None = None) -> Program:
    segments = [(SRAM, A.words_to_bytes(words)), *(data or {}).items()]
    return Program(path=Path("<asm>"), entry=SRAM, segments=segments)


def adds(k: int) -> Program:
    """``k`` independent additions, then the exit store."""
    return program([*(A.i("addi", A0, A0, 1) for _ in range(k)), *exit_with(A0)])


def run_alone(config: ChipConfig, prog: Program, engine: str = "interp") -> tuple[MPSoC, int]:
    chip = MPSoC(config, engine=engine)
    chip.load((1, 0), prog)
    return chip, chip.run(max_cycles=10_000_000).cycles


@pytest.mark.parametrize("d", [2, 3])
def test_a_known_sequence_takes_exactly_d_times_the_chip_cycles(d: int) -> None:
    # 100 more additions (1 core cycle each) cost 100 chip cycles at the chip's clock, 100·d divided
    base1, more1 = run_alone(divided(1), adds(10))[1], run_alone(divided(1), adds(110))[1]
    chip, base_d = run_alone(divided(d), adds(10))
    more_d = run_alone(divided(d), adds(110))[1]
    assert more1 - base1 == 100
    assert more_d - base_d == 100 * d
    # the whole run too: the core counts the same cycles, each lasting d chip cycles
    assert base_d == d * base1
    assert chip.counters((1, 0))["cycles"] == base1 and chip.tile_cycle((1, 0)) == base_d
    assert chip.exit_code((1, 0)) == 10


def test_a_divided_tiles_energy_scales_with_v_squared_and_its_leakage_with_v_and_the_period() -> None:
    chip_cfg = divided(2, dvfs=DvfsConfig(points=POINTS))  # the tile at 8 ns: 125 MHz, 0.8 V
    model = MODEL.for_tile(chip_cfg, (1, 0))
    assert model.instruction["add"].pj == pytest.approx(23.58 * 0.8**2, rel=1e-12)
    assert model.stall["sleep_cycle"].pj == pytest.approx(0.9 * 0.8 * 2, rel=1e-12)
    assert MODEL.for_tile(chip_cfg, (0, 1)) == MODEL.for_chip(chip_cfg)  # the other tiles at the chip's point
    # 100 additions more cost 100 × 23.58 pJ × 0.64 on the divided tile
    energies = []
    for k in (10, 110):
        chip, _ = run_alone(chip_cfg, adds(k))
        chip.finish_accounting()
        energies.append(model.total_pj(chip.counters((1, 0))))
    assert energies[1] - energies[0] == pytest.approx(100 * 23.58 * 0.64, rel=1e-9)
    # without points a divided core keeps the chip's voltage: switching energy as is, leakage per
    # (twice as long) core cycle doubled
    plain = MODEL.for_tile(divided(2), (1, 0))
    assert plain.instruction["add"].pj == MODEL.instruction["add"].pj
    assert plain.stall["sleep_cycle"].pj == pytest.approx(0.9 * 2, rel=1e-12)


def sender() -> Program:
    """Tile (1, 0) sends a 5-flit packet (destination the I/O tile (0, 0)) after a few instructions,
    then spins."""
    packet = SRAM + 0x400
    words = [
        *A.li(T0, NI),
        *A.li(T1, packet),
        A.store("sw", T1, T0, 0x04),  # SEND_ADDR
        A.i("addi", T2, 0, 5),
        A.store("sw", T2, T0, 0x08),  # SEND_SIZE
        A.i("addi", T2, 0, 1),
        A.store("sw", T2, T0, 0x0C),  # SEND
        A.jal(0, 0),  # and spin
    ]
    return program(words, {packet: b"".join(v.to_bytes(2, "little") for v in (0x00, 3, 7, 8, 9))})


@pytest.mark.parametrize("d", [2, 4])
def test_a_packet_from_a_slow_tile_crosses_the_network_at_the_chips_clock(d: int) -> None:
    def send(config: ChipConfig) -> tuple[int, int]:
        chip = MPSoC(config)
        chip.record_timeline()
        chip.load((1, 0), sender())
        chip.step(2000)
        ((arrival, flits),) = chip.received()
        assert flits == [0x00, 3, 7, 8, 9]
        rows, _ = chip.timeline()
        (start,) = [int(r[2]) for r in rows if r[0] == kc.R_SEND]
        return start, arrival

    start1, arrival1 = send(divided(1))
    start_d, arrival_d = send(divided(d))
    # the store and the DMA (a flit per core cycle) are the core's: the injection starts d times later
    assert start_d == d * start1
    # the network (one hop, two Hermes routers, 5 flits) is the chip's: 5·2 + 5 − 1 cycles from the
    # injection's start to the last flit written at the I/O tile, whatever the sender's clock
    assert arrival1 - start1 == arrival_d - start_d == 5 * 2 + 5 - 1


def receiver() -> Program:
    """Tile (1, 0) polls NI_STATUS until a packet waits, then exits with the number of polls."""
    words = [
        *A.li(T0, NI),
        A.i("addi", A0, 0, 0),
        A.i("addi", A0, A0, 1),  # a poll: 1 cycle
        A.load("lw", T2, T0, 0x00),  # NI_STATUS: 3 cycles, reads the core cycle before it
        A.i("andi", T2, T2, 2),  # 1
        A.branch("beq", T2, 0, -12),  # 3 taken: back to the addi
        *exit_with(A0),
    ]
    return program(words)


@pytest.mark.parametrize("d", [1, 2, 3])
def test_a_slow_tile_sees_a_packet_at_its_first_cycle_after_the_arrival(d: int) -> None:
    """The packet's arrival is the chip's (the I/O tile injects it at a chip cycle); the divided core
    sees NI_STATUS bit 1 in the first poll whose registered read (the core cycle before the load,
    which begins in chip cycle (s − 1)·d) is at or after the cycle the receive memory holds it."""
    chip = MPSoC(divided(d))
    chip.record_timeline()
    chip.load((1, 0), receiver())
    chip.inject((1, 0), [1, 2, 3], at_cycle=501)
    chip.run(max_cycles=100_000)
    rows, _ = chip.timeline()
    (ready,) = [int(r[2]) for r in rows if r[0] == kc.R_DELIVER and r[1] == 1]
    assert ready == 501 + 5 * 2 + 5 - 1 + 1  # one hop, 5 flits, visible from the cycle after the last
    # by hand: the core starts in its cycle PIPELINE_FILL; li and addi take a cycle each, a loop
    # iteration 1 + 3 + 1 + 3 = 8; poll j's load begins in core cycle F + len(li) + 2 + 8(j − 1)
    first = PIPELINE_FILL + len(A.li(T0, NI)) + 2
    expect = next(j for j in range(1, 10**6) if (first + 8 * (j - 1) - 1) * d >= ready)
    assert chip.exit_code((1, 0)) == expect
    assert expect > 1  # the packet came while the core polled


def traffic(config: ChipConfig, engine: str = "interp", lockstep: bool = False, rounds: int = 3) -> tuple:
    prog = load_elf(build_elf([TRAFFIC], mul=True, defines={"ROUNDS": rounds}))
    chip = MPSoC(config, engine=engine, lockstep=lockstep)
    chip.load_all(prog)
    result = chip.run(max_cycles=40_000_000)
    tiles = {xy: chip.counters(xy) for xy in chip.core_tiles()}
    tasks = {xy: chip.task_counters(xy) for xy in chip.core_tiles()}
    return result.output, result.cycles, tiles, tasks, chip.noc_counters()


THREE_CLOCKS = ChipConfig(
    tiles=(TileOverride(x=1, y=0, clock_period_ns=8.0), TileOverride(x=0, y=1, clock_period_ns=12.0))
)


@pytest.mark.parametrize(
    "config",
    [THREE_CLOCKS, dataclasses.replace(THREE_CLOCKS, noc=NocConfig(arbiter="per-output", buffer_depth=2))],
    ids=["hermes", "per-output-shallow"],
)
def test_quanta_give_the_lockstep_results_with_divided_clocks(config: ChipConfig) -> None:
    fast = traffic(config)
    assert fast == traffic(config, lockstep=True)
    output, _, _, _, noc = fast
    for xy, text in output.items():
        assert "got 6 " in text.decode(), (xy, text)  # 3 rounds from each of the two others
    assert noc["packets_delivered"] == 3 * 3 * 2
    assert fast != traffic(ChipConfig(noc=config.noc))  # the clocks do change the run


@pytest.mark.parametrize("engine", ["jit", "auto"])
def test_every_engine_gives_the_interpreters_chip_with_divided_clocks(engine: str) -> None:
    assert traffic(THREE_CLOCKS, engine=engine) == traffic(THREE_CLOCKS)


def test_a_tile_clock_that_does_not_divide_the_chips_is_refused() -> None:
    with pytest.raises(ValueError, match=r"tiles\[0\]\.clock_period_ns: 6 ns is not a whole multiple of the chip's"):
        ChipConfig(tiles=(TileOverride(x=1, y=0, clock_period_ns=6.0),))
    with pytest.raises(ValueError, match=r"tiles\[0\]\.clock_period_ns: 2 ns is not a whole multiple"):
        ChipConfig(tiles=(TileOverride(x=1, y=0, clock_period_ns=2.0),))  # faster than the NoC
    with pytest.raises(ValueError, match=r"clock_period_ns: 400 ns is the chip's clock \(4 ns\) divided by 100"):
        ChipConfig(tiles=(TileOverride(x=1, y=0, clock_period_ns=400.0),))
    with pytest.raises(ValueError, match=r"tiles\[0\]\.clock_period_ns: 4 ns \(250 MHz\) is faster than the highest"):
        ChipConfig(
            tile=dataclasses.replace(ChipConfig().tile, clock_period_ns=2.0),
            tiles=(TileOverride(x=1, y=0, clock_period_ns=4.0),),
            dvfs=DvfsConfig(points=((125.0, 0.8), (200.0, 0.9))),
        )
