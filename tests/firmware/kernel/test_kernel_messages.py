"""Messages between the I/O tile and a kernel tile: blocking receive, sleep, event-triggered jobs.

Hand-derived timing: a packet of L flits injected by the I/O tile at cycle X over h hops waits in
the receive memory from device cycle v = X + (h + 1)(R + 1) + L (kernel_harness.packet_visible).
A core sleeping with interrupts enabled enters the interrupt at the boundary b = v + 5 (first
vector instruction in b + 2 and b + 3, docs/platform.md); the kernel's entry (port_asm.S) then
executes addi, sw, lui, lw, sw, sw and 26 more sw (b + 4 .. b + 95) and lui in b + 96, and its
TIMER0 load starts in b + 97, reading b + 96: the arrival stamp of the message is v + 101.
"""

import struct

import pytest
from kernel_harness import BUILDS, CORE, build, packet_visible, run

from robosoc.host.images import (
    FIRST_TASK_ID,
    IDLE_TASK_ID,
    c_header_constants,
    message_packets,
    read_job_log,
    read_stats,
    reassemble,
)

TICK = 32768
IO = 0x00
ENTRY_TO_STAMP = 5 + 96  # from the packet becoming visible to the kernel's TIMER0 stamp, asleep


def answers(result):
    """(arrival, had_it, probe, data) of each answer of echo.c, in order."""
    out = []
    for m in reassemble(result.io_received):
        assert (m.src_tile, m.dest, m.port) == (0x10, IO, 5)
        arrival, had_it, probe = struct.unpack_from("<IIi", m.data)
        out.append((arrival, had_it, probe, m.data[12:][::-1]))
    return out


def test_python_header_constants_match_os_h():
    c = c_header_constants()
    assert c["OS_MSG_HEADER_FLITS"] == 6
    assert c["OS_KERNEL_TASK_ID"] == 0 and c["OS_IDLE_TASK_ID"] == IDLE_TASK_ID
    assert c["OS_FIRST_TASK_ID"] == FIRST_TASK_ID
    assert (c["OS_JOB_MET"], c["OS_JOB_EVENT"], c["OS_JOB_DEPLETED"]) == (1, 2, 4)
    assert c["OS_JOBLOG_MAGIC"] == 0x4A4F4253 and c["OS_STATS_MAGIC"] == 0x4154534B


@pytest.mark.parametrize("mul", BUILDS)
def test_blocking_receive_sleeps_until_the_packet(mul):
    x = 400_000
    data = b"hello, kernel"
    payload = message_packets(data, port=3, src_tile=IO, src_port=9, seq=1)[0]
    elf = build("echo.c", mul, OS_TICK_CYCLES=TICK)
    chip, result = run({CORE: elf}, injections=[(CORE, payload, x)])
    assert result.exit_codes[CORE] == 0
    [(arrival, had_it, probe, echoed)] = answers(result)
    assert echoed == data
    assert probe == c_header_constants()["OS_E_EMPTY"], "nothing waited before the packet"
    v = packet_visible(x, hops=1, flits=len(payload) + 2)
    assert arrival == v + ENTRY_TO_STAMP
    assert arrival < had_it < arrival + 3000
    # no busy wait: from os_start to the packet the core slept except for the ticks
    stats = read_stats(chip, CORE)
    tile = chip.counters(CORE)
    ticks_before = (v - stats.start_cycle) // TICK + 1
    assert tile["sleep_cycle"] > (v - stats.start_cycle) - ticks_before * 1500
    idle = chip.task_counters(CORE)[IDLE_TASK_ID]
    assert idle["sleep_cycle"] == tile["sleep_cycle"], "only the idle task sleeps"
    # per wake-up the idle task runs the entry up to the TASK_ID store (nop twice, addi, sw, lui,
    # lw, sw), the exit after it (lw, addi, lui, addi, sw, jalr) and its loop (sw SLEEP, j)
    assert idle["instructions"] <= 15 * idle["interrupts"] + 15, "the idle task only sleeps"


@pytest.mark.parametrize("mul", BUILDS)
def test_event_triggered_jobs_are_released_by_arrivals(mul):
    # message k: first byte = busy-loop units (4000 cycles each), deadline 1 tick (32768 cycles)
    sends = [(300_000, 1), (500_000, 5), (510_000, 1), (700_000, 12)]
    injections = []
    for k, (cycle, units) in enumerate(sends):
        payload = message_packets(bytes([units, k, 0xA5]), port=3, src_tile=IO, seq=k)[0]
        injections.append((CORE, payload, cycle))
    elf = build("echo.c", mul, OS_TICK_CYCLES=TICK, EVENT=None, EXPECT=len(sends), DEADLINE=1)
    chip, result = run({CORE: elf}, injections=injections)
    assert result.exit_codes[CORE] == 0
    got = answers(result)
    assert [d for *_, d in got] == [bytes([u, k, 0xA5]) for k, (_, u) in enumerate(sends)]
    log = read_job_log(chip, CORE).records
    assert [r.job for r in log] == [1, 2, 3, 4] and all(r.event and r.task == FIRST_TASK_ID for r in log)
    for k, ((cycle, _), r, (arrival, had_it, _, _)) in enumerate(zip(sends, log, got, strict=True)):
        v = packet_visible(cycle, hops=1, flits=6 + 2)  # header, 3 data bytes in 2 flits
        assert r.release == arrival
        assert r.deadline == r.release + TICK
        assert r.release < r.start <= had_it < r.completion
        if k != 2:  # the core slept when these arrived
            assert arrival == v + ENTRY_TO_STAMP
        else:  # it was in job 2's busy loop: the entry is at the first boundary >= v + 5
            assert v + ENTRY_TO_STAMP <= arrival <= v + ENTRY_TO_STAMP + 2
    # message 3 arrived while job 2 ran: released at its arrival, started after job 2
    assert log[2].release < log[1].completion < log[2].start
    # job 4 spins 48000 cycles: more than its deadline of one tick
    assert [r.met for r in log] == [True, True, True, False]
    assert read_stats(chip, CORE).misses(FIRST_TASK_ID) == 1


@pytest.mark.parametrize("mul", BUILDS)
def test_malformed_packets_from_the_io_tile_are_counted_and_dropped(mul):
    good1 = b"first good message"
    good2 = bytes(range(200))  # two packets
    too_long = bytes(300)  # more than OS_MSG_MAX_BYTES (256): dropped whole, not malformed
    split = message_packets(bytes(150), port=3, src_tile=IO, seq=7)
    bad = [
        [0x0009],  # 3 flits: no room for the header
        [(IO << 8) | 1, (200 << 8) | 0, 2, 1, 0x1111],  # port 200 of 8
        [(IO << 8) | 1, (3 << 8) | 3, 4, 2, 0x2222, 0x3333],  # fragment 3 with no fragment 0
        [(IO << 8) | 1, (3 << 8) | 0, 2, 3, 0x4444, 0x5555],  # says 2 bytes, carries 4
        [(IO << 8) | 1, (3 << 8) | 0, 10, 3, 0x4444],  # 2 of 10 bytes, and the next message starts
        split[0],  # a message whose second packet ...
        [split[1][0], split[1][1], split[1][2], 8, *split[1][4:]],  # ... claims another sequence
    ]
    payloads = [
        *bad[:5],
        *message_packets(good1, port=3, src_tile=IO, seq=4),
        *message_packets(too_long, port=3, src_tile=IO, seq=5),
        *bad[5:],
        *message_packets(good2, port=3, src_tile=IO, seq=9),
    ]
    injections = [(CORE, p, 300_000 + 1000 * k) for k, p in enumerate(payloads)]
    elf = build("echo.c", mul, OS_TICK_CYCLES=TICK, EXPECT=2)
    chip, result = run({CORE: elf}, injections=injections)
    assert result.exit_codes[CORE] == 0
    assert [d for *_, d in answers(result)] == [good1, good2]
    stats = read_stats(chip, CORE)
    assert stats.pkt_received == len(payloads)
    # the four bad ones, the message cut short (once) and the out-of-turn second packet
    assert stats.pkt_malformed == 6
    assert stats.msg_dropped == 1  # the 300-byte message
    assert stats.msg_received == 2
