"""Kernel overhead per build, measured on the chip (docs/firmware-kernel.md, "Overhead").

    PYTHONPATH=src python tests/firmware/kernel/measure_overhead.py

Runs programs/overhead.c on a 2x2 mesh (tile A (1,0), tile B (0,1)) and a load scenario on one
tile, and prints the table of docs/firmware-kernel.md.  All figures are cycles of the simulated
chip (TIMER0, per-task counters), the same on every host.
"""

from __future__ import annotations

import statistics

from kernel_harness import build, packet_visible, run  # the script's folder is on sys.path

from robosoc.config.chip import ChipConfig
from robosoc.host.images import FIRST_TASK_ID, IDLE_TASK_ID, KERNEL_TASK_ID, message_packets, read_job_log, read_stats

A, B = (1, 0), (0, 1)
TICK = 65536
LOAD_TICK = 262_144


def _words(chip, xy, n=128):
    t = chip.config.tile_index(xy)
    raw = chip.cores.read(chip.programs[t].address_of("results"), 4 * n, tile=t)
    return [int.from_bytes(raw[4 * i : 4 * i + 4], "little") for i in range(n)]


def measure(mul: bool) -> dict[str, float]:
    """The overhead figures of one build (cycles; shares in percent)."""
    config = ChipConfig(width=2, height=2, powered_off=((1, 1),))
    elf = build("overhead.c", mul, OS_TICK_CYCLES=TICK, OS_MSG_MAX_BYTES=1024)
    chip, _ = run({A: elf, B: elf}, config=config)
    a, b = _words(chip, A), _words(chip, B)
    out: dict[str, float] = {}
    out["voluntary switch (semaphore handover)"] = statistics.median(a[2 * k + 1] - a[2 * k] for k in range(8))
    jobs = [r for r in read_job_log(chip, A).records if r.task == FIRST_TASK_ID]
    out["tick to job start, preempting (interrupt path)"] = statistics.median(r.start - r.release for r in jobs)
    for s, size in enumerate((16, 116, 1000)):
        sends = [a[16 + 2 * (4 * s + k) + 1] - a[16 + 2 * (4 * s + k)] for k in range(4)]
        out[f"os_send {size} B ({-(-size // 116)} packet(s))"] = statistics.median(sends)
        lat = [b[64 + 3 * (4 * s + k) + 2] - b[64 + 3 * (4 * s + k) + 1] for k in range(4)]
        assert all(b[64 + 3 * (4 * s + k)] == size for k in range(4))
        out[f"send start to os_recv return, {size} B, 1 hop, receiver asleep"] = statistics.median(lat)
    tail = b[64 + 36 : 64 + 42]
    assert tail[0] == 1 and tail[3] == 1
    out["os_probe"] = tail[1]
    out["os_recv of a waiting 16 B message"] = tail[2]

    # event release: a packet from the I/O tile wakes the sleeping core and releases a job
    sends = [300_000 + 100_000 * k for k in range(4)]
    payload = message_packets(b"\0\1\2\3", port=3, src_tile=0)[0]
    elf = build("echo.c", mul, OS_TICK_CYCLES=TICK, EVENT=None, EXPECT=len(sends))
    chip, _ = run({(1, 0): elf}, injections=[((1, 0), payload, x) for x in sends])
    jobs = read_job_log(chip, (1, 0)).records
    visible = [packet_visible(x, hops=1, flits=len(payload) + 2) for x in sends]
    out["packet visible to release stamp (event task, core asleep)"] = statistics.median(
        r.release - v for r, v in zip(jobs, visible, strict=True)
    )
    out["release stamp to event job start"] = statistics.median(r.start - r.release for r in jobs)

    # load: one periodic job of 10 % of a tick every tick, default tick
    work = LOAD_TICK // 10 // 4
    elf = build("periodic.c", mul, TASK_SPEC="{{1,1,1,%d}}" % work, STOP_JOBS=20)  # noqa: UP031
    chip, result = run({(1, 0): elf})
    per = chip.task_counters((1, 0))
    stats = read_stats(chip, (1, 0))
    span = result.cycles - stats.start_cycle
    boot = stats.start_cycle
    out["load: kernel share, % (tick + 1 job per tick)"] = 100 * (per[KERNEL_TASK_ID]["cycles"] - boot) / span
    out["load: job share, %"] = 100 * per[FIRST_TASK_ID]["cycles"] / span
    out["load: idle share, % (asleep)"] = 100 * per[IDLE_TASK_ID]["cycles"] / span
    out["load: kernel cycles per tick (tick + switch in + job end + switch out)"] = (
        per[KERNEL_TASK_ID]["cycles"] - boot
    ) / stats.ticks
    return out


def main() -> None:
    rows = {True: measure(True), False: measure(False)}
    print("| figure | mul | no mul |")
    print("|---|---|---|")
    for name in rows[True]:
        m, n = rows[True][name], rows[False][name]
        fmt = "{:.1f}" if "%" in name else "{:.0f}"
        print(f"| {name} | {fmt.format(m)} | {fmt.format(n)} |")


if __name__ == "__main__":
    main()
