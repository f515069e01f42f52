"""Vehicle and scenario configs: presets, TOML loading, and rejection naming the field."""

from pathlib import Path

import pytest

from robosoc.config.scenario import ScenarioConfig, SensorConfig
from robosoc.config.validate import ConfigError, from_mapping, load_toml
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


def test_a_scenario_file_overrides_defaults(tmp_path: Path) -> None:
    path = tmp_path / "s.toml"
    path.write_text(
        'name = "gusty"\nduration_s = 6.0\nvehicle = "laser"\n'
        "[sensors]\nrate_hz = 200.0\nnoise = false\n"
        "[wind]\nconstant = [1.0, 0.0, 0.0]\n"
        '[flight]\ntakeoff_s = 2.0\n[[flight.steps]]\ntime_s = 4.0\naxis = "yaw"\nvalue = -20.0\n'
    )
    config = load_toml(ScenarioConfig, path)
    assert config.name == "gusty" and config.vehicle == "laser"
    assert config.sensors.period_steps == 5 and not config.sensors.noise
    assert config.wind.constant == (1.0, 0.0, 0.0) and config.wind.gusts == ()
    assert config.flight.takeoff_s == 2.0 and config.flight.steps[0].value == -20.0


def test_default_sensor_config_matches_the_reference_table() -> None:
    s = SensorConfig()
    assert s.rate_hz == 100.0 and s.period_steps == 10
    assert s.accel_sigma == (0.35, 0.35, 0.3) and s.gyro_sigma == (0.05, 0.05, 0.015)
    assert (s.accel_bias, s.gyro_bias, s.mag_sigma, s.baro_sigma, s.baro_bias) == (0.1, 0.1, 0.013, 0.1, 10.0)
