"""The quantum scheme of the chip simulator gives exactly the results of lockstep simulation.

robosoc advances cores and the NoC in quanta chosen so that nothing one tile does can reach
another inside a quantum (docs/platform.md, "Time"; docs/noc.md derives their lengths for each
router model).  Running the same programs with every quantum one cycle long must therefore give
bit-identical outputs, counters and network activity, with either router model.  A traffic
program (every tile sends packets of random length to every other, receives in its interrupt
handler, sleeps while waiting) exercises idle and busy network phases, back-pressure, DMA,
interrupts and sleep.
"""

from collections.abc import Sequence
from pathlib import Path

import pytest

from robosoc.chip.mpsoc import MPSoC
from robosoc.config.chip import ChipConfig, NocConfig
from robosoc.kernels import chip as kc
from robosoc.kernels.core_layout import NEVER, S_IRQ_IDLE
from robosoc.program.elf import load_elf
from robosoc.toolchain import build_elf

TRAFFIC = Path(__file__).parent / "programs" / "traffic.c"


def run(config: ChipConfig, lockstep: bool, rounds: int):
    program = load_elf(build_elf([TRAFFIC], mul=True, defines={"ROUNDS": rounds}))
    chip = MPSoC(config, lockstep=lockstep)
    chip.load_all(program)
    result = chip.run(max_cycles=20_000_000)
    tiles = {xy: chip.counters(xy) for xy in chip.core_tiles()}
    tasks = {xy: chip.task_counters(xy) for xy in chip.core_tiles()}
    return result.output, result.cycles, tiles, tasks, chip.noc_counters()


# receive interrupts meet the multiplies of the traffic program's random generator now and then:
# the erratum report (spec mode) is expected there
pytestmark = pytest.mark.filterwarnings("ignore::robosoc.chip.single.IrqDuringMulErratum")

PER_OUTPUT = NocConfig(arbiter="per-output")


@pytest.mark.parametrize(
    "config,rounds",
    [
        (ChipConfig(), 6),
        (ChipConfig(width=3, height=2), 3),
        (ChipConfig(width=3, height=2, noc=NocConfig(buffer_depth=2)), 3),
        (ChipConfig(noc=PER_OUTPUT), 6),
        (ChipConfig(width=3, height=2, noc=PER_OUTPUT), 3),
        (ChipConfig(width=3, height=2, noc=NocConfig(buffer_depth=2, routing_latency=1, arbiter="per-output")), 3),
        # clock-gated routers (docs/noc.md): wake-ups only delay, the quanta stay exact
        (ChipConfig(width=3, height=2, noc=NocConfig(clock_gating=True, gate_after_cycles=3, wake_cycles=2)), 3),
        (ChipConfig(noc=NocConfig(arbiter="per-output", clock_gating=True, gate_after_cycles=1, wake_cycles=5)), 6),
    ],
    ids=[
        "hermes-2x2",
        "hermes-3x2",
        "hermes-3x2-shallow",
        "per-output-2x2",
        "per-output-3x2",
        "per-output-3x2-fast",
        "hermes-3x2-gated",
        "per-output-2x2-gated",
    ],
)
def test_quanta_give_the_lockstep_results(config: ChipConfig, rounds: int):
    fast = run(config, lockstep=False, rounds=rounds)
    slow = run(config, lockstep=True, rounds=rounds)
    output, _, tiles, _, noc = fast
    n_cores = len(tiles)
    for xy, text in output.items():
        assert f"got {rounds * (n_cores - 1)} " in text.decode(), (xy, text)
    assert noc["packets_delivered"] == rounds * n_cores * (n_cores - 1)
    assert (noc["router_wakeups"] > 0) == config.noc.clock_gating  # gated runs do wake routers up
    assert fast == slow


@pytest.mark.parametrize("arbiter", ["hermes", "per-output"])
def test_quanta_give_the_lockstep_results_with_packets_from_the_io_tile(arbiter: str):
    def run_with_io(lockstep: bool):
        program = load_elf(build_elf([TRAFFIC], mul=True, defines={"ROUNDS": 4}))
        chip = MPSoC(ChipConfig(noc=NocConfig(arbiter=arbiter)), lockstep=lockstep)
        chip.load_all(program)
        for k, at in enumerate(range(300, 6000, 700)):
            chip.inject((1, 0) if k % 2 else (1, 1), list(range(k + 1)), at_cycle=at)
        result = chip.run(max_cycles=20_000_000)
        return result.output, result.cycles, {xy: chip.counters(xy) for xy in chip.core_tiles()}

    fast, slow = run_with_io(False), run_with_io(True)
    received = sum(c["packets_received"] for c in fast[2].values())
    assert received == 4 * 3 * 2 + 9  # all-to-all traffic plus the nine injected packets
    assert fast == slow


@pytest.mark.parametrize("arbiter", ["hermes", "per-output"])
def test_send_status_polls_see_the_network_of_their_cycle(arbiter: str):
    # 3-flit packets through 2-flit buffers: when the send memory frees up depends on the routers,
    # so every NI_STATUS poll needs the network as it is in the poll's own cycle
    program = load_elf(build_elf([Path(__file__).parent / "programs" / "send_burst.c"], mul=True))

    def one(lockstep: bool):
        chip = MPSoC(ChipConfig(noc=NocConfig(buffer_depth=2, arbiter=arbiter)), lockstep=lockstep)
        chip.load((1, 0), program)
        result = chip.run(max_cycles=1_000_000)
        return result.cycles, result.io_received, chip.counters((1, 0))

    fast, slow = one(False), one(True)
    assert len(fast[1]) == 20
    assert fast == slow


def test_a_breakpoint_stops_the_chip_without_changing_any_cycle():
    # the traffic program with a breakpoint on one tile's receive handler: the chip stops there
    # (mid-quantum), the host looks, clears the mark and lets it go on; outputs, counters and the
    # network's activity must equal an undisturbed run
    program = load_elf(build_elf([TRAFFIC], mul=True, defines={"ROUNDS": 3}))
    handler = program.address_of("irq_handler")

    def undisturbed():
        chip = MPSoC(ChipConfig())
        chip.load_all(program)
        result = chip.run(max_cycles=20_000_000)
        return result.output, result.cycles, {xy: chip.counters(xy) for xy in chip.core_tiles()}, chip.noc_counters()

    chip = MPSoC(ChipConfig())
    chip.load_all(program)
    chip.set_breakpoint((1, 1), handler)
    stops = []
    while (why := chip.step(20_000_000)) == kc.CHIP_BREAK:
        xy = chip.break_tile()
        stops.append((chip.tile_cycle(xy), chip.pc(xy)))
        assert xy == (1, 1) and chip.pc(xy) == handler
        chip.set_breakpoint(xy, handler, on=False)
        chip.resume_from_break()
        if len(stops) < 3:  # stop at the next three handler entries too
            chip.step(chip.cycle + 1)
            chip.set_breakpoint(xy, handler)
    assert why == kc.CHIP_DONE
    assert len(stops) == 3 and stops == sorted(stops)
    output = chip.drain_output()
    result = undisturbed()
    assert result[0] == output
    assert result[2] == {xy: chip.counters(xy) for xy in chip.core_tiles()}
    assert result[3] == chip.noc_counters()
    assert result[1] == chip.cycle


def test_where_the_host_stops_the_chip_changes_nothing():
    # The flight firmware on the seed's chip: both cores sleep most of the time, one wakes on a
    # sensor packet while the other is due at its next tick.  Advancing the chip in one call or in
    # many short ones must give the same jobs, cycles and counters (a sleeper due later once woke
    # inside a long single-core quantum and ran ahead of the packet sent to it).
    from robosoc.config.firmware import FirmwareConfig
    from robosoc.cosim.replay import built_in_rows, samples_from_rows
    from robosoc.host import images
    from robosoc.host.scenario_image import firmware_image

    fw = FirmwareConfig()
    image = firmware_image(fw)
    program = load_elf(image.elf)
    (tile, port) = image.sensor
    samples = samples_from_rows(built_in_rows(0.03, seed=1), 4.0)
    end = samples[-1].cycle + 2_500_000

    def run(steps):
        chip = MPSoC(fw.seed_chip())
        for xy in image.tiles:
            chip.load(xy, program)
        for k, s in enumerate(samples):
            for payload in images.io_packets(s.payload, port, chip.config.io_tile, k):
                chip.inject(tile, payload, s.cycle)
        for c in steps:
            chip.step(c)
        chip.finish_accounting()
        logs = {xy: images.read_job_log(chip, xy).records for xy in image.tiles}
        return logs, {xy: chip.counters(xy) for xy in image.tiles}, chip.received()

    one_call = run([end])
    assert sum(len(r) for r in one_call[0].values()) == 2 * len(samples)
    assert one_call == run(range(100_000, end + 100_000, 100_000))
    assert one_call == run([s.cycle for s in samples] + [end])


# --- long quanta: cores deaf to the packet line run far ahead of each other ---------------------
MIXED = Path(__file__).parent / "programs" / "mixed.c"
MIXED_ROUNDS = 2


def run_mixed(config: ChipConfig, lockstep: bool, seed: int, late: int, steps: Sequence[int] = ()):
    """mixed.c with I/O packets injected into every core tile; ``steps``: advance in these calls first."""
    program = load_elf(build_elf([MIXED], mul=True, defines={"ROUNDS": MIXED_ROUNDS, "SEED": seed, "LATE": late}))
    chip = MPSoC(config, lockstep=lockstep)
    chip.load_all(program)
    tiles = chip.core_tiles()
    for k, at in enumerate(range(400, 12_000, 1100)):
        chip.inject(tiles[(k * 5) % len(tiles)], [0xFFFF, *range(k + 1)], at_cycle=at)
    for c in steps:
        chip.step(c)
    result = chip.run(max_cycles=20_000_000)
    tiles = {xy: chip.counters(xy) for xy in chip.core_tiles()}
    tasks = {xy: chip.task_counters(xy) for xy in chip.core_tiles()}
    return result.output, result.cycles, tiles, tasks, chip.noc_counters()


@pytest.mark.parametrize(
    "config,seed,late",
    [
        (ChipConfig(), 1, 1),
        (ChipConfig(), 3, 9),
        (ChipConfig(width=3, height=2), 2, 1),
        (ChipConfig(width=3, height=2, noc=NocConfig(buffer_depth=2)), 3, 2),
        (ChipConfig(width=3, height=3, noc=PER_OUTPUT), 1, 2),
        (ChipConfig(width=4, height=2, noc=NocConfig(buffer_depth=2, arbiter="per-output")), 2, 1),
    ],
    ids=["2x2", "2x2-no-late", "3x2", "3x2-shallow", "per-output-3x3", "per-output-4x2-shallow"],
)
def test_long_quanta_give_the_lockstep_results(config: ChipConfig, seed: int, late: int):
    # pollers that read NI_STATUS and IRQ_CAUSE, tick-driven sleepers the packets cannot wake and
    # tiles that unmask the packet line half-way, with I/O packets arriving throughout: the long
    # quanta of the deaf cores must give exactly the cycles, counters and outputs of lockstep
    fast = run_mixed(config, False, seed, late)
    slow = run_mixed(config, True, seed, late)
    output, _, tiles, _, _ = fast
    n_cores = len(tiles)
    roles = set()
    for xy, text in output.items():
        line = text.decode()
        assert f" got {MIXED_ROUNDS * (n_cores - 1)} " in line, (xy, line)
        roles.add(line.split(" role ")[1][0])
    assert len(roles) >= 2  # at least two of the three roles on every mesh
    assert fast == slow


def test_long_quanta_do_not_depend_on_where_the_host_stops_the_chip():
    config = ChipConfig(width=3, height=2)
    one_call = run_mixed(config, False, 2, 1)
    assert one_call == run_mixed(config, False, 2, 1, steps=range(997, 400_000, 997 * 7))


def test_deaf_busy_cores_run_in_long_quanta_with_the_lockstep_results():
    # the matrix workload on every core of a 3x3 mesh: no core listens to the packet line, so the
    # chip needs a handful of quanta instead of one per 17 cycles, with the same counters
    from robosoc.firmware import FIRMWARE_DIR

    program = load_elf(build_elf([FIRMWARE_DIR / "bench" / "matrix_bench.c"], mul=True,
                             defines={"BENCH_ITERATIONS": 100000, "BENCH_QUIET": None}))  # fmt: skip
    cycles = 60_000

    def one(lockstep: bool):
        chip = MPSoC(ChipConfig(width=3, height=3), lockstep=lockstep)
        chip.load_all(program)
        chip.step(cycles)
        return {xy: (chip.counters(xy), chip.tile_cycle(xy), chip.pc(xy)) for xy in chip.core_tiles()}, int(
            chip.gst[kc.G_QUANTA]
        )

    (fast, quanta), (slow, _) = one(False), one(True)
    assert fast == slow
    assert quanta <= 2  # one quantum of kc.SINGLE_QUANTUM cycles at most would do


# --- long quanta through interrupt handlers: a core with interrupts off hears no packet -----------
HANDLERS = Path(__file__).parent / "programs" / "handlers.c"


def run_handlers(config: ChipConfig, lockstep: bool, seed: int, long_quanta: bool = True):
    program = load_elf(build_elf([HANDLERS], mul=True, defines={"ROUNDS": 3, "SEED": seed}))
    chip = MPSoC(config, lockstep=lockstep)
    chip.allow_long_quanta(long_quanta)
    chip.load_all(program)
    result = chip.run(max_cycles=20_000_000)
    tiles = {xy: chip.counters(xy) for xy in chip.core_tiles()}
    tasks = {xy: chip.task_counters(xy) for xy in chip.core_tiles()}
    return (result.output, result.cycles, tiles, tasks, chip.noc_counters()), int(chip.gst[kc.G_QUANTA])


@pytest.mark.parametrize(
    "config,seed",
    [(ChipConfig(), 1), (ChipConfig(), 2), (ChipConfig(width=3, height=2), 3), (ChipConfig(width=3, height=3), 4)],
    ids=["2x2", "2x2-seed2", "3x2", "3x3"],
)
def test_handlers_run_in_long_quanta_with_the_lockstep_results(config: ChipConfig, seed: int):
    # ticks whose handlers work for hundreds of cycles with interrupts off while packets arrive,
    # returns that turn the packet line back on, sleeps with interrupts off that a packet ends: the
    # handlers run in long quanta (fewer quanta than with short ones only: a third fewer on the 3x3 mesh, whose
    # main loops often listen), and every cycle,
    # counter and output is the lockstep one
    (fast, quanta) = run_handlers(config, False, seed)
    (short, short_quanta) = run_handlers(config, False, seed, long_quanta=False)
    (slow, _) = run_handlers(config, True, seed)
    output, _, tiles, _, _ = fast
    n_cores = len(tiles)
    for xy, text in output.items():
        line = text.decode()
        assert f" got {3 * (n_cores - 1)} " in line, (xy, line)
        assert int(line.split(" ticks ")[1].split()[0]) >= 3, (xy, line)  # handlers did run
    assert fast == slow
    assert short == slow
    assert quanta < 0.8 * short_quanta


# --- long quanta inside interrupt handlers: a done controller hears no packet ------------------
BUSY_HANDLERS = Path(__file__).parent / "programs" / "busy_handlers.c"
BUSY_TICKS, BUSY_WORK, BUSY_PERIOD = 8, 200, 5000


def run_busy_handlers(config: ChipConfig, lockstep: bool, steps: Sequence[int] = ()):
    """busy_handlers.c; ``steps``: advance in these calls first, noting after each the quanta so far
    and whether every core is inside its handler (its controller done)."""
    defines = {"TICKS": BUSY_TICKS, "WORK": BUSY_WORK, "PERIOD": BUSY_PERIOD}
    program = load_elf(build_elf([BUSY_HANDLERS], mul=True, defines=defines))
    chip = MPSoC(config, lockstep=lockstep)
    chip.load_all(program)
    seen = []
    for c in steps:
        chip.step(c)
        inside = all(chip.cores.st[config.tile_index(xy), S_IRQ_IDLE] >= NEVER for xy in chip.core_tiles())
        seen.append((int(chip.gst[kc.G_QUANTA]), inside))
    result = chip.run(max_cycles=20_000_000)
    tiles = {xy: chip.counters(xy) for xy in chip.core_tiles()}
    tasks = {xy: chip.task_counters(xy) for xy in chip.core_tiles()}
    return (result.output, result.cycles, tiles, tasks, chip.noc_counters()), seen, int(chip.gst[kc.G_LOOK_IDLE])


@pytest.mark.parametrize(
    "config", [ChipConfig(), ChipConfig(width=3, height=2, noc=PER_OUTPUT)], ids=["hermes-2x2", "per-output-3x2"]
)
def test_cores_inside_their_handlers_run_in_long_quanta_with_the_lockstep_results(config: ChipConfig):
    # Every core takes the same tick and computes in its handler with IRQ_MASK's packet bit set; a
    # quarter of the way in it sends a packet, three quarters in it reads IRQ_CAUSE, and packets that
    # arrive after that read are let in by the re-enabling store.  The first tick (TIMER1 counts every
    # cycle from reset, clears at PERIOD) is entered a few cycles after cycle PERIOD; a handler runs at
    # least WORK iterations of a multiply (>= 5 cycles each), so every core is inside its handler
    # over [PERIOD + 100, PERIOD + 900].  Short quanta there would be G_LOOK_IDLE cycles each (47 of
    # them); inside a handler the controller is done, so the chip runs long quanta, cut by the sends.
    a, b = BUSY_PERIOD + 100, BUSY_PERIOD + 900
    fast, seen, look_idle = run_busy_handlers(config, False, steps=[a, b])
    slow, _, _ = run_busy_handlers(config, True)
    assert fast == slow
    output = fast[0]
    assert len(output) == config.width * config.height - 1  # every tile but the I/O tile
    got = seen_in_handler = late = 0
    for text in output.values():
        words = text.decode().split()
        assert int(words[3]) >= BUSY_TICKS, text
        got += int(words[5])
        seen_in_handler += int(words[7])
        late += int(words[9])
    # every packet sent (one per tick but the last two) arrived, some seen by the IRQ_CAUSE read in the
    # handler, the others let in by the re-enabling store
    assert got == len(output) * (BUSY_TICKS - 2) == seen_in_handler + late
    assert seen_in_handler > 0 and late > 0
    (q_a, inside_a), (q_b, inside_b) = seen
    assert inside_a and inside_b
    assert q_b - q_a < (b - a) // look_idle // 4
