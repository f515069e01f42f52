"""A project file's ``[chip]`` and ``[scenario]`` tables (issue 32, item 1: "optional chip fields and
scenario defaults"): every scenario that flies the project starts from them, under a scenario
file's fields and a command's options, however the project is named (option, scenario file, sweep
point); each wrong key names the project file and the key."""

from __future__ import annotations

from pathlib import Path

import pytest
from tests.firmware.test_project import PINGPONG, write_project

from robosoc.cli.errors import CliError
from robosoc.cli.scenario_flags import ScenarioFlags, resolve
from robosoc.config.firmware import DEFAULT_PROJECT, FirmwareConfig
from robosoc.config.project import PROJECT_FILE, load_project
from robosoc.config.project_scenario import project_scenario, scenario_from_fields
from robosoc.config.scenario import ScenarioConfig
from robosoc.config.sweep import load_sweep
from robosoc.config.validate import ConfigError

DEFAULTS = """
[chip]
width = 3
dvfs.points = []

[scenario]
duration_s = 7.0
seed = 5
wind.gusts = []
flight.height_m = 1.5
"""


@pytest.fixture
def project(tmp_path: Path) -> Path:
    return write_project(tmp_path / "pp", PINGPONG + DEFAULTS)


def test_the_defaults_are_read_as_dotted_fields(project: Path) -> None:
    loaded = load_project(project)
    assert dict(loaded.chip) == {"width": 3, "dvfs.points": []}
    assert dict(loaded.scenario) == {"duration_s": 7.0, "seed": 5, "wind.gusts": [], "flight.height_m": 1.5}


def test_a_project_scenario_is_the_built_in_one_with_the_projects_chip_and_defaults(project: Path) -> None:
    scenario = project_scenario(str(project))
    built_in = ScenarioConfig()
    assert scenario.duration_s == 7.0 and scenario.seed == 5 and scenario.flight.height_m == 1.5
    assert scenario.wind.gusts == () and built_in.wind.gusts != ()
    assert scenario.firmware.project == str(project)
    assert (scenario.chip.width, scenario.chip.height) == (3, 2)
    # the seed's rule on the project's mesh: every core tile no task uses is off (the tasks: (0, 1), (1, 0))
    assert set(scenario.chip.powered_off) == {(1, 1), (2, 0), (2, 1)}
    assert scenario.flight.takeoff_s == built_in.flight.takeoff_s  # a field it does not name: the built-in's
    assert FirmwareConfig(project=str(project)).default_chip() == scenario.chip  # replay and Table I: the same chip


def test_the_shipped_default_project_declares_no_defaults() -> None:
    """The built-in scenario is the quadrotor project's own: ScenarioConfig() needs no project file."""
    loaded = load_project(DEFAULT_PROJECT)
    assert loaded.chip == () and loaded.scenario == ()
    assert project_scenario("") == ScenarioConfig()
    shipped = FirmwareConfig(project=str(DEFAULT_PROJECT))
    assert project_scenario(str(DEFAULT_PROJECT)) == ScenarioConfig(firmware=shipped)


def test_a_scenario_file_and_the_options_win_over_the_projects_defaults(project: Path, tmp_path: Path) -> None:
    scenario_file = tmp_path / "s" / "flight.toml"
    scenario_file.parent.mkdir()
    scenario_file.write_text(f'duration_s = 4.0\n[firmware]\nproject = "{project}"\n[chip]\nheight = 3\n')
    config = resolve(ScenarioFlags.of(None, scenario_file, {})).config
    assert config.duration_s == 4.0 and config.seed == 5 and config.flight.height_m == 1.5
    assert (config.chip.width, config.chip.height) == (3, 3)  # the file's field over the project's chip
    config = resolve(ScenarioFlags.of(None, scenario_file, {"duration": 2.0})).config
    assert config.duration_s == 2.0
    # named by the option alone, the project's defaults are the base
    config = resolve(ScenarioFlags.of(None, None, {"firmware": str(project)})).config
    assert config.duration_s == 7.0 and config.chip.width == 3
    # the option's project replaces the file's, and its defaults come with it
    other = write_project(tmp_path / "other", PINGPONG + "\n[scenario]\nduration_s = 9.0\n")
    config = resolve(ScenarioFlags.of(None, scenario_file, {"firmware": str(other)})).config
    assert config.firmware.project == str(other) and config.duration_s == 4.0 and config.seed == 1
    assert config.chip.width == 2 and config.chip.height == 3


def test_a_sweep_point_that_flies_the_project_gets_its_defaults(project: Path, tmp_path: Path) -> None:
    sweep = tmp_path / "sweep.toml"
    sweep.write_text(f'[base]\nduration_s = 3.0\n[grid]\n"firmware.project" = ["", "{project}"]\n')
    config = load_sweep(sweep)
    default, own = (config.scenario(a) for a in config.assignments())
    assert default == ScenarioConfig(duration_s=3.0)
    assert own.duration_s == 3.0 and own.seed == 5 and own.chip.width == 3 and own.flight.height_m == 1.5
    assert own == scenario_from_fields({"duration_s": 3.0, "firmware.project": str(project)}, "here")


@pytest.mark.parametrize(
    ("tables", "key", "reason"),
    [
        ("[chip]\ncolour = 3", "chip.colour", "is not a scenario field"),
        ("[chip]\nnoc.speed = 3", "chip.noc.speed", "is not a scenario field"),
        ("chip = 3", "chip", "expected a table of chip fields"),
        ("[scenario]\ncolour = 3", "scenario.colour", "is not a scenario field"),
        ("[scenario]\nflight = 3", "scenario.flight", "is a table; name one of its fields"),
        ("[scenario]\nchip.width = 3", "scenario.chip.width", "go in the project's [chip] table"),
        ("[scenario]\nfirmware.project = 'x'", "scenario.firmware.project", "does not name a project"),
        ("scenario = [1]", "scenario", "expected a table of scenario fields"),
    ],
)
def test_a_wrong_key_names_the_project_file_and_the_key(tmp_path: Path, tables: str, key: str, reason: str) -> None:
    text = PINGPONG + "\n" + tables if tables.startswith("[") else tables + "\n" + PINGPONG  # a key: before the tables
    folder = write_project(tmp_path / "pp", text + "\n")
    with pytest.raises(ConfigError) as caught:
        load_project(folder)
    assert caught.value.where == str(folder / PROJECT_FILE) and caught.value.field == key
    assert reason in caught.value.reason


@pytest.mark.parametrize(
    ("tables", "shown"),
    [
        ("[chip]\nwidth = 'three'", "chip.width: expected an integer, got 'three'"),
        ("[chip]\nwidth = 1\nheight = 1", "chip"),  # the tasks' tiles are outside a 1x1 mesh
        ("[scenario]\nduration_s = -1.0", "scenario.duration_s: must be in (0, 3600] s"),
        ("[scenario]\nflight.height_m = 'high'", "scenario.flight.height_m: expected a number"),
    ],
)
def test_a_wrong_value_is_named_with_the_project_file_when_flown(tmp_path: Path, tables: str, shown: str) -> None:
    folder = write_project(tmp_path / "pp", PINGPONG + "\n" + tables + "\n")
    with pytest.raises(CliError) as caught:
        resolve(ScenarioFlags.of(None, None, {"firmware": str(folder)}))
    text = str(caught.value)
    assert text.startswith("--firmware: ") and f"{folder / PROJECT_FILE}: {shown}" in text


def test_a_sweep_point_whose_project_is_missing_names_the_sweep_file_and_key(project: Path, tmp_path: Path) -> None:
    sweep = tmp_path / "sweep.toml"
    sweep.write_text(f'[grid]\n"firmware.project" = ["{project}", "{tmp_path / "nope"}"]\n')
    with pytest.raises(ConfigError) as caught:
        load_sweep(sweep)
    assert str(caught.value).startswith(f"{sweep}: grid.firmware.project[1]: firmware.project: no folder")


def test_a_project_read_again_is_the_file_as_it_is_now(project: Path) -> None:
    # a flight reads its project several times and the checked project is kept by the file's text:
    # an edit (same folder, same process) is seen, and a source removed since is still an error
    first = load_project(project)
    assert load_project(project) is first
    (project / PROJECT_FILE).write_text(PINGPONG + DEFAULTS.replace("duration_s = 7.0", "duration_s = 8.0"))
    assert dict(load_project(project).scenario)["duration_s"] == 8.0
    (project / "tasks.c").unlink()
    with pytest.raises(ConfigError, match=r"project.sources\[0\].*no such file"):
        load_project(project)
