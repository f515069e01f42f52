"""The debug targets step one instruction at a time and stop at marks without changing any cycle.

Stepping a core through its whole program (every instruction a separate run call that ends
before the next instruction) must leave every counter, every cycle and the network exactly as in
an undisturbed run, on one core and on a tile of the MPSoC (where each step runs the whole chip).
"""

from __future__ import annotations

import signal
from pathlib import Path

import numpy as np
import pytest

from robosoc.chip.mpsoc import MPSoC
from robosoc.chip.single import SingleCoreSoC
from robosoc.config.chip import ChipConfig
from robosoc.debug.points import Kind, Points, memory_access
from robosoc.debug.target import ChipTarget, MemoryRefused, Outcome, Progress, SingleCoreTarget, Target
from robosoc.isa.table import OP_BREAK
from robosoc.kernels.core_layout import S_IRQ_VECTOR, S_MAX_CYCLES
from robosoc.kernels.dev_irq import IRQ_VECTOR
from robosoc.kernels.dev_timer import TIMER0
from robosoc.kernels.ni_registers import NI_BASE, NI_MESH, NI_TILE
from robosoc.program.elf import load_elf

pytestmark = pytest.mark.filterwarnings("ignore::robosoc.chip.single.IrqDuringMulErratum")


def single(elf: Path) -> SingleCoreSoC:
    soc = SingleCoreSoC()
    soc.load(load_elf(elf, soc.regions()))
    return soc


def chip_with(elf: Path) -> MPSoC:
    chip = MPSoC(ChipConfig())
    chip.load_all(load_elf(elf, chip.regions()))
    return chip


def chip_facts(chip: MPSoC) -> tuple:
    chip.finish_accounting()
    tiles = chip.core_tiles()
    return (
        chip.cycle,
        {xy: chip.counters(xy) for xy in tiles},
        {xy: chip.task_counters(xy) for xy in tiles},
        chip.noc_counters(),
    )


def run_until_stop(target: Target, until: int = 10**9) -> Progress:
    """Run in the slices the GDB server uses until the target stops, exits or fails."""
    while True:
        progress = target.run(min(until, target.now() + target.slice_cycles))
        if progress.outcome not in (Outcome.SLICE, Outcome.HOST):
            return progress


def step_to_the_end(target: Target, until: int) -> tuple[int, Outcome, list[int]]:
    """Step until the core exits; (steps, final outcome, pcs it stopped at)."""
    steps, pcs = 0, []
    while True:
        target.start_step()
        progress = run_until_stop(target, until)
        if progress.outcome != Outcome.STOPPED:
            return steps, progress.outcome, pcs
        steps += 1
        pcs.append(target.pc)


def test_stepping_one_core_through_its_program_changes_no_cycle(one_core_elf: Path):
    reference = single(one_core_elf)
    result = reference.run()
    soc = single(one_core_elf)
    target = SingleCoreTarget(soc)
    steps, outcome, _ = step_to_the_end(target, 10**9)
    assert outcome == Outcome.EXITED and target.exit_code == 7
    assert soc.counters() == result.counters
    # no interrupts in this program: each step is exactly one instruction, the last the exit store
    assert steps + 1 == result.instructions
    assert soc.drain_output() == result.output


def test_stepping_a_tile_runs_the_chip_and_changes_no_cycle(mesh_elf: Path):
    reference = chip_with(mesh_elf)
    reference.run()
    chip = chip_with(mesh_elf)
    target = ChipTarget(chip, (1, 0))
    steps, outcome, _ = step_to_the_end(target, 10**9)
    assert outcome == Outcome.EXITED
    assert not (chip.cores.op_rows(target.t) == OP_BREAK).any()  # no mark left behind
    chip.run()  # the other tiles go on
    assert chip_facts(chip) == chip_facts(reference)
    # no interrupts in this program: each step is exactly one instruction, the last the exit store
    assert steps + 1 == chip.counters((1, 0))["instructions"]


def test_stepping_through_interrupts_and_sleep_changes_no_cycle(traffic_elf: Path):
    # the traffic program receives in its interrupt handler and sleeps: the steps enter the vector
    reference = chip_with(traffic_elf)
    reference.run(max_cycles=20_000_000)
    chip = chip_with(traffic_elf)
    target = ChipTarget(chip, (1, 1))
    _, outcome, pcs = step_to_the_end(target, 20_000_000)
    assert outcome == Outcome.EXITED
    vector = int(chip.cores.st[target.t, S_IRQ_VECTOR])
    assert pcs.count(vector) >= 2  # interrupt entries stopped at the vector
    assert chip.counters((1, 1))["sleep_cycle"] > 0
    chip.run(max_cycles=20_000_000)
    assert chip_facts(chip) == chip_facts(reference)


@pytest.mark.parametrize("where", ["single", "tile"])
def test_a_step_of_a_jump_to_itself_comes_back(self_loop_elf: Path, where: str):
    if where == "single":
        target = SingleCoreTarget(single(self_loop_elf))
    else:
        target = ChipTarget(chip_with(self_loop_elf), (1, 0))
    previous = -1
    for _ in range(100):
        target.start_step()
        cycle = target.cycle
        progress = run_until_stop(target)
        assert progress.outcome == Outcome.STOPPED and target.cycle > cycle
        if target.pc == previous:
            break
        previous = target.pc
    else:
        pytest.fail("the steps never reached the loop")
    word = target.word(target.pc)
    assert word is not None and word & 0x7F == 0x6F  # jal x0, 0: j .


def test_a_mark_stops_the_tile_before_the_instruction(mesh_elf: Path):
    chip = chip_with(mesh_elf)
    target = ChipTarget(chip, (1, 0))
    program = chip.programs[target.t]
    addr = program.address_of("next_value")
    points = Points()
    points.insert(Kind.SOFTWARE, addr, 4)
    target.apply_marks(points.marks(target.code_words(), target.code_base))
    assert target.is_marked(addr)
    progress = run_until_stop(target)
    assert progress.outcome == Outcome.STOPPED and target.pc == addr
    assert chip.counters((1, 0))["instructions"] > 0


def test_memory_and_registers_through_the_target(one_core_elf: Path):
    soc = single(one_core_elf)
    target = SingleCoreTarget(soc)
    program = soc.program
    assert program is not None
    total = program.address_of("total")
    assert target.read_memory(total, 4) == (5).to_bytes(4, "little")
    target.write_memory(total, (9).to_bytes(4, "little"))
    assert soc.state.word(total) == 9
    with pytest.raises(MemoryRefused):
        target.write_memory(TIMER0, b"\0\0\0\0")
    # a device register reads as a load at the current cycle would: TIMER0 = cycle - 1
    assert int.from_bytes(target.read_memory(TIMER0, 4), "little") == soc.cycle - 1
    assert target.read_memory(IRQ_VECTOR - 4, 4) == b""  # nothing there
    # SRAM runs up to its end, then reads stop
    end = soc.state.base + soc.state.size
    assert len(target.read_memory(end - 2, 8)) == 2
    target.set_register(5, 0xFFFFFFFF)
    target.set_register(0, 1234)
    assert target.registers()[5] == 0xFFFFFFFF and target.registers()[0] == 0
    assert soc.regs[5] == -1


def test_network_interface_registers_read_without_side_effects(mesh_elf: Path):
    chip = chip_with(mesh_elf)
    target = ChipTarget(chip, (1, 0))
    before = chip.counters((1, 0))
    assert int.from_bytes(target.read_memory(NI_BASE + NI_TILE, 4), "little") == 0x10
    assert int.from_bytes(target.read_memory(NI_BASE + NI_MESH, 4), "little") == 2 | (2 << 8)
    assert chip.counters((1, 0)) == before


def test_watch_hits_decode_the_access_from_the_registers():
    regs = np.zeros(33, dtype=np.int32)
    regs[10] = 0x40000100
    sw = (0x10 << 25) | (5 << 20) | (10 << 15) | (2 << 12) | (0x0 << 7) | 0x23  # sw x5, 0x200(x10)
    lw = (0x8 << 20) | (10 << 15) | (2 << 12) | (6 << 7) | 0x03  # lw x6, 8(x10)
    access = memory_access(sw, regs)
    assert access is not None and access.addr == 0x40000300 and access.size == 4 and access.store
    points = Points()
    points.insert(Kind.WRITE, 0x40000302, 1)
    assert points.watch_hit(sw, regs) == (Kind.WRITE, 0x40000302)
    assert points.watch_hit(lw, regs) is None
    points.insert(Kind.READ, 0x40000108, 4)
    assert points.watch_hit(lw, regs) == (Kind.READ, 0x40000108)


def test_failure_signals(one_core_elf: Path):
    soc = single(one_core_elf)
    target = SingleCoreTarget(soc)
    soc.state.st[0, S_MAX_CYCLES] = 20  # a budget the program cannot make
    progress = run_until_stop(target)
    assert progress.outcome == Outcome.FAILED
    assert target.failure_signal(progress.status) == signal.SIGXCPU
