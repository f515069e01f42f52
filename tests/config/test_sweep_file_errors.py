"""Every refusal of a sweep file, message for message, and the defaults a minimal sweep file gets.

The messages are what a user reads when a sweep does not start: each must name the file, the key
as written in the file (``grid.duration_s``, ``points[1].chip.bogus``, ``seeds[0]``) and the reason.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from robosoc.config.sweep import DEFAULT_METRICS, MAX_POINTS, TASK_METRICS, load_sweep
from robosoc.config.validate import ConfigError

SCENARIO_FIELDS = "chip, controller, duration_s, firmware, flight, name, power, seed, sensors, vehicle, vehicles, wind"


def refusal(tmp_path: Path, text: str) -> tuple[str, str]:
    """(file, message) of the error loading a sweep file holding ``text``."""
    path = tmp_path / "s.toml"
    path.write_text(text)
    with pytest.raises(ConfigError) as info:
        load_sweep(path)
    return str(path), str(info.value)


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("bogus = 1\n", "bogus: unknown field (known: base, grid, metrics, name, points, scenario, seeds)"),
        ('name = "a b"\n', "name: expected a name of letters, digits, '-', '_' or '.', got 'a b'"),
        ('name = ""\n', "name: expected a name of letters, digits, '-', '_' or '.', got ''"),
        ("name = 5\n", "name: expected a name of letters, digits, '-', '_' or '.', got 5"),
        ("scenario = 3\n", "scenario: expected a file name, got 3"),
        ("base = 3\n", "base: expected a table of scenario fields, got 3"),
        (
            "[base]\nbogus = 1\n",
            f"base.bogus: 'bogus' is not a scenario field (the scenario has: {SCENARIO_FIELDS})",
        ),
        ("grid = 3\n", "grid: expected a table of field = [values], got 3"),
        ("[grid]\nduration_s = 1.0\n", "grid.duration_s: expected a non-empty list of values, got 1.0"),
        ("[grid]\nduration_s = []\n", "grid.duration_s: expected a non-empty list of values, got []"),
        (
            "[grid]\nseed = [1, 2]\n",
            "grid.seed: vary the seed with seeds = [...] at the top of the sweep file",
        ),
        (
            "[grid]\nchip = [1]\n",
            "grid.chip: 'chip' is a table; vary one of its fields (width, height, io_tile, powered_off, "
            "tile.multiplier, tile.sram_bytes, tile.clock_period_ns, tiles, noc.buffer_depth, noc.flit_bits, "
            "noc.max_packet_flits, noc.routing_latency, noc.arbiter, noc.clock_gating, noc.gate_after_cycles, "
            "noc.wake_cycles, noc.power_off_unused_routers, errata, engine, dvfs.points, dvfs.reference_v)",
        ),
        (
            '[grid]\n"chip.bogus" = [1]\n',
            "grid.chip.bogus: 'chip.bogus' is not a scenario field (chip has: dvfs, engine, errata, height, io_tile, "
            "noc, powered_off, tile, tiles, width)",
        ),
        (
            '[grid]\n"duration_s.x" = [1]\n',
            "grid.duration_s.x: 'duration_s.x' is not a scenario field (duration_s has: none: it is not a table)",
        ),
        ("points = 3\n", "points: expected [[points]] tables of field = value"),
        ("points = [1, 2]\n", "points: expected [[points]] tables of field = value"),
        ("points = [{}]\n", "points[0]: an empty point: name at least one field"),
        (
            '[[points]]\nduration_s = 2.0\n[[points]]\n"chip.bogus" = 1\n',
            "points[1].chip.bogus: 'chip.bogus' is not a scenario field (chip has: dvfs, engine, errata, height, "
            "io_tile, noc, powered_off, tile, tiles, width)",
        ),
        ("seeds = 1\n", "seeds: expected a non-empty list of seeds (integers), got 1"),
        ("seeds = []\n", "seeds: expected a non-empty list of seeds (integers), got []"),
        ("seeds = [1, true]\n", "seeds[1]: expected seeds (integers), got True"),
        ("seeds = [1, 2.0]\n", "seeds[1]: expected seeds (integers), got 2.0"),
        ("seeds = [-1]\n", "seeds[0]: must be between 0 and 2**63-1, got -1"),
        ("seeds = [4, 5, 4]\n", "seeds: a seed is listed twice: [4, 5, 4]"),
        ('metrics = ["a", 3]\n', "metrics[1]: expected dotted names, got 3"),
    ],
)
def test_a_bad_sweep_file_is_refused_naming_the_file_the_key_and_the_reason(tmp_path, text, message):
    path, got = refusal(tmp_path, text)
    assert got == f"{path}: {message}"


def test_a_grid_value_is_checked_alone_and_named_by_its_index(tmp_path):
    path, got = refusal(tmp_path, "[grid]\nduration_s = [1.0, -2.0]\n")
    assert got == f"{path}: grid.duration_s[1]: duration_s: must be in (0, 3600] s, got -2.0"


def test_a_grid_value_is_checked_against_the_base_not_the_defaults(tmp_path):
    """The default mesh is 2x2: tile [3, 0] exists only on the 4x2 mesh the base sets.

    (The base's keys are quoted dotted names, as the grid's may be.)
    """
    path = tmp_path / "s.toml"
    moves = '[[{task = "estimator", tile = [3, 0]}], [{task = "estimator", tile = [1, 0]}]]'
    path.write_text(f'[base]\n"chip.width" = 4\n"chip.height" = 2\n[grid]\n"firmware.placement" = {moves}\n')
    config = load_sweep(path)
    assert config.base.chip.width == 4
    assert config.grid == (
        ("firmware.placement", ([{"task": "estimator", "tile": [3, 0]}], [{"task": "estimator", "tile": [1, 0]}])),
    )
    assert config.scenario(config.assignments()[0]).firmware.mapping == {"estimator": (3, 0)}


def test_the_base_scenario_file_is_read_and_its_errors_name_it(tmp_path):
    (tmp_path / "base.toml").write_text("duration_s = 4.0\n")
    path = tmp_path / "s.toml"
    path.write_text('scenario = "base.toml"\n[base]\nvehicles = 2\n')
    config = load_sweep(path)
    assert config.base.duration_s == 4.0 and config.base.vehicles == 2
    assert config.base_fields == (("duration_s", 4.0), ("vehicles", 2))

    (tmp_path / "base.toml").write_text("duration_s = -4.0\n")
    with pytest.raises(ConfigError) as info:
        load_sweep(path)
    assert str(info.value) == f"{tmp_path / 'base.toml'}: duration_s: must be in (0, 3600] s, got -4.0"

    (tmp_path / "base.toml").unlink()
    (tmp_path / "base.toml").mkdir()
    with pytest.raises(ConfigError) as info:
        load_sweep(path)
    assert str(info.value) == f"{tmp_path / 'base.toml'}: <root>: is a folder, expected a scenario TOML file"


def test_a_minimal_sweep_file_gets_its_name_from_the_file_one_seed_and_the_default_metrics(tmp_path):
    path = tmp_path / "hover-test.toml"
    path.write_text("[grid]\nduration_s = [1.0]\n")
    config = load_sweep(path)
    assert config.name == "hover-test"
    assert config.seeds == (1,)
    per_task = tuple(f"tasks.{t}.{m}" for t in ("estimator", "pid") for m in TASK_METRICS)  # the quadrotor's
    assert config.metrics == (*per_task, *DEFAULT_METRICS)
    assert config.source == str(path)
    path.write_text('name = "v1.2_a-b"\nseeds = [7, 0]\nmetrics = ["flight.hover_rms_m"]\n')
    config = load_sweep(path)
    assert (config.name, config.seeds, config.metrics) == ("v1.2_a-b", (7, 0), ("flight.hover_rms_m",))


def test_the_size_guard_allows_exactly_max_points_runs_and_refuses_one_more(tmp_path):
    seeds = list(range(100))
    durations = [0.01 * (i + 1) for i in range(MAX_POINTS // len(seeds))]
    path = tmp_path / "s.toml"
    path.write_text(f"seeds = {seeds}\n[grid]\nduration_s = {durations}\n")
    assert len(load_sweep(path).assignments()) * 100 == MAX_POINTS
    path.write_text(f"seeds = {[*seeds, 100]}\n[grid]\nduration_s = {durations}\n")
    with pytest.raises(ConfigError) as info:
        load_sweep(path)
    assert str(info.value) == f"{path}: grid: {1000 * 101} runs (1000 points × 101 seeds), more than {MAX_POINTS}"
