"""``robosoc fly`` and ``robosoc bench physics`` through the CLI."""

from pathlib import Path

import pytest
from typer.testing import CliRunner

from robosoc.cli import app
from robosoc.control.flight_log import read_flight_log

runner = CliRunner()


def test_firmware_options_need_the_chip_controller() -> None:
    for args in (["--arith", "float"], ["--no-mul"], ["--mul"]):
        result = runner.invoke(app, ["fly", "--controller", "host", "--seconds", "0.01", "--no-out", *args])
        assert result.exit_code == 2, result.output
        assert "only with the chip controller" in result.output and "flying scenario" not in result.output


def test_fly_writes_log_and_plot_and_prints_errors(tmp_path: Path) -> None:
    result = runner.invoke(
        app, ["fly", "--controller", "host", "--seconds", "6", "--seed", "2", "--out", str(tmp_path)]
    )
    assert result.exit_code == 0, result.output
    assert "hover height error RMS" in result.output and "attitude estimate RMS" in result.output
    rows = read_flight_log(tmp_path / "flight.csv")
    assert rows.shape[0] == 600
    assert (tmp_path / "flight.png").stat().st_size > 10_000


def test_bad_scenario_file_is_reported_with_the_field(tmp_path: Path) -> None:
    path = tmp_path / "bad.toml"
    path.write_text("[sensors]\nrate_hz = 300.0\n")
    result = runner.invoke(app, ["fly", "--scenario", str(path)])
    assert result.exit_code == 2
    assert "sensors.rate_hz" in result.output
    result = runner.invoke(app, ["fly", "--vehicle", "blimp"])
    assert result.exit_code == 2 and "vehicle" in result.output


def test_video_renders_frames_or_explains_why_not(tmp_path: Path) -> None:
    frames = tmp_path / "frames"
    result = runner.invoke(app, ["fly", "--seconds", "0.2", "--no-out", "--video", str(frames)])
    assert result.exit_code == 0, result.output
    if "no video" in result.output:
        pytest.skip("no OpenGL backend here: " + result.output)
    assert len(list(frames.glob("frame_*.png"))) == 5  # 0.2 s at 25 fps


def test_bench_physics_prints_the_summary_line() -> None:
    result = runner.invoke(app, ["bench", "physics", "--seconds", "0.2", "--runs", "2"])
    assert result.exit_code == 0, result.output
    last = result.output.strip().splitlines()[-1]
    assert last.startswith("physics: ") and last.endswith("x real time")
    assert float(last.split()[1].rstrip("x")) > 0


def test_fly_prints_which_fields_came_from_the_scenario_file(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    Path("h2.toml").write_text("[flight]\nheight_m = 2.0\n[sensors]\nnoise = false\n")
    result = runner.invoke(app, ["fly", "--scenario", "h2.toml", "--seconds", "0.5", "--no-out"])
    assert result.exit_code == 0, result.output
    assert "from h2.toml: flight.height_m, sensors.noise" in result.output
    assert "from --seconds: duration_s" in result.output
    assert "every other field: built-in default" in result.output
    result = runner.invoke(app, ["fly", "--seconds", "0.5", "--no-out"])
    assert result.exit_code == 0, result.output
    assert "from --seconds: duration_s" in result.output and "h2.toml" not in result.output
