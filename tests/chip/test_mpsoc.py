"""The MPSoC: network-interface timing, DMA stalls, receive interrupt, sleep, errors, I/O tile.

Cycle numbers are derived by hand from platform.md and docs/noc.md: a SEND store starting in
cycle s stalls the core for the DMA copy (one cycle per flit) after its own three cycles, the
first flit enters the router in s + 3 + L, the last flit is written into the receive memory
5(h + 1) + L - 1 cycles later (Hermes RTL: 5 cycles per router, platform.md §4) and the packet
is visible (NI_STATUS, IRQ_CAUSE bit 1) from the cycle after that.
"""

from pathlib import Path

import pytest

import rv32_asm as A
from core_harness import exit_with
from robosoc.chip.mpsoc import ChipError, MPSoC
from robosoc.config.chip import ChipConfig
from robosoc.program.elf import Program

SRAM = 0x40000000
NI, IRQ, TIMER0 = 0xE1040000, 0xF0000000, 0xE1024000
T0, T1, T2, T3, T4 = 5, 6, 7, 28, 29
A0, A1, A2, A3 = 10, 11, 12, 13
ROUTER_CYCLES = 5  # an uncontended header spends 5 cycles in each Hermes router
PACKET = SRAM + 0x400
RXBUF = SRAM + 0x500


def program(words: list[int], data: dict[int, bytes] | None = None) -> Program:
    segments = [(SRAM, A.words_to_bytes(words))]
    segments += list((data or {}).items())
    return Program(path=Path("<asm>"), entry=SRAM, segments=segments)


def flits(*values: int) -> bytes:
    return b"".join((v & 0xFFFF).to_bytes(2, "little") for v in values)


def sender(dest: int, payload: int = 0xBEEF, size: int = 3) -> Program:
    words = [
        *A.li(T0, NI),  # cycles 3, 4
        *A.li(T1, PACKET),  # 5, 6
        *A.li(T3, TIMER0),  # 7, 8
        A.store("sw", T1, T0, 0x04),  # SEND_ADDR: 9..11
        A.i("addi", T2, 0, size),  # 12
        A.store("sw", T2, T0, 0x08),  # SEND_SIZE: 13..15
        A.i("addi", T2, 0, 1),  # 16
        A.store("sw", T2, T0, 0x0C),  # SEND at 17: store 17..19, DMA 20..22
        A.load("lw", A1, T3, 0),  # starts in 23: reads 22
        *exit_with(A1),
    ]
    return program(words, {PACKET: flits(dest, 1, payload)})


SEND_START = 17
FIRST_FLIT = SEND_START + 3 + 3  # cycle the first flit enters the source router: 23


def last_flit(hops: int, length: int = 3) -> int:
    return FIRST_FLIT + (hops + 1) * ROUTER_CYCLES + length - 1


def poller() -> Program:
    words = [
        *A.li(T0, NI),  # 3, 4
        *A.li(T1, RXBUF),  # 5, 6
        *A.li(T3, TIMER0),  # 7, 8
        A.store("sw", T1, T0, 0x10),  # RECV_ADDR: 9..11
        # poll: lw (3) addi (1) andi (1) beq (3 taken / 1 not): 8 cycles a round, first lw in 12
        A.load("lw", T2, T0, 0x00),
        A.i("addi", A2, A2, 1),
        A.i("andi", T2, T2, 2),
        A.branch("beq", T2, 0, -12),
        A.i("addi", T2, 0, 2),
        A.store("sw", T2, T0, 0x0C),  # RECV: store, then DMA of 3 flits
        A.load("lw", A1, T3, 0),  # TIMER0 right after the DMA
        A.load("lhu", A0, T1, 4),  # the payload flit
        *exit_with(A0),
    ]
    return program(words)


def test_ping_timing_by_hand():
    chip = MPSoC(ChipConfig())  # 2x2, I/O tile (0,0)
    chip.load((1, 0), sender(dest=0x01))  # to (0,1): x 1 -> 0 then y 0 -> 1: 2 hops
    chip.load((0, 1), poller())
    chip.load((1, 1), program(exit_with(0)))
    result = chip.run(max_cycles=100_000)
    assert result.exit_codes[(0, 1)] == 0xBEEF
    # sender: TIMER0 read right after the SEND's DMA: the load starts in 23, reads 22
    assert result.exit_codes[(1, 0)] == SEND_START + 3 + 3 - 1
    d = last_flit(hops=2)  # 23 + 3*5 + 2 = 40
    assert d == 40
    # the poll load starting in c sees the packet when d + 1 <= c - 1: polls start in 12 + 8k
    k = next(k for k in range(100) if 12 + 8 * k >= d + 2)
    poll = 12 + 8 * k  # 44 (k = 4: the load of 36 reads cycle 35, before the packet)
    assert (k, poll) == (4, 44)
    recv = poll + 3 + 1 + 1 + 1 + 1  # lw, addi, andi, beq not taken, addi -> the RECV store in 51
    regs = chip.regs((0, 1))
    assert int(regs[A2]) == k + 1, "number of polls"
    assert int(regs[A1]) == recv + 3 + 3 - 1, "TIMER0 after the RECV store and its 3-flit DMA"
    c = chip.counters((1, 0))
    assert c["dma_cycle"] == 3 and c["packets_sent"] == 1
    assert chip.counters((0, 1))["dma_cycle"] == 3 and chip.counters((0, 1))["packets_received"] == 1
    assert chip.noc_counters()["flit_hops"] == 3 * 2  # three flits, two router-to-router hops


def test_receive_interrupt_wakes_a_sleeping_core():
    handler = SRAM + 0x200
    words = [
        *A.li(T0, NI),  # 3, 4
        *A.li(T4, IRQ),  # 5, 6
        *A.li(T3, TIMER0),  # 7, 8
        *A.li(T1, handler),  # 9, 10
        A.store("sw", T1, T4, 0x00),  # IRQ_VECTOR 11..13
        A.i("addi", T2, 0, 2),  # 14
        A.store("sw", T2, T4, 0x20),  # IRQ_MASK = NI: 15..17
        A.i("addi", T2, 0, 1),  # 18
        A.store("sw", T2, T4, 0x30),  # IRQ_STATUS: 19..21
        A.store("sw", T2, T0, 0x24),  # SLEEP: 22..24, asleep from 25
        *[A.NOP] * 40,
        *exit_with(0),
    ]
    words += [A.NOP] * (0x200 // 4 - len(words))
    words += [A.i("addi", A0, A0, 1), A.load("lw", A1, T3, 0), *exit_with(A1)]
    chip = MPSoC(ChipConfig())
    chip.load((1, 0), sender(dest=0x01))
    chip.load((0, 1), program(words))
    result = chip.run(max_cycles=100_000)
    rise = last_flit(hops=2) + 1  # IRQ_CAUSE bit 1 is up from this device cycle
    assert rise == 41
    # platform.md §3: the request reaches the core in instruction cycle rise + 4 and is entered at
    # the first boundary >= rise + 5; the sleeping core wakes exactly there.  The first vector
    # instruction executes in b + 2 and b + 3, the TIMER0 load in b + 4 reads b + 3.
    b = rise + 5
    assert result.exit_codes[(0, 1)] == b + 4 - 1
    assert int(chip.regs((0, 1))[A0]) == 2, "first vector instruction executes twice"
    assert chip.counters((0, 1))["sleep_cycle"] == b - 25
    assert chip.counters((0, 1))["interrupts"] == 1


def test_timer_interrupt_wakes_a_sleeping_core_on_the_exact_cycle():
    handler = SRAM + 0x200
    ocr = 400
    words = [
        *A.li(T0, NI),
        *A.li(T4, IRQ),
        *A.li(T3, TIMER0),
        *A.li(T1, handler),
        A.store("sw", T1, T4, 0x00),
        *A.li(T2, ocr),
        A.store("sw", T2, T3, 0x430),  # TIMER1_OCR
        *A.li(T1, 0xE1020800),
        A.i("addi", T2, 0, 8),
        A.store("sw", T2, T1, 0x000),  # TIMERCAUSE_INV: line = TIMER1 >= OCR
        A.store("sw", T2, T1, 0x400),  # TIMERMASK
        A.i("addi", T2, 0, 1),
        A.store("sw", T2, T4, 0x20),  # IRQ_MASK = SoC line
        A.store("sw", T2, T4, 0x30),  # IRQ_STATUS
        A.store("sw", T2, T0, 0x24),  # SLEEP
        *[A.NOP] * 20,
        *exit_with(0),
    ]
    words += [A.NOP] * (0x200 // 4 - len(words))
    words += [A.NOP, A.load("lw", A1, T3, 0), *exit_with(A1)]
    chip = MPSoC(ChipConfig())
    chip.load((1, 0), program(words))
    result = chip.run(max_cycles=100_000)
    t = ocr + 2  # TIMER1 = device cycle - 2 with the reset prescaler: TIMER1 >= OCR from 402
    b = t + 5  # the entry boundary (platform.md §3): the core wakes in it
    assert result.exit_codes[(1, 0)] == b + 4 - 1  # the TIMER0 load in b + 4 reads b + 3
    assert chip.counters((1, 0))["sleep_cycle"] == b - sleep_start(words)


def sleep_start(words: list[int]) -> int:
    """The cycle after the SLEEP store of a straight-line program (1-cycle ALU ops, 3-cycle stores)."""
    cycle = 3
    for w in words:
        cycle += 3 if (w & 0x7F) in (0x03, 0x23) else 1
        if w == A.store("sw", T2, T0, 0x24):
            return cycle
    raise AssertionError("no SLEEP store")


def test_io_tile_injects_and_receives():
    # (0,1) waits for a packet from the outside, adds 1 to its payload and sends it to the I/O tile
    words = [
        *A.li(T0, NI),
        *A.li(T1, RXBUF),
        A.store("sw", T1, T0, 0x10),
        A.load("lw", T2, T0, 0x00),
        A.i("andi", T2, T2, 2),
        A.branch("beq", T2, 0, -8),
        A.i("addi", T2, 0, 2),
        A.store("sw", T2, T0, 0x0C),  # RECV
        A.load("lw", A0, T0, 0x28),  # IO_TILE address
        A.store("sh", A0, T1, 0),  # reuse the buffer as the reply: flit 0 = I/O tile
        A.load("lhu", A1, T1, 4),
        A.i("addi", A1, A1, 1),
        A.store("sh", A1, T1, 4),
        A.store("sw", T1, T0, 0x04),
        A.i("addi", T2, 0, 3),
        A.store("sw", T2, T0, 0x08),
        A.i("addi", T2, 0, 1),
        A.store("sw", T2, T0, 0x0C),  # SEND
        *[A.NOP] * 60,  # let the packet leave before exiting
        *exit_with(0),
    ]
    chip = MPSoC(ChipConfig())
    chip.load((0, 1), program(words))
    chip.inject((0, 1), [41], at_cycle=100)
    result = chip.run(max_cycles=100_000)
    ((cycle, packet),) = result.io_received
    assert packet == [0x00, 1, 42]
    assert 100 < cycle < result.cycles


def test_packet_to_a_powered_off_tile_is_an_error():
    chip = MPSoC(ChipConfig(powered_off=((1, 1),)))
    chip.load((1, 0), sender(dest=0x11))
    with pytest.raises(ChipError, match=r"tile \(1, 0\).*powered off.*tile \(1, 1\)"):
        chip.run(max_cycles=100_000)
    with pytest.raises(ValueError, match="powered off"):
        chip.load((1, 1), sender(dest=0x10))
    with pytest.raises(ValueError, match="I/O tile"):
        chip.load((0, 0), sender(dest=0x10))


def test_packet_to_its_own_tile_and_bad_commands_are_errors():
    chip = MPSoC(ChipConfig())
    chip.load((1, 0), sender(dest=0x10))
    with pytest.raises(ChipError, match="its own tile"):
        chip.run(max_cycles=100_000)
    chip = MPSoC(ChipConfig())
    chip.load((1, 0), program([*A.li(T0, NI), A.store("sb", 0, T0, 0x0C), *exit_with(0)]))
    with pytest.raises(ChipError, match="word loads and stores"):
        chip.run(max_cycles=100_000)
    chip = MPSoC(ChipConfig())
    chip.load((1, 0), program([*A.li(T0, NI), A.i("addi", T2, 0, 2), A.store("sw", T2, T0, 0x0C), *exit_with(0)]))
    with pytest.raises(ChipError, match="RECV with no packet"):
        chip.run(max_cycles=100_000)


def test_packet_shorter_than_3_flits_is_an_error_naming_tile_and_pc():
    """On the Hermes RTL a packet without payload keeps its connection open and swallows the next one."""
    chip = MPSoC(ChipConfig())
    chip.load((1, 0), sender(dest=0x01, size=2))
    send_pc = SRAM + 4 * 10  # the SEND store, after three li pairs, two stores and two addi
    text = r"tile \(1, 0\): the packet cannot be sent: packet shorter than 3 flits.*\(SEND_SIZE = 2\)"
    with pytest.raises(ChipError, match=rf"{text} at address 0x{PACKET:08x}, pc 0x{send_pc:08x}") as err:
        chip.run(max_cycles=100_000)
    assert err.value.tile == (1, 0)
    with pytest.raises(ValueError, match="at least 1 payload flit"):
        chip.inject((1, 1), [], at_cycle=0)


def test_sleeping_forever_is_reported():
    chip = MPSoC(ChipConfig())
    chip.load((1, 0), program([*A.li(T0, NI), A.store("sw", 0, T0, 0x24), *exit_with(0)]))
    with pytest.raises(ChipError, match=r"\(1, 0\) sleeps"):
        chip.run(max_cycles=1_000_000)


@pytest.mark.parametrize("pc", [SRAM + 2, SRAM + 0x40, SRAM - 4])
def test_a_running_tile_whose_pc_left_its_code_is_named_before_the_chip_runs(pc):
    from robosoc.chip.single import CoreError
    from robosoc.kernels.core_layout import S_PC

    chip = MPSoC(ChipConfig())
    for xy in ((1, 0), (0, 1)):
        chip.load(xy, program([A.i("addi", T0, 0, 1), *exit_with(0)]))
    t = chip.config.tile_index((0, 1))
    chip.cores.st[t, S_PC] = pc  # as a debugger's register write could leave it
    with pytest.raises(CoreError, match=rf"^tile \(0, 1\): pc 0x{pc:08x} .* is not an instruction of the loaded code"):
        chip.step(100)
    assert chip.cycle == 0  # nothing ran


def test_per_task_counters_add_up_to_the_tile_totals():
    words = [*A.li(T0, NI)]
    for task in (1, 2, 1):
        words += [A.i("addi", T2, 0, task), A.store("sw", T2, T0, 0x20), *[A.i("addi", A0, A0, 1)] * (10 * task)]
    words += [A.store("sw", 0, T0, 0x20), *exit_with(0)]
    chip = MPSoC(ChipConfig())
    chip.load((1, 0), program(words))
    chip.run(max_cycles=100_000)
    tasks = chip.task_counters((1, 0))
    total = chip.counters((1, 0))
    assert set(tasks) == {0, 1, 2}
    for key in ("instructions", "cycles", "memory", "add"):
        assert sum(t[key] for t in tasks.values()) == total[key], key
    # task 1 runs 10 addi, then the addi preparing the switch to 2, later 10 addi more (the final
    # switch stores x0); the store that switches is charged to the task it switches away from
    assert tasks[1]["add"] == 10 + 1 + 10
    assert tasks[2]["add"] == 20 + 1
