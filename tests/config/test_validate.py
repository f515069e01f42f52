"""``robosoc.config.validate``: conversion of every field type, the dotted path of an error, files.

Every message is compared whole: ``<file>: <dotted.path>: <reason>`` is the user's only clue.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any

import pytest

from robosoc.config import ConfigError, from_mapping, load_toml, replace_checked
from robosoc.config.chip import ChipConfig, load_chip_config
from robosoc.config.scenario import ScenarioConfig, SensorConfig, SetpointStep
from robosoc.config.validate import load_toml_named, named_fields
from robosoc.config.vehicle import DragConfig, VehicleConfig


@dataclasses.dataclass(frozen=True)
class Probe:
    """A test-only class with the field types the conversion knows, and two it does not."""

    either: int | bool = 0
    anything: Any = None
    listed: list[int] = dataclasses.field(default_factory=list)
    note: str = ""

    def __post_init__(self) -> None:
        if self.note == "plain":
            raise ValueError("no field named here")
        if self.note == "spaces":
            raise ValueError("two words: then the reason")


def error(cls: type, data: dict[str, Any], where: str = "f.toml") -> ConfigError:
    with pytest.raises(ConfigError) as info:
        from_mapping(cls, data, where)
    return info.value


def test_config_error_formats_file_field_and_reason() -> None:
    e = ConfigError("f.toml", "a.b", "bad")
    assert (e.where, e.field, e.reason, str(e)) == ("f.toml", "a.b", "bad", "f.toml: a.b: bad")
    assert str(ConfigError("", "", "r")) == "<root>: r"
    assert str(ConfigError("", "x", "r")) == "x: r"
    assert str(ConfigError("f.toml", "", "r")) == "f.toml: <root>: r"
    assert isinstance(e, ValueError)


CONVERSION_ERRORS = [
    (SensorConfig, {"noise": 1}, "f.toml: noise: expected true or false, got 1"),
    (VehicleConfig, {"idle_pwm": "5"}, "f.toml: idle_pwm: expected an integer, got '5'"),
    (VehicleConfig, {"idle_pwm": True}, "f.toml: idle_pwm: expected an integer, got True"),
    (VehicleConfig, {"mass": "1"}, "f.toml: mass: expected a number, got '1'"),
    (VehicleConfig, {"mass": False}, "f.toml: mass: expected a number, got False"),
    (VehicleConfig, {"name": 5}, "f.toml: name: expected a string, got 5"),
    (VehicleConfig, {"variant": "big"}, "f.toml: variant: must be one of 'default', 'laser', got 'big'"),
    (VehicleConfig, {"motor": 5}, "f.toml: motor: expected a table, got int"),
    (VehicleConfig, {"inertia": 5}, "f.toml: inertia: expected a list, got int"),
    (VehicleConfig, {"inertia": [0.01, 0.02]}, "f.toml: inertia: expected 3 values, got 2"),
    (VehicleConfig, {"inertia": [0.01, "x", 0.02]}, "f.toml: inertia[1]: expected a number, got 'x'"),
    (VehicleConfig, {"drag": {"c_x": 1.0}}, "f.toml: drag.c_x: unknown field (known: c_mxy, c_mz, c_wxy, c_wz)"),
    (DragConfig, {"zz": 1.0, "aa": 1.0}, "f.toml: aa: unknown field (known: c_mxy, c_mz, c_wxy, c_wz)"),
    (ScenarioConfig, {"wind": {"gusts": 5}}, "f.toml: wind.gusts: expected a list, got int"),
    (ScenarioConfig, {"wind": {"gusts": [{}, {"start_s": "x"}]}},
     "f.toml: wind.gusts[1].start_s: expected a number, got 'x'"),
    (ScenarioConfig, {"flight": {"steps": [{"axis": "roll", "value": 1.0}]}},
     "f.toml: flight.steps[0].time_s: missing required field"),
    (SetpointStep, {"time_s": 1.0, "axis": "roll"}, "f.toml: value: missing required field"),
    (ChipConfig, {"powered_off": [[1, "a"]]}, "f.toml: powered_off[0][1]: expected an integer, got 'a'"),
    (ChipConfig, {"tiles": [{"x": 1, "y": 0, "sram_bytes": "big"}]},
     "f.toml: tiles[0].sram_bytes: expected an integer, got 'big'"),
    (Probe, {"either": "x"}, "f.toml: either: expected an integer, got 'x'; expected true or false, got 'x'"),
    (Probe, {"listed": [1]}, "f.toml: listed: unsupported field type list[int]"),
    # a rule of the class: the field named in its message is joined to the path of the table
    (ScenarioConfig, {"wind": {"gust_sigma": 50}}, "f.toml: wind.gust_sigma: must be in [0, 10] m/s, got 50.0"),
    (ScenarioConfig, {"flight": {"steps": [{"time_s": 1.0, "axis": "roll", "value": 1.0}]}},
     "f.toml: flight.steps[0].time_s: must not come before take-off + climb_s (4.5 s), got 1.0"),
    (ChipConfig, {"tiles": [{"x": 1, "y": 0, "clock_period_ns": 0.0}]},
     "f.toml: tiles[0].clock_period_ns: must be in [0.5, 1000] ns, got 0"),
    (Probe, {"note": "plain"}, "f.toml: <root>: no field named here"),
    (Probe, {"note": "spaces"}, "f.toml: <root>: two words: then the reason"),
    (ScenarioConfig, {"wind": {"gusts": [{"start_s": 1.0, "duration_s": 1.0, "rise_s": 0.8}]}},
     "f.toml: wind.gusts[0].rise_s: must be >= 0 and at most half of duration_s, got 0.8"),
]  # fmt: skip


@pytest.mark.parametrize(("cls", "data", "message"), CONVERSION_ERRORS)
def test_conversion_errors_name_the_dotted_field(cls: type, data: dict[str, Any], message: str) -> None:
    e = error(cls, data)
    assert str(e) == message
    assert e.where == "f.toml"


def test_conversions_that_succeed() -> None:
    v = from_mapping(VehicleConfig, {"mass": 2, "inertia": [0.01, 0.01, 0.02], "motor": {"psi": 0.01}})
    assert v.mass == 2.0 and isinstance(v.mass, float) and v.inertia == (0.01, 0.01, 0.02)
    assert v.motor.psi == 0.01 and v.motor.r_a == VehicleConfig().motor.r_a  # a table merges into the default's
    p = from_mapping(Probe, {"either": True, "anything": {"k": [1]}})
    assert p.either is True and p.anything == {"k": [1]}
    assert from_mapping(Probe, {"either": 3}).either == 3
    c = from_mapping(ChipConfig, {"tiles": [{"x": 1, "y": 0, "multiplier": None}], "powered_off": [[1, 1]]})
    assert c.tiles[0].multiplier is None and c.powered_off == ((1, 1),)
    s = from_mapping(ScenarioConfig, {"wind": {"gusts": [{"start_s": 2.0}, {}]}})
    assert [g.start_s for g in s.wind.gusts] == [2.0, 0.0]


def test_an_explicit_base_keeps_the_fields_not_named() -> None:
    base = VehicleConfig(name="b", mass=2.0)
    v = from_mapping(VehicleConfig, {"spawn_yaw_deg": 10.0}, base=base)
    assert (v.name, v.mass, v.spawn_yaw_deg) == ("b", 2.0, 10.0)
    nested = from_mapping(
        VehicleConfig, {"drag": {"c_wz": 0.5}}, base=dataclasses.replace(base, drag=DragConfig(c_mz=1.0))
    )
    assert nested.drag == DragConfig(c_wz=0.5, c_mz=1.0)


def test_named_fields_descends_tables_only() -> None:
    data = {"a": {"b": {"c": 1}, "d": 2}, "e": [{"f": 1}], "g": 3}
    assert named_fields(data) == ("a.b.c", "a.d", "e", "g")
    assert named_fields({"x": {"y": 1}}, "top") == ("top.x.y",)


def test_files(tmp_path: Path) -> None:
    missing = tmp_path / "none.toml"
    with pytest.raises(ConfigError) as info:
        load_toml(SensorConfig, missing)
    assert str(info.value) == f"{missing}: <root>: file not found" and info.value.where == str(missing)
    broken = tmp_path / "broken.toml"
    broken.write_text("rate_hz = [")
    with pytest.raises(ConfigError) as info:
        load_toml(SensorConfig, broken)
    assert (info.value.where, info.value.field) == (str(broken), "")
    assert info.value.reason.startswith("invalid TOML: ") and len(info.value.reason) > len("invalid TOML: ")
    chip = tmp_path / "chip.toml"
    chip.write_text("[chip]\nwidth = 3\n[other]\nx = 1\n")
    assert load_chip_config(chip, section="chip").width == 3
    assert load_toml(ChipConfig, chip, "chip").width == 3
    config, named = load_toml_named(ChipConfig, chip, "chip")
    assert config.width == 3 and named == ("width",)
    with pytest.raises(ConfigError) as info:
        load_chip_config(chip, section="mesh")
    assert str(info.value) == f"{chip}: mesh: missing table"
    with pytest.raises(ConfigError) as info:
        load_chip_config(chip)  # without a section the whole file is the chip: [chip] is unknown
    assert str(info.value).startswith(f"{chip}: chip: unknown field (known: ")
    plain = tmp_path / "plain.toml"
    plain.write_text("width = 4\nheight = 1\n")
    assert (load_chip_config(plain).width, load_chip_config(plain).height) == (4, 1)


def test_replace_checked() -> None:
    v = VehicleConfig()
    assert replace_checked(v, mass=2.0) == dataclasses.replace(v, mass=2.0)
    with pytest.raises(ConfigError) as info:
        replace_checked(v, mass=-1.0)
    e = info.value
    assert (e.where, e.field, e.reason) == ("", "", "mass: must be positive, got -1.0")
    assert str(e) == "<root>: mass: must be positive, got -1.0"
    with pytest.raises(ConfigError) as info:
        replace_checked(v, wings=2)
    assert "wings" in info.value.reason and info.value.where == "" and info.value.field == ""
