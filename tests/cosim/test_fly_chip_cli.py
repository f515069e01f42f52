"""``robosoc fly``: the chip flies by default; the run folder, the summary table, the options."""

from __future__ import annotations

import csv
import json
import re
import tomllib
from pathlib import Path

import pytest
from typer.testing import CliRunner

from robosoc.cli import app
from robosoc.config.scenario import ScenarioConfig
from robosoc.config.validate import from_mapping
from robosoc.control.flight import ROW_FIELDS
from robosoc.control.flight_log import read_flight_log
from robosoc.outputs.run_folder import JOB_CSV_FIELDS

runner = CliRunner()


def test_fly_flies_the_chip_by_default_and_writes_the_run_folder(tmp_path: Path) -> None:
    out = tmp_path / "run"
    result = runner.invoke(app, ["fly", "--duration", "0.5", "--seed", "4", "--out", str(out)])
    assert result.exit_code == 0, result.output
    text = result.output
    assert "controller chip (fixed+mul, lockstep)" in text
    assert "hover height error RMS" in text and "roll tracking RMS" in text
    assert re.search(r"estimator jobs\s+│\s+50", text) and re.search(r"pid jobs\s+│\s+50", text)
    assert re.search(r"deadline misses\s+│\s+0", text)
    assert re.search(r"real-time factor [0-9.]+ \(0.5 s simulated in [0-9.]+ s\)", text)
    assert f"run folder: {out}" in text
    rows = read_flight_log(out / "flight.csv")
    assert rows.shape == (50, len(ROW_FIELDS))
    assert (out / "flight.png").stat().st_size > 10_000
    with (out / "jobs.csv").open() as handle:
        jobs = list(csv.DictReader(handle))
    assert tuple(jobs[0]) == JOB_CSV_FIELDS and len(jobs) == 100
    summary = json.loads((out / "summary.json").read_text())
    assert summary["complete"] is True and summary["seed"] == 4 and summary["tasks"]["pid"]["jobs"] == 50
    resolved = from_mapping(ScenarioConfig, tomllib.loads((out / "scenario.toml").read_text()))
    assert resolved == ScenarioConfig(duration_s=0.5, seed=4)


def test_options_override_the_scenario_file(tmp_path: Path) -> None:
    path = tmp_path / "s.toml"
    path.write_text('name = "mine"\nseed = 3\n[firmware]\narith = "fixed"\n')
    result = runner.invoke(
        app, ["fly", str(path), "--arith", "float", "--no-mul", "--seconds", "0.05", "--seed", "9", "--no-out"]
    )
    assert result.exit_code == 0, result.output
    assert "controller chip (float-no-mul, lockstep), seed 9" in result.output
    assert f"from {path}: name, seed, firmware.arith" in result.output
    assert "from --seconds: duration_s" in result.output and "from --arith: firmware.arith" in result.output
    assert "from --mul/--no-mul: firmware.multiplier" in result.output


def test_the_default_run_folder_is_named_after_scenario_and_seed(tmp_path: Path, monkeypatch) -> None:
    monkeypatch.chdir(tmp_path)
    result = runner.invoke(app, ["fly", "--controller", "host", "--duration", "0.05", "--seed", "12"])
    assert result.exit_code == 0, result.output
    summary = json.loads(Path("runs/fly-default-s12/summary.json").read_text())
    assert summary["controller"] == "host" and summary["tasks"] is None
    assert not Path("runs/fly-default-s12/jobs.csv").exists()


def test_conflicting_options_are_refused_before_flying(tmp_path: Path) -> None:
    path = tmp_path / "s.toml"
    path.write_text("")
    for args, option in (
        (["--controller", "host", "--arith", "float"], "--arith"),
        (["--controller", "host", "--no-mul"], "--mul/--no-mul"),
        (["--duration", "1", "--seconds", "1"], "--duration"),
        ([str(path), "--scenario", str(path)], "--scenario"),
    ):
        result = runner.invoke(app, ["fly", "--no-out", *args])
        assert result.exit_code == 2, (args, result.output)
        assert option in result.output and "flying scenario" not in result.output


def test_a_host_scenario_file_refuses_firmware_options(tmp_path: Path) -> None:
    path = tmp_path / "host.toml"
    path.write_text('controller = "host"\n')
    result = runner.invoke(app, ["fly", str(path), "--arith", "fixed", "--no-out"])
    assert result.exit_code == 2 and "--arith: only with the chip controller" in result.output


def test_two_vehicles_from_the_command_line(tmp_path: Path) -> None:
    result = runner.invoke(app, ["fly", "--vehicles", "2", "--duration", "0.1", "--out", str(tmp_path)])
    assert result.exit_code == 0, result.output
    assert "2 vehicles (default)" in result.output and "vehicle 2" in result.output
    top = json.loads((tmp_path / "summary.json").read_text())
    assert [v["tasks"]["pid"]["jobs"] for v in top["vehicles"]] == [10, 10]
    assert (tmp_path / "vehicle-2" / "jobs.csv").is_file()


def test_bench_fly_prints_its_last_line() -> None:
    result = runner.invoke(app, ["bench", "fly", "--arith", "fixed", "--mul", "--duration", "0.1"])
    assert result.exit_code == 0, result.output
    last = result.output.strip().splitlines()[-1]
    assert re.fullmatch(r"fly: [0-9]+\.[0-9]{2}× real time", last), last
    assert "chip fixed+mul" in result.output and "float" not in result.output


def test_bench_fly_flies_every_build_on_the_engine_asked_for(monkeypatch: pytest.MonkeyPatch) -> None:
    from robosoc.benchmarks import fly as bench

    engines = []
    real = bench.fly_scenario

    def flown(scenario, *args, **kwargs):
        engines.append((scenario.controller, scenario.chip.engine))
        return real(scenario, *args, **kwargs)

    monkeypatch.setattr(bench, "fly_scenario", flown)
    result = runner.invoke(app, ["bench", "fly", "--duration", "0.1", "--arith", "fixed", "--engine", "interp"])
    assert result.exit_code == 0, result.output
    assert "chip engine interp, the median of 3 flights each" in result.output
    assert engines == [("chip", "interp")] * 8  # two builds, each a warm-up flight and three timed ones
    bad = runner.invoke(app, ["bench", "fly", "--engine", "fast"])
    assert bad.exit_code == 2 and "--engine: must be one of interp, jit, auto, got 'fast'" in bad.output
    for runs in ("0", "101", "two"):
        refused = runner.invoke(app, ["bench", "fly", "--runs", runs])
        assert refused.exit_code == 2 and "--runs" in refused.output, refused.output


def test_bench_fly_reports_each_builds_median_flight(monkeypatch: pytest.MonkeyPatch) -> None:
    from robosoc.benchmarks import fly as bench

    factors = iter([9.0, 30.0, 10.0, 20.0, 9.0, 11.0, 12.0, 50.0])  # host: warm-up, 3 timed; chip: the same
    real = bench.fly_scenario

    def flown(scenario, *args, **kwargs):
        flight = real(scenario, *args, **kwargs)
        flight.summary["real_time_factor"] = next(factors)
        return flight

    monkeypatch.setattr(bench, "fly_scenario", flown)
    monkeypatch.setattr(bench, "ALL_BUILDS", (bench.ALL_BUILDS[-1],))
    result = runner.invoke(app, ["bench", "fly", "--duration", "0.03"])
    assert result.exit_code == 0, result.output
    assert re.search(r"host\s+│\s+20\.00×", result.output), result.output  # of 30, 10 and 20
    assert re.search(r"chip fixed\+mul\s+│\s+12\.00×\s+│\s+0\.60", result.output), result.output  # of 11, 12, 50
    assert result.output.strip().splitlines()[-1] == "fly: 12.00× real time"


def test_bench_fly_warms_up_and_marks_a_build_flown_while_its_code_was_translated(monkeypatch) -> None:
    """The warm-up flight lasts WARM_UP_S (at most the timed one's duration), so that auto enters
    its translations before the timing; a build flown while the second process translated its
    firmware (robosoc.chip.whole_code) is marked, with a note, as not yet at its steady speed."""
    from robosoc.benchmarks import fly as bench

    durations = []
    real = bench.fly_scenario

    def flown(scenario, *args, **kwargs):
        durations.append(scenario.duration_s)
        return real(scenario, *args, **kwargs)

    class Translating:
        def running(self) -> str:
            return "a key"

    monkeypatch.setattr(bench, "fly_scenario", flown)
    monkeypatch.setattr(bench, "WARM_UP_S", 0.05)
    monkeypatch.setattr(bench, "whole_code_translations", lambda: Translating())
    result = runner.invoke(app, ["bench", "fly", "--arith", "fixed", "--mul", "--duration", "0.1", "--runs", "1"])
    assert result.exit_code == 0, result.output
    assert durations == [0.05, 0.1]
    assert "chip fixed+mul *" in result.output and "still translating" in result.output
    runner.invoke(app, ["bench", "fly", "--arith", "fixed", "--mul", "--duration", "0.03", "--runs", "2"])
    assert durations[2:] == [0.03, 0.03, 0.03]  # (a warm-up no longer than the timed flights)
    monkeypatch.setattr(bench, "whole_code_translations", lambda: type("Idle", (), {"running": lambda self: None})())
    quiet = runner.invoke(app, ["bench", "fly", "--arith", "fixed", "--mul", "--duration", "0.1"])
    assert quiet.exit_code == 0 and "*" not in quiet.output


def test_fly_gives_the_same_flight_with_every_engine(tmp_path: Path) -> None:
    """The engine is a matter of host speed only: flight, jobs and figures are bit-identical."""
    folders = {}
    for engine in ("interp", "jit", "auto"):
        out = tmp_path / engine
        result = runner.invoke(app, ["fly", "--duration", "0.3", "--seed", "2", "--engine", engine, "--out", str(out)])
        assert result.exit_code == 0, result.output
        folders[engine] = out
    for engine in ("jit", "auto"):
        for name in ("flight.csv", "jobs.csv"):
            assert (folders[engine] / name).read_bytes() == (folders["interp"] / name).read_bytes(), (engine, name)
        summaries = [json.loads((folders[e] / "summary.json").read_text()) for e in (engine, "interp")]
        for summary in summaries:
            summary.pop("host_s")
            summary.pop("real_time_factor")
        assert summaries[0] == summaries[1]
        scenario = tomllib.loads((folders[engine] / "scenario.toml").read_text())
        assert scenario["chip"]["engine"] == engine  # the run folder records it
    host = runner.invoke(app, ["fly", "--controller", "host", "--engine", "jit", "--no-out"])
    assert host.exit_code == 2
    assert "--engine: only with the chip controller (the host controller runs no code)" in host.output
