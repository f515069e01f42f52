"""What a user reads when a configuration file or value is wrong, and how configs are written back.

Each message is checked whole: the file, the dotted field and the reason.
"""

from __future__ import annotations

import dataclasses
import math
import tomllib
from pathlib import Path

import pytest

from robosoc.config.scenario import MAX_VEHICLES, ScenarioConfig
from robosoc.config.sweep import load_sweep
from robosoc.config.toml_text import to_toml
from robosoc.config.validate import ConfigError, from_mapping, read_toml_mapping


def scenario_error(data: dict) -> str:
    with pytest.raises(ConfigError) as info:
        from_mapping(ScenarioConfig, data, "s.toml")
    return str(info.value)


# --- reading TOML files ---------------------------------------------------------------------------


def test_each_unreadable_file_is_named_with_what_is_wrong(tmp_path: Path):
    missing = tmp_path / "none.toml"
    folder = tmp_path / "folder.toml"
    folder.mkdir()
    blocker = tmp_path / "plain"
    blocker.write_text("")
    binary = tmp_path / "binary.toml"
    binary.write_bytes(b'name = "ok"\n\xff\xfe')
    broken = tmp_path / "broken.toml"
    broken.write_text("name = \n")
    cases = [
        (missing, "TOML file", f"{missing}: <root>: file not found"),
        (folder, "chip TOML file", f"{folder}: <root>: is a folder, expected a chip TOML file"),
        (blocker / "x.toml", "TOML file", f"{blocker / 'x.toml'}: <root>: cannot read: Not a directory"),
        (binary, "TOML file", f"{binary}: <root>: not UTF-8 text (offset 12): expected a TOML file"),
    ]
    for path, kind, message in cases:
        with pytest.raises(ConfigError) as info:
            read_toml_mapping(path, kind)
        assert str(info.value) == message
        assert info.value.where == str(path) and info.value.field == ""
    with pytest.raises(ConfigError) as info:
        read_toml_mapping(broken)
    assert str(info.value).startswith(f"{broken}: <root>: invalid TOML: ")
    assert read_toml_mapping(tmp_path / "folder.toml/../plain") == {}


def test_a_sweep_file_that_is_a_folder_is_named_as_a_sweep_file(tmp_path: Path):
    (tmp_path / "s.toml").mkdir()
    with pytest.raises(ConfigError) as info:
        load_sweep(tmp_path / "s.toml")
    assert str(info.value) == f"{tmp_path / 's.toml'}: <root>: is a folder, expected a sweep TOML file"


# --- scenario fields ------------------------------------------------------------------------------


def test_scenario_names_may_hold_letters_digits_underscore_dash_and_dot():
    assert from_mapping(ScenarioConfig, {"name": "Hover_2-b.v1"}).name == "Hover_2-b.v1"
    reason = "must be letters, digits, '_', '-' or '.' (it names the run folder)"
    for bad in ("", "a b", "a/b", "x*", "é?"):
        assert scenario_error({"name": bad}) == f"s.toml: name: {reason}, got {bad!r}"


def test_scenario_seed_and_vehicle_count_bounds_are_inclusive():
    assert from_mapping(ScenarioConfig, {"seed": 0}).seed == 0
    assert from_mapping(ScenarioConfig, {"vehicles": MAX_VEHICLES}).vehicles == 16
    assert scenario_error({"seed": -1}) == "s.toml: seed: must be between 0 and 2**63-1, got -1"
    assert scenario_error({"vehicles": 0}) == "s.toml: vehicles: must be between 1 and 16, got 0"
    assert scenario_error({"vehicles": 17}) == "s.toml: vehicles: must be between 1 and 16, got 17"


def test_scenario_controller_must_be_chip_or_host():
    assert from_mapping(ScenarioConfig, {"controller": "host"}).controller == "host"
    assert scenario_error({"controller": "fpga"}) == "s.toml: controller: must be one of 'chip', 'host', got 'fpga'"


def test_a_multiplier_build_needs_the_multiplier_on_both_task_tiles():
    no_mul_at_ekf = {"chip": {"tiles": [{"x": 0, "y": 1, "multiplier": False}]}}
    assert scenario_error(no_mul_at_ekf) == (
        "s.toml: firmware.multiplier: the build uses the multiplier but task 'estimator' runs on [0, 1], which has "
        "none (chip.tile or chip.tiles)"
    )
    no_mul_at_pid = {"chip": {"tiles": [{"x": 1, "y": 0, "multiplier": False}]}}
    assert "task 'pid' runs on [1, 0], which has none" in scenario_error(no_mul_at_pid)
    # without the multiplier in the build, or with it turned off on another tile, all is well
    from_mapping(ScenarioConfig, {**no_mul_at_ekf, "firmware": {"multiplier": False}})
    from_mapping(ScenarioConfig, {"chip": {"tiles": [{"x": 1, "y": 1, "multiplier": False}]}})


def test_a_fixed_length_tuple_takes_exactly_its_length():
    def placed(tile: list) -> dict:
        return {"firmware": {"placement": [{"task": "estimator", "tile": tile}]}}

    assert scenario_error(placed([1, 0, 0])) == "s.toml: firmware.placement[0].tile: expected 2 values, got 3"
    assert scenario_error(placed([1])) == "s.toml: firmware.placement[0].tile: expected 2 values, got 1"
    assert scenario_error(placed([1, "a"])) == "s.toml: firmware.placement[0].tile[1]: expected an integer, got 'a'"
    assert scenario_error({"firmware": {"placement": [{"task": "ekf", "tile": [1, 1]}]}}) == (
        "s.toml: firmware.placement[0].task: the project 'quadrotor' has no task 'ekf' (its tasks: estimator, pid)"
    )


def test_a_sweep_point_that_breaks_the_scenario_names_the_sweep_file_and_keeps_the_base(tmp_path: Path):
    path = tmp_path / "s.toml"
    placement = '[{task = "estimator", tile = [5, 5]}]'
    path.write_text(f'[base]\nduration_s = 4.0\n[[points]]\n"firmware.placement" = {placement}\n')
    with pytest.raises(ConfigError) as info:  # a listed point is checked before anything runs
        load_sweep(path)
    assert str(info.value).startswith(f"{path}: points[0]: firmware.placement[0].tile: [5, 5] (estimator)")
    path.write_text("[base]\nduration_s = 4.0\n[[points]]\nvehicles = 2\n")
    config = load_sweep(path)
    point = (("firmware.placement", [{"task": "estimator", "tile": [5, 5]}]),)
    with pytest.raises(ConfigError) as info:
        config.scenario(point)
    assert str(info.value).startswith(f"{path}: firmware.placement[0].tile")
    with pytest.raises(ConfigError) as info:
        config.scenario(point, where="point 0")
    assert str(info.value).startswith("point 0: firmware.placement[0].tile")
    assert config.scenario((("vehicles", 2),)).duration_s == 4.0


# --- writing TOML ----------------------------------------------------------------------------------


@dataclasses.dataclass(frozen=True)
class _Inner:
    gain: float = 1.5


@dataclasses.dataclass(frozen=True)
class _Sample:
    a: float = math.nan
    b: float = math.inf
    c: float = -math.inf
    d: float = 0.0
    label: str = 'say "hi"'
    flags: tuple[bool, ...] = (True, False)
    inner: _Inner = _Inner()
    items: tuple[_Inner, ...] = (_Inner(2.0), _Inner(-1.0))


def test_to_toml_writes_every_float_toml_can_hold_and_reads_back_equal():
    text = to_toml(_Sample(), header="first line  \nsecond")
    assert text.startswith("# first line\n# second\na = nan\nb = inf\nc = -inf\nd = 0.0\n")
    assert text.endswith("\n") and not text.endswith("\n\n")
    data = tomllib.loads(text)
    assert math.isnan(data["a"]) and data["b"] == math.inf and data["c"] == -math.inf
    assert data["label"] == 'say "hi"' and data["flags"] == [True, False]
    assert data["inner"] == {"gain": 1.5}
    assert data["items"] == [{"gain": 2.0}, {"gain": -1.0}]
    assert "[[items]]" in text and "[inner]" in text
    assert to_toml(_Inner()) == "gain = 1.5\n"


def test_to_toml_writes_nested_table_lists_under_their_full_path():
    scenario = from_mapping(ScenarioConfig, {"wind": {"gusts": [{"start_s": 1.0}]}})
    text = to_toml(scenario)
    assert "[[wind.gusts]]" in text
    assert tomllib.loads(text)["wind"]["gusts"][0]["start_s"] == 1.0
    assert from_mapping(ScenarioConfig, tomllib.loads(text)) == scenario


def test_to_toml_refuses_what_toml_cannot_hold():
    with pytest.raises(TypeError) as info:
        to_toml(_Inner)
    assert str(info.value) == "expected a dataclass instance, got type"
    with pytest.raises(TypeError) as info:
        to_toml({"a": 1})
    assert str(info.value) == "expected a dataclass instance, got dict"

    @dataclasses.dataclass
    class Odd:
        value: object = dataclasses.field(default_factory=lambda: {1, 2})

    with pytest.raises(TypeError) as info:
        to_toml(Odd())
    assert str(info.value) == "cannot write set as TOML"
