"""The kernel's tick, releases and scheduling on one tile, in both builds.

Expectations are derived by hand from the timer rules of docs/platform.md: with prescaler p and
CTC + 1 = N, TIMER1 counts on pulses in the cycles y with (y - 1) a multiple of p; the kernel
writes TIMER1 so that it holds floor((x - 2) / p) mod N in every cycle x, so the compare flag
toggles into view in cycle k * p * N + 2 = k * L + 2: tick k.
"""

import itertools

import pytest
from kernel_harness import BUILDS, CORE, build, run

from robosoc.host.images import FIRST_TASK_ID, read_job_log, read_stats
from robosoc.toolchain import CompileError

#: tick length -> (prescaler, CTC + 1) as os_config.h must choose them: the smallest prescaler of
#: 16, 64, ... that divides L with a quotient of at most 65536
TICKS = {
    4096: (16, 256),
    50_000: (16, 3125),
    262_144: (16, 16384),
    2_097_152: (64, 32768),
    3_000_000: (64, 46875),
}


def spec(*tasks: tuple[int, int, int, int]) -> str:
    return "{" + ",".join("{" + ",".join(map(str, t)) + "}" for t in tasks) + "}"


def first_tick(start_cycle: int, tick: int) -> int:
    """The first tick rising after the kernel aligned TIMER1 (just before start_cycle)."""
    return (start_cycle - 2) // tick + 1


@pytest.mark.parametrize("mul", BUILDS)
@pytest.mark.parametrize("tick", list(TICKS))
def test_releases_fall_on_the_tick_grid(mul, tick):
    defines = {"TASK_SPEC": spec((2, 1, 2, 10), (3, 1, 3, 10)), "STOP_JOBS": 5, "SAMPLE_TIMER1": None}
    if tick != 262_144:
        defines["OS_TICK_CYCLES"] = tick  # 262144 is the default
    chip, result = run({CORE: build("periodic.c", mul, **defines)})
    assert result.exit_codes[CORE] == 0
    stats = read_stats(chip, CORE)
    assert stats.tick_cycles == tick
    j1 = first_tick(stats.start_cycle, tick)
    assert stats.first_tick == j1
    log = read_job_log(chip, CORE).records
    for task, period in ((FIRST_TASK_ID, 2), (FIRST_TASK_ID + 1, 3)):
        releases = [r.release for r in log if r.task == task]
        assert len(releases) >= 3
        assert releases == [(j1 + k * period) * tick + 2 for k in range(len(releases))]
        jobs = [r for r in log if r.task == task]
        assert [r.job for r in jobs] == list(range(1, len(jobs) + 1))
        assert all(r.deadline == r.release + period * tick for r in jobs)
        assert all(r.met and r.release < r.start < r.completion for r in jobs)
    # TIMER1 read back to back with TIMER0 by the jobs of task 0 (TIMER1 of cycle TIMER0 - 3)
    p, n = TICKS[tick]
    words = chip.cores.read(chip.programs[1].address_of("timer_samples"), 8 * 5, tile=1)
    samples = [int.from_bytes(words[4 * i : 4 * i + 4], "little") for i in range(10)]
    for t1, t0 in zip(samples[0::2], samples[1::2], strict=True):
        x = t0 - 3
        assert t1 == ((x - 2) // p) % n


@pytest.mark.parametrize("mul", BUILDS)
def test_best_effort_spinner_is_preempted_by_every_release(mul):
    tick = 32768
    elf = build("periodic.c", mul, TASK_SPEC=spec((1, 1, 1, 500)), STOP_JOBS=6, SPINNER=None, OS_TICK_CYCLES=tick)
    chip, result = run({CORE: elf})
    assert result.exit_codes[CORE] == 0
    log = read_job_log(chip, CORE).records
    assert len(log) == 6
    for r in log:
        # the spinner never blocks: the job runs because the tick preempts it, within the
        # kernel's entry, tick and dispatch (a few hundred cycles, far below a tick)
        assert r.start - r.release < 2000
        assert r.met
    spinner = FIRST_TASK_ID + 1
    per_task = chip.task_counters(CORE)
    assert per_task[spinner]["cycles"] > 5 * tick  # it had the core between jobs
    assert 1 not in per_task, "the idle task never ran"
    assert int.from_bytes(chip.cores.read(chip.programs[1].address_of("spinner_count"), 4, tile=1), "little") > 0


@pytest.mark.parametrize("mul", BUILDS)
def test_edf_preempts_a_long_job_for_an_earlier_deadline(mul):
    tick = 32768
    # task 2: a job of 2.5 ticks every 8 ticks (deadline 8); task 3: 1 tick period, deadline 1
    long_work = (5 * tick // 2) // 4
    elf = build(
        "periodic.c", mul, TASK_SPEC=spec((1, 1, 1, 200), (8, 8, 8, long_work)), STOP_JOBS=12, OS_TICK_CYCLES=tick
    )
    chip, _ = run({CORE: elf})
    log = read_job_log(chip, CORE).records
    short = [r for r in log if r.task == FIRST_TASK_ID]
    long = [r for r in log if r.task == FIRST_TASK_ID + 1]
    assert long and all(r.met for r in log)
    a = long[0]
    inside = [r for r in short if a.start < r.release < a.completion]
    assert len(inside) >= 2, "short jobs released while the long one runs"
    for r in inside:
        assert r.start - r.release < 2000, "the earlier deadline preempts at once"
        assert a.start < r.start < r.completion < a.completion
    # the long job was off the core while the short ones ran
    assert a.completion - a.start >= a.exec_cycles + sum(r.exec_cycles for r in inside)
    assert 4 * long_work <= a.exec_cycles


# Three tasks released together (period, capacity, deadline, work): EDF orders them by deadline,
# RM by period.  A (6, 1, 2), B (4, 1, 4), C (5, 1, 3): EDF A, C, B; RM B, C, A.
ORDER_SPEC = spec((6, 1, 2, 2000), (4, 1, 4, 2000), (5, 1, 3, 2000))


@pytest.mark.parametrize("mul", BUILDS)
@pytest.mark.parametrize(("policy", "order"), [("OS_SCHED_EDF", "ACB"), ("OS_SCHED_RM", "BCA")])
def test_edf_and_rm_order(mul, policy, order):
    tick = 32768
    elf = build("periodic.c", mul, TASK_SPEC=ORDER_SPEC, STOP_JOBS=3, OS_TICK_CYCLES=tick, OS_SCHED_POLICY=policy)
    chip, _ = run({CORE: elf})
    log = read_job_log(chip, CORE).records
    stats = read_stats(chip, CORE)
    j1 = first_tick(stats.start_cycle, tick)
    first = [r for r in log if r.release == j1 * tick + 2]
    assert len(first) == 3
    by_start = sorted(first, key=lambda r: r.start)
    assert "".join("ABC"[r.task - FIRST_TASK_ID] for r in by_start) == order
    # one after the other, none preempted: each starts after the previous completed
    for before, after in itertools.pairwise(by_start):
        assert before.completion < after.start


@pytest.mark.parametrize("mul", BUILDS)
def test_deadline_misses_are_counted_and_logged(mul):
    tick = 32768
    work = (5 * tick // 4) // 4  # 1.25 ticks
    # task 2: deadline 1 tick, always missed; task 3: the same work after it (EDF), done within
    # 2.5 ticks and the overheads: its deadline of 3 ticks is met
    elf = build("periodic.c", mul, TASK_SPEC=spec((4, 1, 1, work), (4, 3, 3, work)), STOP_JOBS=4, OS_TICK_CYCLES=tick)
    chip, result = run({CORE: elf})
    assert result.exit_codes[CORE] == 0
    log = read_job_log(chip, CORE).records
    stats = read_stats(chip, CORE)
    missed = [r for r in log if r.task == FIRST_TASK_ID]
    met = [r for r in log if r.task == FIRST_TASK_ID + 1]
    assert len(missed) == 4 and len(met) >= 3
    assert not any(r.met for r in missed) and all(r.met for r in met)
    assert all(r.completion > r.deadline for r in missed)
    assert stats.misses(FIRST_TASK_ID) == 4 and stats.misses(FIRST_TASK_ID + 1) == 0
    assert stats.jobs(FIRST_TASK_ID) == 4


@pytest.mark.parametrize("mul", BUILDS)
def test_capacity_is_enforced_at_ticks(mul):
    tick = 32768
    work = (5 * tick // 2) // 4  # 2.5 ticks of work, capacity 1 tick per period of 4
    elf = build("periodic.c", mul, TASK_SPEC=spec((4, 1, 4, work)), STOP_JOBS=2, OS_TICK_CYCLES=tick)
    chip, _ = run({CORE: elf})
    log = read_job_log(chip, CORE).records
    stats = read_stats(chip, CORE)
    j1 = first_tick(stats.start_cycle, tick)
    a = log[0]
    # At the tick j1 + 1 the job has used less than one tick (it started after the release);
    # at j1 + 2 it has used more: it waits for its next period at j1 + 4 and ends in it, so it
    # misses its deadline (the tick of j1 + 4), and job 2, released then, starts after it.
    assert a.release == j1 * tick + 2 and a.depleted and not a.met
    assert (j1 + 4) * tick + 2 < a.completion < (j1 + 5) * tick
    b = log[1]
    assert b.release == (j1 + 4) * tick + 2 and b.start > a.completion and b.depleted
    assert stats.misses(FIRST_TASK_ID) >= 1


@pytest.mark.parametrize(
    ("defines", "words"),
    [
        ({"OS_TICK_CYCLES": 1000}, "below 4096"),
        ({"OS_TICK_CYCLES": 40008}, "multiple of 16"),
        ({"OS_TICK_CYCLES": 1048592}, "prescaler x (CTC + 1)"),
        ({"OS_SCHED_POLICY": "LLF"}, "OS_SCHED_EDF or OS_SCHED_RM"),
        ({"OS_MAX_TASKS": 15}, "OS_MAX_TASKS must be 1..14"),
    ],
)
def test_invalid_configuration_fails_the_build_naming_the_setting(defines, words):
    with pytest.raises(CompileError, match="OS_") as info:
        build("periodic.c", True, **defines)
    assert words in str(info.value)
