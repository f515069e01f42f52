"""``robosoc profile RUN_DIR`` and ``robosoc fly --profile``: the same profile, checked against the
run's summary.json, and clear refusals of what is not a chip run folder."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from typer.testing import CliRunner

from robosoc.cli import app

FLY = ["fly", "--duration", "0.3"]


def _invoke(args: list[str]):
    result = CliRunner().invoke(app, [str(a) for a in args])
    assert "Traceback" not in result.output, result.output
    return result


@pytest.fixture(scope="module")
def flown(tmp_path_factory) -> tuple[Path, Path]:
    """The same 0.3 s chip flight, once plainly and once with --profile."""
    plain, profiled = tmp_path_factory.mktemp("plain"), tmp_path_factory.mktemp("profiled")
    assert _invoke([*FLY, "--out", plain]).exit_code == 0
    result = _invoke([*FLY, "--out", profiled, "--profile"])
    assert result.exit_code == 0, result.output
    assert "os_port_interrupt" in result.output  # the table
    return plain, profiled


def test_profile_of_a_run_folder_equals_fly_profile(flown) -> None:
    plain, profiled = flown
    assert not (plain / "profile.json").exists()
    result = _invoke(["profile", plain, "--top", "3"])
    assert result.exit_code == 0, result.output
    assert "the profile's totals equal" in result.output and "DIFFERS" not in result.output
    assert (plain / "profile.csv").read_bytes() == (profiled / "profile.csv").read_bytes()
    summary = json.loads((plain / "summary.json").read_text())
    totals = json.loads((plain / "profile.json").read_text())["totals"]
    assert totals["cycles"] == summary["cycles"]["tiles"]
    assert totals["total_uj"] == pytest.approx(summary["energy"]["total_uj"], rel=1e-12)
    # the report of a profiled flight shows the profile
    assert 'data-plot="profile"' in (profiled / "report.html").read_text()


def test_a_summary_that_differs_is_said_loudly(flown, tmp_path: Path) -> None:
    plain, _ = flown
    copy = tmp_path / "copy"
    copy.mkdir()
    for name in ("scenario.toml", "summary.json"):
        (copy / name).write_bytes((plain / name).read_bytes())
    summary = json.loads((copy / "summary.json").read_text())
    summary["energy"]["noc_uj"] *= 2
    (copy / "summary.json").write_text(json.dumps(summary))
    result = _invoke(["profile", copy])
    assert result.exit_code == 0
    assert "THE RE-RUN DIFFERS" in result.output and "noc_uj" in result.output
    assert "differ from summary.json" in json.loads((copy / "profile.json").read_text())["notes"][0]


@pytest.mark.parametrize(
    ("setup", "message"),
    [
        (lambda d: None, "has no scenario.toml"),
        (lambda d: (d / "scenario.toml").write_text("duration_s = 0.3\n"), "has no summary.json"),
        (lambda d: [(d / "scenario.toml").write_text("duration_s = [\n"), (d / "summary.json").write_text("{}")],
         "invalid TOML"),
        (lambda d: [(d / "scenario.toml").write_text("duration_s = -1\n"), (d / "summary.json").write_text("{}")],
         "duration_s"),
        (lambda d: [(d / "scenario.toml").write_text("controller = 'host'\n"), (d / "summary.json").write_text("{}")],
         "no firmware to profile"),
        (lambda d: [(d / "scenario.toml").write_text("duration_s = 0.3\n"), (d / "summary.json").write_text("[1]")],
         "expected a JSON object"),
    ],
)  # fmt: skip
def test_what_is_not_a_chip_run_folder_is_refused(setup, message: str, tmp_path: Path) -> None:
    setup(tmp_path)
    result = _invoke(["profile", tmp_path])
    assert result.exit_code == 2, result.output
    assert message in result.output and tmp_path.name in result.output
    assert not (tmp_path / "profile.json").exists()


def test_fly_profile_needs_the_chip(tmp_path: Path) -> None:
    result = _invoke(["fly", "--duration", "0.01", "--controller", "host", "--profile", "--no-out"])
    assert result.exit_code == 2 and "--profile" in result.output
