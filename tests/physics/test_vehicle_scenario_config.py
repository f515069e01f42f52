"""Vehicle and scenario configs: presets, TOML loading, and rejection naming the field."""

import dataclasses
import math
from pathlib import Path

import pytest

from robosoc.config.scenario import GustConfig, ScenarioConfig, SensorConfig, SetpointStep
from robosoc.config.validate import ConfigError, from_mapping, load_toml, load_toml_named
from robosoc.config.vehicle import VehicleConfig, laser_vehicle, vehicle_preset


def test_presets_carry_the_reference_numbers() -> None:
    default = vehicle_preset("default")
    assert default.mass == 1.478 and default.inertia == (0.01152, 0.01152, 0.0218)
    assert default.rest_height == 0.1825 and default.spawn_position == (0.0, 0.0, 0.3)
    laser = laser_vehicle()
    assert laser.mass == 1.748 and laser.com == (0.0, 0.0, -0.015)
    with pytest.raises(ValueError, match="variant"):
        vehicle_preset("hexacopter")


@pytest.mark.parametrize(
    ("data", "field"),
    [
        ({"mass": -1.0}, "mass"),
        ({"inertia": [0.01, 0.01, 0.5]}, "inertia"),
        ({"inertia": [0.01, 0.01]}, "inertia"),
        ({"com": [0.0, 0.0, 0.5]}, "com"),
        ({"arm_length": 0.0}, "arm_length"),
        ({"spawn_position": [0.0, 0.0, 0.1]}, "spawn_position"),
        ({"motor": {"psi": 0.0}}, "motor.psi"),
        ({"drag": {"c_wz": -0.1}}, "drag.c_wz"),
        ({"name": "a b"}, "name"),
        ({"mass": True}, "mass"),
        ({"wingspan": 1.0}, "wingspan"),
    ],
)
def test_bad_vehicle_configs_are_rejected_naming_the_field(data: dict, field: str) -> None:
    with pytest.raises(ConfigError) as info:
        from_mapping(VehicleConfig, data, "vehicle.toml")
    assert info.value.field == field
    assert str(info.value).startswith(f"vehicle.toml: {field}: ")


@pytest.mark.parametrize(
    ("text", "field"),
    [
        ("[sensors]\nrate_hz = 300.0\n", "sensors.rate_hz"),
        ("[sensors]\nbaro_sigma = -1.0\n", "sensors.baro_sigma"),
        ("duration_s = 0.0\n", "duration_s"),
        ("duration_s = 1.0005\n", "duration_s"),
        ('vehicle = "blimp"\n', "vehicle"),
        ("[wind]\ngust_sigma = 50.0\n", "wind.gust_sigma"),
        ("[[wind.gusts]]\nstart_s = 1.0\nduration_s = 1.0\nrise_s = 0.8\n", "wind.gusts[0].rise_s"),
        ('[[flight.steps]]\ntime_s = 1.0\naxis = "roll"\nvalue = 5.0\n', "flight.steps[0].time_s"),
        ('[[flight.steps]]\ntime_s = 6.0\naxis = "roll"\nvalue = 90.0\n', "flight.steps[0].value"),
        ('[[flight.steps]]\ntime_s = 6.0\naxis = "thrust"\nvalue = 1.0\n', "flight.steps[0].axis"),
        ("[flight]\nheight_m = 9.0\n", "flight.height_m"),
    ],
)
def test_bad_scenarios_are_rejected_naming_the_field(tmp_path: Path, text: str, field: str) -> None:
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(ConfigError) as info:
        load_toml(ScenarioConfig, path)
    assert info.value.field == field


def _load(tmp_path: Path, text: str) -> tuple[ScenarioConfig, tuple[str, ...]]:
    path = tmp_path / "s.toml"
    path.write_text(text)
    return load_toml_named(ScenarioConfig, path)


DEFAULT = ScenarioConfig()


def test_a_scenario_file_overrides_only_what_it_names(tmp_path: Path) -> None:
    config, named = _load(
        tmp_path,
        'name = "gusty"\nduration_s = 6.0\nvehicle = "laser"\n'
        "[sensors]\nrate_hz = 200.0\nnoise = false\n"
        "[wind]\nconstant = [1.0, 0.0, 0.0]\n"
        '[flight]\ntakeoff_s = 2.0\n[[flight.steps]]\ntime_s = 4.0\naxis = "yaw"\nvalue = -20.0\n',
    )
    assert config.name == "gusty" and config.vehicle == "laser"
    assert config.sensors.period_steps == 5 and not config.sensors.noise
    assert config.sensors.baro_bias == DEFAULT.sensors.baro_bias
    assert config.wind.constant == (1.0, 0.0, 0.0) and config.wind.gusts == DEFAULT.wind.gusts
    assert config.flight.takeoff_s == 2.0 and config.flight.height_m == DEFAULT.flight.height_m
    assert config.flight.steps == (SetpointStep(4.0, "yaw", -20.0),)
    assert named == (
        "name",
        "duration_s",
        "vehicle",
        "sensors.rate_hz",
        "sensors.noise",
        "wind.constant",
        "flight.takeoff_s",
        "flight.steps",
    )


def test_one_field_changes_one_field(tmp_path: Path) -> None:
    # The case: a [flight] table naming only the height kept none of the default plan.
    config, named = _load(tmp_path, "[flight]\nheight_m = 2.0\n")
    assert config == dataclasses.replace(DEFAULT, flight=dataclasses.replace(DEFAULT.flight, height_m=2.0))
    assert len(config.flight.steps) == 5
    assert named == ("flight.height_m",)


def test_a_nested_field_keeps_its_siblings(tmp_path: Path) -> None:
    config, named = _load(tmp_path, "[sensors]\nnoise = false\n")
    assert config == dataclasses.replace(DEFAULT, sensors=dataclasses.replace(DEFAULT.sensors, noise=False))
    assert named == ("sensors.noise",)
    config, named = _load(tmp_path, "flight.climb_rate_mps = 3.0\nwind.gust_sigma = 0.5\n")
    assert config.flight == dataclasses.replace(DEFAULT.flight, climb_rate_mps=3.0)
    assert config.wind == dataclasses.replace(DEFAULT.wind, gust_sigma=0.5)
    assert named == ("flight.climb_rate_mps", "wind.gust_sigma")


def test_a_list_is_replaced_as_a_whole(tmp_path: Path) -> None:
    config, named = _load(tmp_path, '[[flight.steps]]\ntime_s = 5.0\naxis = "pitch"\nvalue = 5.0\n')
    assert config.flight.steps == (SetpointStep(5.0, "pitch", 5.0),)  # not merged into the five defaults
    assert config.flight.height_m == DEFAULT.flight.height_m and config.wind == DEFAULT.wind
    assert named == ("flight.steps",)
    config, named = _load(tmp_path, "[wind]\ngusts = []\n")
    assert config.wind.gusts == () and config.wind.constant == DEFAULT.wind.constant
    assert named == ("wind.gusts",)
    # A list element is built from its own class's defaults.
    config, _ = _load(tmp_path, "[[wind.gusts]]\nstart_s = 2.0\n")
    assert config.wind.gusts == (GustConfig(start_s=2.0),)


def test_merging_into_an_explicit_base() -> None:
    base = dataclasses.replace(DEFAULT, name="base", duration_s=4.0)
    config = from_mapping(ScenarioConfig, {"flight": {"height_m": 1.5}}, "x.toml", base=base)
    assert config.name == "base" and config.duration_s == 4.0 and config.flight.height_m == 1.5
    assert config.flight.steps == DEFAULT.flight.steps


def test_height_moves_follow_the_rate_limits(tmp_path: Path) -> None:
    config, _ = _load(tmp_path, "[flight]\nheight_m = 5.0\n")
    (climb,) = config.flight.height_moves(0.1825)
    # Peak speed π·Δ/(2T) of the half cosine equals the climb rate, 2 m/s: T = π·4.8175/4.
    assert climb.duration_s == pytest.approx(math.pi * 4.8175 / 4)
    # The default 1 m climb keeps its 1.5 s (peak speed 0.86 m/s, acceleration 1.8 m/s²).
    assert DEFAULT.flight.height_moves(0.1825)[0].duration_s == 1.5
    # A height step must wait for the previous move: the 5 m climb ends at 3 + 3.78 s.
    with pytest.raises(ConfigError) as info:
        _load(tmp_path, '[flight]\nheight_m = 5.0\nsteps = [{time_s = 6.0, axis = "height", value = 1.0}]\n')
    assert info.value.field == "flight.steps[0].time_s"
    assert "6.78" in str(info.value)


def test_idle_pwm_is_a_validated_vehicle_field() -> None:
    assert vehicle_preset("default").idle_pwm == 50 and laser_vehicle().idle_pwm == 50
    for bad in (255, -1, True, 50.0):
        with pytest.raises(ConfigError) as info:
            from_mapping(VehicleConfig, {"idle_pwm": bad}, "vehicle.toml")
        assert info.value.field == "idle_pwm"


def test_default_sensor_config_matches_the_reference_table() -> None:
    s = SensorConfig()
    assert s.rate_hz == 100.0 and s.period_steps == 10
    assert s.accel_sigma == (0.35, 0.35, 0.3) and s.gyro_sigma == (0.05, 0.05, 0.015)
    assert (s.accel_bias, s.gyro_bias, s.mag_sigma, s.baro_sigma, s.baro_bias) == (0.1, 0.1, 0.013, 0.1, 10.0)
