"""Sweep files: expansion of grids and listed points, dotted-name validation, stable point keys."""

from __future__ import annotations

import itertools
import math
from pathlib import Path

import pytest

from robosoc.config.scenario import ScenarioConfig
from robosoc.config.sweep import field_names, flatten, load_sweep, nest
from robosoc.config.validate import ConfigError
from robosoc.sweep.plan import plan, point_key
from robosoc.sweep.plots import pareto_front


def write(tmp_path: Path, text: str, name: str = "s.toml") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def test_grid_is_the_cartesian_product_in_file_order(tmp_path):
    path = write(
        tmp_path,
        """
seeds = [3, 4]
[grid]
duration_s = [1.0, 2.0, 3.0]
sensors.noise = [true, false]
""",
    )
    config = load_sweep(path)
    points = plan(config)
    expected = [
        ((("duration_s", d), ("sensors.noise", n)), s)
        for d, n in itertools.product([1.0, 2.0, 3.0], [True, False])
        for s in (3, 4)
    ]
    assert [(p.assignment, p.seed) for p in points] == expected
    assert [p.index for p in points] == list(range(12))
    assert config.varied() == ["duration_s", "sensors.noise"]
    # each point's scenario carries its values, everything else the defaults
    scenario = config.scenario(points[3].assignment)
    assert scenario.duration_s == 1.0 and scenario.sensors.noise is False  # (1.0, false) with seed 4
    assert scenario.wind == ScenarioConfig().wind


def test_points_combine_with_the_grid_and_win_where_both_set_a_field(tmp_path):
    path = write(
        tmp_path,
        """
[grid]
duration_s = [1.0, 2.0]
[[points]]
"sensors.rate_hz" = 50.0
[[points]]
"sensors.rate_hz" = 200.0
duration_s = 5.0
""",
    )
    assignments = load_sweep(path).assignments()
    assert assignments == [
        (("duration_s", 1.0), ("sensors.rate_hz", 50.0)),
        (("duration_s", 2.0), ("sensors.rate_hz", 50.0)),
        (("sensors.rate_hz", 200.0), ("duration_s", 5.0)),
        (("sensors.rate_hz", 200.0), ("duration_s", 5.0)),
    ]
    with pytest.raises(ConfigError, match="two points are the same run"):
        plan(load_sweep(path))


def test_listed_points_alone(tmp_path):
    path = write(tmp_path, '[[points]]\nvehicle = "laser"\n[[points]]\nvehicle = "default"\n')
    points = plan(load_sweep(path))
    assert [p.assignment for p in points] == [(("vehicle", "laser"),), (("vehicle", "default"),)]
    assert [p.seed for p in points] == [1, 1]


@pytest.mark.parametrize(
    ("text", "field", "reason"),
    [
        ("[grid]\nduraton_s = [1.0]\n", "grid.duraton_s", "'duraton_s' is not a scenario field"),
        ("[grid]\nsensors.rate = [1.0]\n", "grid.sensors.rate", "sensors has: "),
        ('[grid]\n"duration_s.x" = [1.0]\n', "grid.duration_s.x", "not a table"),
        ("[grid]\nsensors = [1.0]\n", "grid.sensors", "is a table"),
        ("[grid]\nduration_s = []\n", "grid.duration_s", "non-empty list"),
        ("[grid]\nduration_s = 1.0\n", "grid.duration_s", "non-empty list"),
        ('[grid]\nduration_s = [1.0, "x"]\n', "grid.duration_s[1]: duration_s", "expected a number"),
        ("[grid]\nduration_s = [-1.0]\n", "grid.duration_s[0]", "duration_s"),
        ("[[points]]\nwnd.constant = [1.0, 0.0, 0.0]\n", "points[0].wnd.constant", "not a scenario field"),
        ("[[points]]\n", "points[0]", "empty point"),
        ("seeds = []\n", "seeds", "non-empty list"),
        ("seeds = [1, true]\n", "seeds[1]", "expected seeds"),
        ("seeds = [-3]\n", "seeds[0]", ""),
        ("seeds = [1, 1]\n", "seeds", "listed twice"),
        ("metrics = [1]\n", "metrics[0]", "expected dotted names"),
        ("gird = {}\n", "gird", "unknown field"),
        ('name = "a b"\n', "name", "letters, digits"),
        ('scenario = "missing.toml"\n', "", "file not found"),
        ('[base]\nduration_s = "long"\n', "duration_s", "expected a number"),
    ],
)
def test_bad_sweep_files_name_file_and_field(tmp_path, text, field, reason):
    path = write(tmp_path, text)
    with pytest.raises(ConfigError) as info:
        plan(load_sweep(path))
    message = str(info.value)
    assert message.startswith(str(tmp_path)), message
    assert field in message and reason in message, message


def test_invalid_combination_is_not_refused_up_front(tmp_path):
    # each value alone is valid; together they may not be: that is a failed point, not a bad file
    # (4 ms is one sample at the base's 250 Hz, none at 100 Hz)
    text = '[base.sensors]\nrate_hz = 250.0\n[grid]\nduration_s = [0.004, 1.0]\n"sensors.rate_hz" = [100.0]\n'
    path = write(tmp_path, text)
    assert len(plan(load_sweep(path))) == 2


def test_base_scenario_file_and_base_table(tmp_path):
    write(tmp_path, 'name = "windy"\nduration_s = 4.0\n[wind]\ngust_sigma = 0.5\n', "base.toml")
    path = write(tmp_path, 'scenario = "base.toml"\n[base]\nduration_s = 2.0\n[grid]\nseeds_unused = []\n')
    with pytest.raises(ConfigError, match="seeds_unused"):
        load_sweep(path)
    path = write(tmp_path, 'scenario = "base.toml"\n[base]\nduration_s = 2.0\n[grid]\n"wind.gust_sigma" = [0.0, 1.0]\n')
    config = load_sweep(path)
    assert config.base.name == "windy" and config.base.duration_s == 2.0 and config.base.wind.gust_sigma == 0.5
    assert config.scenario(plan(config)[1].assignment).wind.gust_sigma == 1.0


def test_point_keys_are_stable_and_depend_on_everything_that_decides_a_run(tmp_path):
    base = ScenarioConfig()
    key = point_key(base, (("duration_s", 1.0),), 1)
    assert key == point_key(ScenarioConfig(), (("duration_s", 1.0),), 1)
    assert len(key) == 16 and int(key, 16) >= 0
    others = {
        point_key(base, (("duration_s", 2.0),), 1),
        point_key(base, (("duration_s", 1.0),), 2),
        point_key(ScenarioConfig(duration_s=5.0), (("duration_s", 1.0),), 1),
    }
    assert key not in others and len(others) == 3
    # the same sweep read twice plans the same keys; editing the grid keeps the keys of points kept
    one = plan(load_sweep(write(tmp_path, "[grid]\nduration_s = [1.0, 2.0]\n")))
    two = plan(load_sweep(write(tmp_path, "[grid]\nduration_s = [2.0, 3.0, 1.0]\n", "t.toml")))
    assert {p.key for p in one} < {p.key for p in two}


def test_flatten_and_nest_are_inverse():
    tree = {"a": 1, "b": {"c": [1, 2], "d": {"e": "x"}}}
    assert flatten(tree) == {"a": 1, "b.c": [1, 2], "b.d.e": "x"}
    assert nest(flatten(tree)) == tree


def test_field_names_cover_the_scenario():
    names = field_names()
    assert "duration_s" in names and "sensors.rate_hz" in names and "wind.gust_sigma" in names
    assert "sensors" not in names


@pytest.mark.parametrize(
    ("costs", "front"),
    [
        ([(1, 5), (2, 3), (3, 4), (4, 1)], [0, 1, 3]),  # (3, 4) is beaten by (2, 3)
        ([(1, 1), (1, 1), (2, 2)], [0, 1]),  # equal points are both on the front
        ([(1, 2), (1, 3)], [0]),  # same time, more energy: dominated
        ([(1, 2), (3, 2)], [0]),  # same energy, slower: dominated
        ([(math.nan, 1), (2, 2)], [1]),
        ([], []),
    ],
)
def test_pareto_front(costs, front):
    assert pareto_front([(float(x), float(y)) for x, y in costs]) == front


def test_the_shipped_estimator_clock_sweep_plans_its_five_clocks() -> None:
    """docs/sweeps/estimator-clock.toml (docs/power.md, "Per-tile clock"): five points, the estimator's
    tile at 4..64 ns, every other tile at the chip's clock; each point's chip is valid."""
    path = Path(__file__).parents[2] / "docs" / "sweeps" / "estimator-clock.toml"
    config = load_sweep(path)
    chips = [config.scenario(p.assignment).chip for p in plan(config)]
    assert [chip.tile_config((0, 1)).clock_period_ns for chip in chips] == [4.0, 8.0, 16.0, 32.0, 64.0]
    assert [chip.tile_volts((0, 1)) for chip in chips] == [1.0, 0.8, 0.7, 0.7, 0.7]
    assert all(chip.tile_divider((1, 0)) == 1 and chip.tile.clock_period_ns == 4.0 for chip in chips)
