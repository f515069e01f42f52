"""The mission of a scenario (``[flight.mission]``) and its position sensor (``[sensors.position]``):
every field typed and checked, errors naming the dotted field, and a resolved scenario written as
TOML loading back equal."""

from __future__ import annotations

import math
import tomllib
from typing import Any

import pytest

from robosoc.config.scenario import MissionPlan, ScenarioConfig, scenario_toml
from robosoc.config.validate import ConfigError, from_mapping

SQUARE = [[2.0, 0.0, 1.0], [2.0, 2.0, 1.0], [0.0, 2.0, 1.0], [0.0, 0.0, 1.0]]


def _load(mission: dict[str, Any], **flight: Any) -> ScenarioConfig:
    return from_mapping(ScenarioConfig, {"flight": {"steps": [], **flight, "mission": mission}}, "m.toml")


def test_a_mission_loads_with_its_defaults_and_round_trips() -> None:
    scenario = _load({"waypoints": SQUARE, "hold_s": 1})
    mission = scenario.flight.mission
    assert mission == MissionPlan(waypoints=tuple(tuple(w) for w in SQUARE), hold_s=1.0)  # type: ignore[misc]
    assert isinstance(mission.hold_s, float) and mission.land and mission.acceptance_m == 0.3
    text = scenario_toml(scenario)
    assert "[flight.mission]" in text
    assert from_mapping(ScenarioConfig, tomllib.loads(text)) == scenario
    assert ScenarioConfig().flight.mission is None and "[flight.mission]" not in scenario_toml(ScenarioConfig())


@pytest.mark.parametrize(
    ("mission", "field", "reason"),
    [
        ({}, "flight.mission.waypoints", "missing required field"),
        ({"waypoints": []}, "flight.mission.waypoints", "at least one waypoint"),
        ({"waypoints": "square"}, "flight.mission.waypoints", "expected a list"),
        ({"waypoints": [[1.0, 2.0]]}, "flight.mission.waypoints[0]", "expected 3 values, got 2"),
        ({"waypoints": [[1.0, "2", 1.0]]}, "flight.mission.waypoints[0][1]", "expected a number"),
        ({"waypoints": [[1.0, True, 1.0]]}, "flight.mission.waypoints[0][1]", "expected a number"),
        ({"waypoints": [[1.0, 0.0, 1.0], [math.nan, 0.0, 1.0]]}, "flight.mission.waypoints[1]", "x and y must be"),
        ({"waypoints": [[math.inf, 0.0, 1.0]]}, "flight.mission.waypoints[0]", "x and y must be finite"),
        ({"waypoints": [[101.0, 0.0, 1.0]]}, "flight.mission.waypoints[0]", "within ±100 m"),
        ({"waypoints": [[1.0, 0.0, 0.1]]}, "flight.mission.waypoints[0]", "z must be a height in [0.3, 5] m"),
        ({"waypoints": [[1.0, 0.0, math.nan]]}, "flight.mission.waypoints[0]", "z must be a height"),
        ({"waypoints": [[0.0, 0.0, 1.0]] * 101}, "flight.mission.waypoints", "at most 100 waypoints"),
        ({"waypoints": SQUARE, "hold_s": -1.0}, "flight.mission.hold_s", "must be >= 0"),
        ({"waypoints": SQUARE, "hold_s": math.inf}, "flight.mission.hold_s", "must be >= 0"),
        ({"waypoints": SQUARE, "hold_s": "2"}, "flight.mission.hold_s", "expected a number"),
        ({"waypoints": SQUARE, "acceptance_m": 0.0}, "flight.mission.acceptance_m", "must be positive"),
        ({"waypoints": SQUARE, "acceptance_m": math.nan}, "flight.mission.acceptance_m", "must be positive"),
        ({"waypoints": SQUARE, "speed_mps": 0.0}, "flight.mission.speed_mps", "must be positive"),
        ({"waypoints": SQUARE, "speed_mps": 50.0}, "flight.mission.speed_mps", "must be in [0.1, 10]"),
        ({"waypoints": SQUARE, "land": "yes"}, "flight.mission.land", "expected true or false"),
        ({"waypoints": SQUARE, "land_settle_s": -0.5}, "flight.mission.land_settle_s", "must be >= 0"),
        ({"waypoints": SQUARE, "colour": "red"}, "flight.mission.colour", "unknown field"),
    ],
)
def test_a_wrong_mission_names_the_field(mission: dict[str, Any], field: str, reason: str) -> None:
    with pytest.raises(ConfigError) as caught:
        _load(mission)
    assert caught.value.where == "m.toml"
    assert caught.value.field == field and reason in caught.value.reason, caught.value


def test_a_mission_with_setpoint_steps_is_refused() -> None:
    with pytest.raises(ConfigError) as caught:
        from_mapping(ScenarioConfig, {"flight": {"mission": {"waypoints": SQUARE}}}, "m.toml")
    assert caught.value.field == "flight.steps" and "must be empty in a flight with a mission" in caught.value.reason
    with pytest.raises(ConfigError, match="expected a table"):
        from_mapping(ScenarioConfig, {"flight": {"steps": [], "mission": [1, 2]}}, "m.toml")


@pytest.mark.parametrize(
    ("position", "field", "reason"),
    [
        ({"enabled": "yes"}, "sensors.position.enabled", "expected true or false"),
        ({"rate_hz": 0.0}, "sensors.position.rate_hz", "must be in [0.1, 1000]"),
        ({"position_sigma": -0.1}, "sensors.position.position_sigma", "must be in [0, 100]"),
        ({"velocity_sigma": math.nan}, "sensors.position.velocity_sigma", "finite"),
        ({"enabled": True, "rate_hz": 30.0}, "sensors.position.rate_hz", "must divide the sensor rate (100 Hz)"),
        ({"enabled": True, "rate_hz": 200.0}, "sensors.position.rate_hz", "must divide the sensor rate"),
        ({"gps": True}, "sensors.position.gps", "unknown field"),
    ],
)
def test_a_wrong_position_sensor_names_the_field(position: dict[str, Any], field: str, reason: str) -> None:
    with pytest.raises(ConfigError) as caught:
        from_mapping(ScenarioConfig, {"sensors": {"position": position}}, "m.toml")
    assert caught.value.field == field and reason in caught.value.reason, caught.value


def test_the_position_sensor_is_off_by_default_and_its_rate_divides_the_sensor_rate() -> None:
    assert not ScenarioConfig().sensors.position.enabled
    on = from_mapping(ScenarioConfig, {"sensors": {"rate_hz": 200.0, "position": {"enabled": True, "rate_hz": 20}}})
    assert on.sensors.position_every == 10
