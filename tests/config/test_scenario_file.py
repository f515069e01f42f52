"""Scenario files with the controller, firmware and chip: one schema, errors naming file and field,
and ``scenario show`` text that loads back to the same scenario."""

from __future__ import annotations

import tomllib
from pathlib import Path

import pytest
from typer.testing import CliRunner

from robosoc.cli import app
from robosoc.config.chip import ChipConfig, TileConfig, TileOverride
from robosoc.config.firmware import FirmwareConfig, Placement
from robosoc.config.scenario import ScenarioConfig, scenario_toml
from robosoc.config.validate import ConfigError, from_mapping, load_toml

runner = CliRunner()


def test_the_default_scenario_flies_fixed_mul_firmware_on_the_seeds_2x2_chip() -> None:
    s = ScenarioConfig()
    assert s.controller == "chip" and s.seed == 1 and s.vehicles == 1
    assert s.firmware == FirmwareConfig(arith="fixed", multiplier=True)
    # the seed's chip: I/O tile (0, 0), estimator (0, 1), PID (1, 0), the fourth tile off
    assert (s.chip.width, s.chip.height, s.chip.io_tile, s.chip.powered_off) == (2, 2, (0, 0), ((1, 1),))


def _placed(task: str, tile: str) -> str:
    return f'[[firmware.placement]]\ntask = "{task}"\ntile = {tile}\n'


@pytest.mark.parametrize(
    ("text", "field", "reason"),
    [
        ('[firmware]\narth = "fixed"\n', "firmware.arth", "unknown field"),
        ("colour = 3\n", "colour", "unknown field"),
        ('vehicles = "two"\n', "vehicles", "expected an integer"),
        ("[chip]\nwidth = 2.5\n", "chip.width", "expected an integer"),
        (_placed("estimator", "[3, 3]"), "firmware.placement[0].tile", "outside the 2x2 mesh"),
        (_placed("pid", "[1, 1]"), "firmware.placement[0].tile", "powered off"),
        (_placed("estimator", "[0, 0]"), "firmware.placement[0].tile", "the I/O tile"),
        (_placed("ekf", "[1, 1]"), "firmware.placement[0].task", "has no task 'ekf'"),
        ('[firmware]\nproject = "/nowhere"\n', "firmware.project", "no folder /nowhere"),
        ('controller = "chp"\n', "controller", "must be one of 'chip', 'host'"),
        ("vehicles = 17\n", "vehicles", "between 1 and 16"),
        ("seed = -1\n", "seed", "between 0 and 2**63-1"),
        ("[chip.tile]\nmultiplier = false\n", "firmware.multiplier", "has none"),
        ('[firmware]\narith = "double"\n', "firmware.arith", "must be one of 'float', 'fixed'"),
    ],
)
def test_a_bad_scenario_file_is_rejected_naming_file_and_field(tmp_path: Path, text: str, field: str, reason: str):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(ConfigError) as info:
        load_toml(ScenarioConfig, path)
    assert info.value.where == str(path) and info.value.field == field, str(info.value)
    assert reason in info.value.reason
    result = runner.invoke(app, ["fly", str(path), "--no-out"])
    assert result.exit_code == 2, result.output
    assert f"{path}: {field}: " in result.output and reason in result.output
    assert "flying scenario" not in result.output


def test_moving_a_task_to_the_fourth_tile_needs_it_powered_on(tmp_path: Path) -> None:
    path = tmp_path / "moved.toml"
    path.write_text(_placed("pid", "[1, 1]") + "[chip]\npowered_off = [[1, 0]]\n")
    s = load_toml(ScenarioConfig, path)
    assert s.firmware.mapping == {"pid": (1, 1)} and s.chip.powered_off == ((1, 0),)


def _odd_scenario() -> ScenarioConfig:
    chip = ChipConfig(
        width=3,
        height=2,
        powered_off=((2, 1),),
        tile=TileConfig(clock_period_ns=5.0),
        tiles=(TileOverride(x=1, y=0, sram_bytes=1 << 20),),
    )
    return ScenarioConfig(
        name="odd-one",
        duration_s=4.25,
        seed=2**63 - 1,
        vehicles=3,
        controller="host",
        firmware=FirmwareConfig(
            arith="float",
            multiplier=False,
            scheduler="rm",
            placement=(Placement("estimator", (2, 0)), Placement("pid", (2, 0))),
        ),
        chip=chip,
    )


@pytest.mark.parametrize("scenario", [ScenarioConfig(), _odd_scenario()], ids=["default", "odd"])
def test_scenario_text_loads_back_to_the_same_scenario(scenario: ScenarioConfig) -> None:
    data = tomllib.loads(scenario_toml(scenario))
    assert from_mapping(ScenarioConfig, data, "shown") == scenario
    assert data["chip"]["tile"]["clock_period_ns"] == scenario.chip.tile.clock_period_ns  # every field written


def test_scenario_show_prints_every_field_and_round_trips_through_a_file(tmp_path: Path) -> None:
    result = runner.invoke(app, ["scenario", "show"])
    assert result.exit_code == 0, result.output
    shown = tmp_path / "shown.toml"
    shown.write_text(result.output)
    assert load_toml(ScenarioConfig, shown) == ScenarioConfig()
    for table in ("[sensors]", "[wind]", "[[wind.gusts]]", "[flight]", "[[flight.steps]]", "[firmware]", "[chip]"):
        assert table in result.output
    # a file naming two fields: shown resolved, and the shown text loads back to the same scenario
    partial = tmp_path / "partial.toml"
    partial.write_text('controller = "host"\n[firmware]\narith = "float"\n')
    result = runner.invoke(app, ["scenario", "show", str(partial)])
    assert result.exit_code == 0, result.output
    shown.write_text(result.output)
    assert load_toml(ScenarioConfig, shown) == load_toml(ScenarioConfig, partial)
    assert load_toml(ScenarioConfig, shown).firmware.arith == "float"


def test_scenario_show_names_a_bad_file(tmp_path: Path) -> None:
    path = tmp_path / "bad.toml"
    path.write_text("[wind]\ngust_sigma = 11.0\n")
    result = runner.invoke(app, ["scenario", "show", str(path)])
    assert result.exit_code == 2 and f"{path}: wind.gust_sigma: must be in [0, 10]" in result.output
