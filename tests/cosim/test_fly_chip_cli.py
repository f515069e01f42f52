"""``robosoc fly --controller chip``: the lockstep flight through the CLI."""

from __future__ import annotations

import csv
from pathlib import Path

from typer.testing import CliRunner

from robosoc.cli import app
from robosoc.control.flight import ROW_FIELDS
from robosoc.control.flight_log import read_flight_log
from robosoc.cosim.replay import JOB_CSV_FIELDS


def test_fly_with_the_chip_writes_log_plot_and_jobs(tmp_path: Path) -> None:
    out = tmp_path / "run"
    result = CliRunner().invoke(
        app, ["fly", "--controller", "chip", "--seconds", "0.5", "--seed", "4", "--out", str(out)]
    )
    assert result.exit_code == 0, result.output
    text = result.output
    assert "controller chip (fixed+mul, lockstep)" in text
    assert "hover height error" in text and "attitude tracking error" in text
    assert "EKF attitude error" not in text, "the chip's estimate is not visible"
    assert "estimator 50 jobs: response mean" in text and "pid       50 jobs: response mean" in text
    assert "deadline misses: 0; 50 PWM commands; real-time factor" in text
    rows = read_flight_log(out / "flight.csv")
    assert rows.shape == (50, len(ROW_FIELDS))
    assert (out / "flight.png").stat().st_size > 10_000
    with (out / "jobs.csv").open() as handle:
        jobs = list(csv.DictReader(handle))
    assert tuple(jobs[0]) == JOB_CSV_FIELDS
    assert sorted({j["task"] for j in jobs}) == ["estimator", "pid"] and len(jobs) == 100
    assert all(j["deadline_met"] == "1" for j in jobs)


def test_fly_with_the_soft_float_build_without_multiplier(tmp_path: Path) -> None:
    result = CliRunner().invoke(
        app, ["fly", "--controller", "chip", "--arith", "float", "--no-mul", "--seconds", "0.05", "--no-out"]
    )
    assert result.exit_code == 0, result.output
    assert "controller chip (float-no-mul, lockstep)" in result.output
    assert "5 PWM commands" in result.output
