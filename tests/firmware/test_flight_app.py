"""The flight firmware (the shipped quadrotor project) end to end on the seed's chip
(fw.seed_chip(), MPSoC): 2 s of a recorded host flight's sensor messages injected from the I/O
tile at their sample cycles (1 s of calibration on the ground, then 1 s of flight after arming),
the PWM messages collected.

Checked in all four builds with event release: one PWM message per sample with its seq, PWM within
one count of HostController (float64, on the same quantised samples) on >= 99 % of samples, no
deadline miss, every job met, the cores asleep most of the time.  Then the periodic release,
foreign and malformed packets, and both tasks on one tile.
"""

import numpy as np
import pytest
from app_chip import ChipRun, read_app_stats, run_app
from app_data import Golden, SensorRecord, golden, record_flight

from robosoc.config.firmware import FirmwareConfig, Placement
from robosoc.host import images
from robosoc.host.firmware_image import FIRST_SAMPLE_CYCLE
from robosoc.host.packets import PWM, SENSOR_PORT

MATCH_SHARE = 0.99
WINDOW = (200, 400)
"""Samples 2.0 s .. 4.0 s of the recorded flight (it arms at 3 s), as a flight of their own."""
BUILDS = [
    pytest.param("float", True, id="float+mul"),
    pytest.param("float", False, id="float-no-mul"),
    pytest.param("fixed", True, id="fixed+mul"),
    pytest.param("fixed", False, id="fixed-no-mul"),
]


@pytest.fixture(scope="module")
def flight() -> tuple[SensorRecord, Golden]:
    record = record_flight(4.0).window(*WINDOW)
    assert record.armed.sum() == 100 and not record.armed[0]
    return record, golden(record)


def _match_share(run: ChipRun, gold: Golden) -> float:
    return float(np.mean(np.max(np.abs(run.pwm - gold.pwm), axis=1) <= 1))


@pytest.mark.parametrize(("arith", "mul"), BUILDS)
def test_event_release_flies_like_the_golden_model(flight: tuple[SensorRecord, Golden], arith: str, mul: bool) -> None:
    record, gold = flight
    fw = FirmwareConfig(arith=arith, multiplier=mul)
    run = run_app(fw, record)
    assert run.seq == list(range(record.steps)), "one PWM message per sample, in order"
    assert np.all(run.pwm[~record.armed] == 0)
    share = _match_share(run, gold)
    assert share >= MATCH_SHARE, share
    for name in ("estimator", "pid"):
        xy = run.tile_of(name)
        task = run.image.tasks[xy][name]
        stats = images.read_stats(run.chip, xy)
        assert stats.start_cycle < FIRST_SAMPLE_CYCLE
        assert stats.jobs(task) == record.steps and stats.misses(task) == 0
        assert stats.pkt_malformed == 0 and stats.msg_dropped == 0
        log = images.read_job_log(run.chip, xy)
        jobs = [r for r in log.records if r.task == task]
        assert len(jobs) == record.steps and all(r.met and r.event for r in jobs)
        app = read_app_stats(run.chip, xy)
        assert app.send_errors == 0 and app.est_foreign == 0 and app.pid_foreign == 0
        counters = run.chip.counters(xy)
        assert counters["sleep_cycle"] > 0.5 * counters["cycles"], "the core sleeps most of the time"
        responses = [r.response for r in jobs]
        print(f"{fw.label} {name}: response mean {np.mean(responses):.0f} max {max(responses)} cycles, "
              f"asleep {counters['sleep_cycle'] / counters['cycles']:.1%}")  # fmt: skip
    assert read_app_stats(run.chip, run.tile_of("estimator")).est_jobs == record.steps
    assert read_app_stats(run.chip, run.tile_of("pid")).pid_jobs == record.steps
    # the PWM message leaves within the sample period
    assert max(run.arrival[k] - (FIRST_SAMPLE_CYCLE + k * 2_500_000) for k in range(record.steps)) < 2_500_000


def test_periodic_release_takes_the_newest_sample(flight: tuple[SensorRecord, Golden]) -> None:
    record, _ = flight
    # robosoc's periodic release: 10 ticks of 262,144 cycles, slower than the 2,500,000-cycle samples
    fw = FirmwareConfig(release="periodic")
    run = run_app(fw, record)
    est = read_app_stats(run.chip, run.tile_of("estimator"))
    pid = read_app_stats(run.chip, run.tile_of("pid"))
    assert est.est_jobs + est.est_stale in (record.steps - 1, record.steps)  # the last may still wait
    assert est.est_stale > 0 and pid.pid_jobs == len(run.seq)
    assert run.seq == sorted(set(run.seq)), "PWM messages carry increasing sequence numbers"
    for xy in run.image.tiles:
        stats = images.read_stats(run.chip, xy)
        assert stats.misses(images.FIRST_TASK_ID) == 0
        jobs = [r for r in images.read_job_log(run.chip, xy).records if r.task == images.FIRST_TASK_ID]
        assert jobs and all(r.met and not r.event for r in jobs)
    assert est.est_empty + pid.pid_empty > 0, "a job that found nothing is counted"


def test_foreign_and_malformed_packets_are_counted_and_dropped(flight: tuple[SensorRecord, Golden]) -> None:
    record, _ = flight
    fw = FirmwareConfig()
    clean = run_app(fw, record)
    io = images.tile_address((0, 0))
    # a PWM packet on the sensor port (right port, wrong kind), a sensor packet cut short, and a
    # packet whose message header is inconsistent (length 0: the kernel's to drop)
    wrong_kind = images.message_packets(PWM.pack({"seq": 7}) + bytes(72), SENSOR_PORT, src_tile=io, seq=90)
    short = images.message_packets(record.packet(0)[:40], SENSOR_PORT, src_tile=io, seq=91)
    bad_header = [[io << 8, SENSOR_PORT << 8, 0, 92, 0x1234]]
    run = run_app(fw, record, extra={50: wrong_kind, 120: short, 150: bad_header})
    assert run.seq == clean.seq and np.array_equal(run.pwm, clean.pwm), "nothing changed"
    assert read_app_stats(run.chip, run.tile_of("estimator")).est_foreign == 2
    assert images.read_stats(run.chip, run.tile_of("estimator")).pkt_malformed == 1


def test_both_tasks_on_one_tile(flight: tuple[SensorRecord, Golden]) -> None:
    record, gold = flight
    fw = FirmwareConfig(placement=(Placement("estimator", (1, 0)),))
    run = run_app(fw, record)
    assert run.image.tasks == {(1, 0): {"estimator": 2, "pid": 3}}
    assert run.seq == list(range(record.steps))
    assert _match_share(run, gold) >= MATCH_SHARE
    stats = images.read_stats(run.chip, (1, 0))
    assert stats.jobs(2) == stats.jobs(3) == record.steps
    assert stats.misses(2) == stats.misses(3) == 0


def test_q16_multiply_through_muldi3_gives_the_same_commands_at_a_higher_cost(
    flight: tuple[SensorRecord, Golden],
) -> None:
    """fixed_mul64 = "muldi3" (the 64-bit product through compiler-rt, as HellfireOS): both routines
    compute the exact 64-bit product, so the fixed-no-mul build sends the same PWM commands, but
    through the general 64 x 64-bit __muldi3 (about 470 cycles against about 190 for the
    shift-and-add), so its estimator jobs take longer."""
    from robosoc.host.scenario_image import firmware_image

    record, _ = flight
    runs = {}
    for routine in ("shift-add", "muldi3"):
        fw = FirmwareConfig(arith="fixed", multiplier=False, fixed_mul64=routine)
        assert fw.muldi3 == (routine == "muldi3")
        runs[routine] = run_app(fw, record)
    soft, muldi3 = runs["shift-add"], runs["muldi3"]
    assert np.array_equal(soft.pwm, muldi3.pwm) and soft.seq == muldi3.seq
    xy = soft.tile_of("estimator")
    task = soft.image.tasks[xy]["estimator"]
    cycles = {
        name: sum(r.exec_cycles for r in images.read_job_log(run.chip, xy).records if r.task == task)
        for name, run in runs.items()
    }
    assert cycles["muldi3"] > 1.2 * cycles["shift-add"], cycles
    # with the multiplier the option changes nothing: MUL + MULH either way (the same ELF)
    with_mul = [firmware_image(FirmwareConfig(arith="fixed", fixed_mul64=r)).elf for r in ("shift-add", "muldi3")]
    assert with_mul[0] == with_mul[1]
