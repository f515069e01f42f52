"""``robosoc serve``'s option rules and ``fly --decoupled``'s summary numbers, called as library
functions (no process, no socket).

Expectations from docs/cli.md: SCENARIO or its hidden alias ``--scenario`` (not both),
``--duration`` or its alias ``--seconds`` (not both), overrides named by the option as typed, a
flight of at least one sensor period, and an ``--out`` folder that is not an input file.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from robosoc.cli.errors import CliError
from robosoc.cli.serve import _out, resolve_scenario
from robosoc.config.vehicle import vehicle_preset

SCENARIO = 'name = "hop"\nduration_s = 1.5\nseed = 11\n[flight]\ntakeoff_s = 0.3\nsteps = []\n'


@pytest.fixture
def scenario(tmp_path: Path) -> Path:
    path = tmp_path / "hop.toml"
    path.write_text(SCENARIO)
    return path


def test_the_file_alone_gives_its_fields(scenario: Path) -> None:
    config, vehicle, path = resolve_scenario(None, scenario, None, None, None, None)
    assert (config.name, config.duration_s, config.seed, path) == ("hop", 1.5, 11, scenario)
    assert vehicle == vehicle_preset(config.vehicle)


def test_the_alias_and_the_argument_name_the_same_file(scenario: Path) -> None:
    by_alias = resolve_scenario(scenario, None, None, None, None, None)
    assert by_alias == resolve_scenario(None, scenario, None, None, None, None)
    with pytest.raises(CliError, match="--scenario"):
        resolve_scenario(scenario, scenario, None, None, None, None)


def test_overrides_are_taken_and_each_duration_option_works(scenario: Path) -> None:
    config, vehicle, _ = resolve_scenario(None, scenario, 0.5, None, "laser", 4)
    assert (config.duration_s, config.vehicle, config.seed) == (0.5, "laser", 4)
    assert vehicle == vehicle_preset("laser")
    assert resolve_scenario(None, scenario, None, 0.25, None, None)[0].duration_s == 0.25
    with pytest.raises(CliError, match=r"--duration.*--seconds|--seconds.*--duration"):
        resolve_scenario(None, scenario, 0.5, 0.25, None, None)
    default = resolve_scenario(None, None, 0.75, None, None, None)
    assert default[0].duration_s == 0.75 and default[2] is None


@pytest.mark.parametrize(("duration", "seconds", "named"), [(0.001, None, "--duration"), (None, 0.001, "--seconds")])
def test_a_flight_shorter_than_a_sensor_period_names_the_option(
    scenario: Path, duration: float | None, seconds: float | None, named: str
) -> None:
    with pytest.raises(CliError) as caught:
        resolve_scenario(None, scenario, duration, seconds, None, None)
    assert caught.value.message == f"{named}: a flight lasts at least one sensor period, got 0.001 s"


def test_a_short_file_names_the_file_and_field(tmp_path: Path) -> None:
    short = tmp_path / "short.toml"
    short.write_text(SCENARIO.replace("duration_s = 1.5", "duration_s = 0.001"))
    with pytest.raises(CliError) as caught:
        resolve_scenario(None, short, None, None, None, None)
    assert caught.value.message == f"{short}: duration_s: a flight lasts at least one sensor period, got 0.001 s"
    with pytest.raises(CliError) as caught:
        resolve_scenario(short, None, None, None, None, None)
    assert caught.value.message.startswith(f"--scenario: {short}: duration_s: ")


def test_a_bad_vehicle_is_named_by_its_option(scenario: Path) -> None:
    with pytest.raises(CliError, match=r"^--vehicle: "):
        resolve_scenario(None, scenario, None, None, "blimp", None)


def test_out_folder_default_and_rules(scenario: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    assert _out(None, True, "chip", "hop", 11, scenario) is None
    made = _out(None, False, "chip", "hop", 11, scenario)
    assert made is not None and made.resolve() == (tmp_path / "runs" / "serve-chip-hop-s11").resolve()
    with pytest.raises(CliError, match="--out"):
        _out(tmp_path / "x", True, "physics", "hop", 11, scenario)
    with pytest.raises(CliError, match=r"^--out: "):
        _out(scenario, False, "physics", "hop", 11, scenario)  # the input file itself


def test_decoupled_summary_numbers() -> None:
    from robosoc.cli.fly_decoupled import _number

    assert _number(0.0234, 100, "cm") == "2.34 cm"
    assert _number(-1.5, 1, "deg") == "-1.50 deg"
    assert _number(None, 100, "cm") == "n/a"
    assert _number(float("nan"), 100, "cm") == "n/a"
    assert _number(float("inf"), 1, "deg") == "n/a"
