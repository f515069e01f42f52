"""Bounds and defaults of the smaller configuration rules, each checked on both sides.

These close gaps a mutation run found (docs/testing.md): an inclusive bound made exclusive, a
tolerance divided instead of multiplied, a default name changed, a header dropped.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from robosoc.config.firmware import TICK_CYCLES_RANGE, FirmwareConfig, load_firmware_config
from robosoc.config.link import LinkFaults, parse_faults
from robosoc.config.ranges import describe
from robosoc.config.scenario import SCENARIO_HEADER, ScenarioConfig, scenario_toml, steps_per_period
from robosoc.config.sweep import check_field, load_sweep
from robosoc.config.toml_text import to_toml
from robosoc.config.validate import ConfigError, from_mapping, read_toml_mapping
from robosoc.config.vehicle import default_vehicle, laser_vehicle, vehicle_preset


def test_firmware_tick_and_period_bounds_are_inclusive():
    low, high = TICK_CYCLES_RANGE
    assert (low, high) == (4096, 1 << 30)
    for ok in (low, high):
        assert FirmwareConfig(tick_cycles=ok).tick_cycles == ok
    for bad in (low - 16, high + 16, low + 8):
        with pytest.raises(ValueError) as info:
            FirmwareConfig(tick_cycles=bad)
        assert str(info.value) == f"tick_cycles: must be a multiple of 16 from 4096 to 1073741824, got {bad}"
    for ok in (1, 1_000_000):
        assert FirmwareConfig(period_ticks=ok).period_ticks == ok
    for bad in (0, 1_000_001):
        with pytest.raises(ValueError) as info:
            FirmwareConfig(period_ticks=bad)
        assert str(info.value) == f"period_ticks: must be between 1 and 1000000, got {bad}"


def test_firmware_config_is_read_from_the_named_table(tmp_path: Path):
    path = tmp_path / "f.toml"
    path.write_text("period_ticks = 7\n")
    assert load_firmware_config(path).period_ticks == 7
    path.write_text("[build]\nperiod_ticks = 3\n[other]\nx = 1\n")
    assert load_firmware_config(path, "build").period_ticks == 3


def test_exclusive_fault_rates_may_sum_to_one_within_rounding():
    LinkFaults(loss=0.5, duplicate=0.5 + 1e-12)  # 1 + 1e-12: allowed (rounding of rates that sum to 1)
    LinkFaults(reorder=0.6, truncate=0.4)
    for rates in ({"reorder": 0.6, "loss": 0.5}, {"duplicate": 0.7, "reorder": 0.4}, {"truncate": 0.9, "loss": 0.2}):
        with pytest.raises(ValueError, match="must be at most 1"):
            LinkFaults(**rates)


def test_parse_faults_splits_each_item_at_its_first_equals_sign():
    with pytest.raises(ValueError) as info:
        parse_faults("loss=0.1=2")
    assert str(info.value) == "loss: must be a rate between 0 and 1, got '0.1=2'"


def test_describe_keeps_small_round_numbers_as_they_are():
    assert [describe(v) for v in (10, 100, 1000, 10**6)] == ["10", "100", "1000", "1000000"]


def test_steps_per_period_tolerates_only_rounding():
    dt = 0.001
    assert steps_per_period(100.0, dt) == 10
    assert steps_per_period(1.0 / (dt * (10 + 5e-9)), dt) == 10  # relative error 5e-10: rounding
    assert steps_per_period(1.0 / (dt * (10 + 5e-7)), dt) is None
    assert steps_per_period(1.0 / (dt * (1 + 1.5e-9)), dt) is None  # one step: absolute tolerance 1e-9
    assert steps_per_period(1.0 / (dt * (1 + 0.5e-9)), dt) == 1
    assert steps_per_period(2000.0, dt) is None  # less than one step per period
    assert steps_per_period(0.0, dt) is None and steps_per_period(float("nan"), dt) is None
    assert steps_per_period(1 / 1.8e305, dt) is None  # a period that overflows (was an OverflowError)
    assert steps_per_period(5e-324, dt) is None  # a rate whose product with dt is 0 (was a ZeroDivisionError)


def test_scenario_controller_is_checked_when_built_directly():
    with pytest.raises(ValueError) as info:
        ScenarioConfig(controller="fpga")  # type: ignore[arg-type]
    assert str(info.value) == "controller: must be one of 'chip', 'host', got 'fpga'"


def test_scenario_toml_starts_with_its_header_and_loads_back_equal(tmp_path: Path):
    text = scenario_toml(ScenarioConfig())
    header = "".join(f"# {line}\n" for line in SCENARIO_HEADER.splitlines())
    assert text.startswith(header)
    path = tmp_path / "s.toml"
    path.write_text(text)
    assert from_mapping(ScenarioConfig, read_toml_mapping(path)) == ScenarioConfig()


def test_defaults_of_the_reading_helpers_and_presets(tmp_path: Path):
    with pytest.raises(ConfigError) as info:
        from_mapping(ScenarioConfig, {"seed": -1})
    assert str(info.value) == "seed: must be between 0 and 2**63-1, got -1"  # no file: no location
    with pytest.raises(ConfigError) as info:
        read_toml_mapping(tmp_path)
    assert str(info.value) == f"{tmp_path}: <root>: is a folder, expected a TOML file"
    assert default_vehicle().name == "quad"
    assert laser_vehicle().name == "quad"
    assert vehicle_preset("default").name == "quad"
    assert vehicle_preset("default", "q2").name == "q2"


def test_check_field_names_the_parent_table_of_a_deep_field():
    with pytest.raises(ConfigError) as info:
        check_field("chip.noc.bogus", "s.toml", "grid.x")
    assert str(info.value).startswith("s.toml: grid.x: 'chip.noc.bogus' is not a scenario field (chip.noc has: ")
    with pytest.raises(ConfigError) as info:
        check_field("firmware.project.x", "s.toml", "k")
    assert str(info.value) == (
        "s.toml: k: 'firmware.project.x' is not a scenario field (firmware.project has: none: it is not a table)"
    )


def test_varied_lists_grid_fields_then_new_point_fields_once(tmp_path: Path):
    path = tmp_path / "s.toml"
    path.write_text(
        "[grid]\nduration_s = [1.0, 2.0]\n"
        "[[points]]\nvehicles = 2\nduration_s = 3.0\n"
        '[[points]]\nvehicles = 3\n"sensors.noise" = false\n'
    )
    assert load_sweep(path).varied() == ["duration_s", "vehicles", "sensors.noise"]


def test_to_toml_writes_tables_inside_table_lists_under_their_full_path():
    scenario = from_mapping(ScenarioConfig, {"wind": {"gusts": [{"start_s": 1.0, "velocity": [1.0, 2.0, 3.0]}]}})
    text = to_toml(scenario)
    assert "\n[[wind.gusts]]\nstart_s = 1.0\n" in text
    assert "\n[wind]\n" in text


def test_to_toml_of_a_config_with_only_tables_starts_with_the_first_table():
    from dataclasses import dataclass, field

    @dataclass(frozen=True)
    class Leaf:
        v: int = 1

    @dataclass(frozen=True)
    class Outer:
        leaf: Leaf = field(default_factory=Leaf)

    @dataclass(frozen=True)
    class Item:
        leaf: Leaf = field(default_factory=Leaf)

    @dataclass(frozen=True)
    class Root:
        items: tuple[Item, ...] = (Item(),)

    assert to_toml(Outer()) == "[leaf]\nv = 1\n"
    assert to_toml(Root()) == "[[items]]\n\n[items.leaf]\nv = 1\n"
