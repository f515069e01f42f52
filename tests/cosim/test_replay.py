"""The replay harness: a recorded flight's samples into the firmware on the chip, per-job records."""

import json
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from robosoc.cli import app
from robosoc.config.firmware import FirmwareConfig
from robosoc.control.flight import ROW_FIELDS, column
from robosoc.control.flight_log import CsvFlightLog, read_flight_log
from robosoc.cosim.replay import built_in_rows, replay, samples_from_rows
from robosoc.host import images

# 3.5 s of the default flight: 3 s calibrating on the ground, then take-off
SECONDS = 3.5


@pytest.fixture(scope="module")
def rows() -> np.ndarray:
    return built_in_rows(SECONDS, seed=2)


@pytest.fixture(scope="module")
def fixed_mul(rows: np.ndarray):
    return replay(rows, FirmwareConfig())


def test_every_sample_gets_its_pwm_command_as_the_golden_model_computes_it(rows, fixed_mul):
    result = fixed_mul
    assert [c.seq for c in result.commands] == list(range(len(rows)))
    golden = np.stack([column(rows, f"pwm{i}") for i in range(4)], axis=1)
    chip = np.array([c.pwm for c in result.commands])
    within_one = (np.abs(chip - golden) <= 1).all(axis=1)
    assert within_one.mean() >= 0.99
    assert (column(rows, "armed") > 0.5).sum() >= 40, "the replay covers flying samples too"
    # each command comes back after its sample went in, before the next one
    for c, s in zip(result.commands, result.samples, strict=True):
        assert s.cycle < c.cycle < s.cycle + 2_500_000


def test_one_job_per_sample_and_task_with_timing_and_energy(rows, fixed_mul):
    result = fixed_mul
    assert result.deadline_misses == 0
    for name in ("estimator", "pid"):
        jobs = result.jobs_of(name)
        assert len(jobs) == len(rows)
        for job, sample in zip(jobs, result.samples, strict=True):
            assert job.release_cycle >= sample.cycle
            assert job.release_cycle <= job.start_cycle < job.completion_cycle
            # the kernel's own dispatch-to-dispatch stamps start before the job's start stamp
            assert 0 < job.exec_cycles <= job.completion_cycle - job.release_cycle
            assert job.instructions > 0 and not job.spans_periods
            assert set(job.energy_pj) == {"task", "kernel", "idle", "noc"}
            assert min(job.energy_pj.values()) >= 0 and job.energy_pj["task"] > 0
    # the jobs' own energies add up to their tasks' energy over the whole replay
    for name in ("estimator", "pid"):
        xy = result.jobs_of(name)[0].tile
        task_id = images.FIRST_TASK_ID  # each task alone on its tile: the first created there
        summed = sum(j.energy_pj["task"] for j in result.jobs_of(name))
        assert summed == pytest.approx(result.task_energy_pj[(xy, task_id)], rel=1e-9)
    # the PID job is released by the estimator's message, which the estimator's job sends
    for est, pid in zip(result.jobs_of("estimator"), result.jobs_of("pid"), strict=True):
        assert est.start_cycle < pid.release_cycle < est.completion_cycle + 50_000


def test_a_flight_log_on_disk_replays_like_the_flight_itself(rows, tmp_path: Path):
    short = rows[:60]
    path = tmp_path / "flight.csv"
    with CsvFlightLog(path) as log:
        for row in short:
            log.write(row)
    back = read_flight_log(path)
    assert [s.payload for s in samples_from_rows(back, 4.0)] == [s.payload for s in samples_from_rows(short, 4.0)]


def test_a_flight_without_sensor_columns_is_refused():
    with pytest.raises(ValueError, match="columns"):
        samples_from_rows(np.zeros((3, len(ROW_FIELDS) - 11)), 4.0)


def test_firmware_replay_command_writes_jobs_and_summary(tmp_path: Path):
    out = tmp_path / "replay"
    result = CliRunner().invoke(app, ["firmware", "replay", "--seconds", "0.3", "--out", str(out)])
    assert result.exit_code == 0, result.output
    assert "fixed+mul: 30 samples, 30 PWM commands, 0 deadline misses" in result.stdout
    lines = (out / "jobs.csv").read_text().splitlines()
    assert len(lines) == 1 + 2 * 30
    text = (out / "summary.json").read_text()
    summary = json.loads(text)
    assert text == json.dumps(summary, indent=2) + "\n"  # two-space JSON, one final newline
    assert summary["tasks"]["estimator"]["jobs"] == 30 and summary["tasks"]["pid"]["deadline_misses"] == 0


def test_firmware_build_and_size_commands(tmp_path: Path):
    elf = tmp_path / "fw.elf"
    result = CliRunner().invoke(app, ["firmware", "build", "--arith", "float", "--no-mul", "-o", str(elf)])
    assert result.exit_code == 0, result.output
    assert "float-no-mul:" in result.stdout and elf.stat().st_size > 0
    result = CliRunner().invoke(app, ["firmware", "size", str(elf), "--top", "5"])
    assert result.exit_code == 0, result.output
    assert ".text" in result.stdout and "largest functions and objects (5 of" in result.stdout
    result = CliRunner().invoke(app, ["firmware", "size", str(elf), "--arith", "fixed"])
    assert result.exit_code == 2 and "--arith: chooses a build" in result.output


def test_job_stamps_are_placed_past_the_32_bit_wrap_of_timer0():
    # TIMER0 wraps every 2**32 cycles (17 s at 4 ns): a record read at chip cycle `now` lies less
    # than that before it
    from robosoc.cosim.firmware_run import _full_cycle

    now = 5 * 2**32 + 1000
    placed = [_full_cycle(stamp, now) for stamp in (100, 150, 900, 1000)]
    assert placed == [5 * 2**32 + 100, 5 * 2**32 + 150, 5 * 2**32 + 900, now]
    assert _full_cycle(2**32 - 5, now) == 4 * 2**32 + 2**32 - 5  # before the wrap
