"""Sweep files: a base scenario, the fields to vary, the seeds and the metrics to keep.

A sweep file is TOML::

    name = "builds"                      # names the output folder (default: the file's stem)
    scenario = "base.toml"               # optional base scenario, relative to this file
    seeds = [1, 2, 3]                    # every point is flown once per seed (default [1])
    metrics = [                          # dotted fields of each run's summary.json to tabulate
        "tasks.estimator.response_us_mean",
        "tasks.estimator.energy_nj_mean",
        "flight.hover_rms_m",
    ]

    [base]                               # optional changes to the base scenario, any field
    duration_s = 5.0

    [grid]                               # every combination of these lists (a Cartesian product)
    "firmware.arith" = ["fixed", "float"]
    firmware.multiplier = [true, false]  # unquoted dotted keys are the same field

    [[points]]                           # and/or listed points, each a set of field values
    "chip.width" = 3

Field names are the scenario's (``robosoc scenario show``), dotted; a name that is not a field
is an error naming the sweep file and the key.  Each grid value is checked alone against the
base scenario before anything runs, and each listed point as a whole (with a grid: valid with
at least one grid combination), so a wrong type or an out-of-range value stops the sweep at
once; a *combination* that is invalid (a task mapped outside a smaller mesh, say) is a failed
point, recorded with its reason, and the sweep goes on.

When both ``grid`` and ``points`` are given, every listed point is combined with every grid
combination (the listed values win where both set a field).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from robosoc.config.dotted import flatten, nest
from robosoc.config.firmware import FirmwareConfig
from robosoc.config.project_scenario import PROJECT_FIELD, project_beside, scenario_from_fields
from robosoc.config.ranges import check_seed
from robosoc.config.scenario import ScenarioConfig
from robosoc.config.scenario_fields import SEED_FIELD, field_names
from robosoc.config.scenario_fields import check_field as check_scenario_field
from robosoc.config.validate import ConfigError, from_mapping, read_toml_mapping

MAX_POINTS = 100_000
"""Largest sweep (points × seeds): a guard against a grid typed with one list too many."""

Value = bool | int | float | str | list[Any]
Assignment = tuple[tuple[str, Value], ...]
"""One point's field values: (dotted name, value) pairs in the file's order."""


def check_field(name: str, where: str, key: str) -> None:
    """Raise :class:`ConfigError` unless ``name`` is a dotted field of the scenario a sweep may vary."""
    if name == SEED_FIELD:
        raise ConfigError(where, key, "vary the seed with seeds = [...] at the top of the sweep file")
    check_scenario_field(name, where, key, "vary")


def point_scenario(
    base: ScenarioConfig, base_fields: Sequence[tuple[str, Any]], assignment: Sequence[tuple[str, Any]], where: str
) -> ScenarioConfig:
    """The scenario of one point: ``base`` with the point's values; a point that flies another
    project than the base's starts from that project's defaults under the base's fields
    (``base_fields``, the scenario file's and ``[base]``'s: :mod:`robosoc.config.project_scenario`).

    Raises:
        ConfigError: a value is wrong (``where`` named) or the point's project is (its file named).
    """
    project = dict(assignment).get(PROJECT_FIELD)
    if project is not None and project != base.firmware.project:
        base = scenario_from_fields({**dict(base_fields), PROJECT_FIELD: project}, where)
    return from_mapping(ScenarioConfig, nest(assignment), where, base=base)


@dataclass(frozen=True)
class SweepConfig:
    """A validated sweep file (see the module docstring)."""

    name: str
    base: ScenarioConfig
    base_fields: tuple[tuple[str, Any], ...]
    """The dotted fields the base scenario file and ``[base]`` set (for the record)."""
    grid: tuple[tuple[str, tuple[Value, ...]], ...]
    points: tuple[Assignment, ...]
    seeds: tuple[int, ...]
    metrics: tuple[str, ...]
    source: str

    def point_count(self) -> int:
        """How many points :meth:`assignments` gives, computed without building them."""
        return math.prod(len(values) for _, values in self.grid) * max(1, len(self.points))

    def assignments(self) -> list[Assignment]:
        """Every point's field values, grid order first (the last grid field varies fastest)."""
        combos: list[Assignment] = [()]
        for name, values in self.grid:
            combos = [(*combo, (name, value)) for combo in combos for value in values]
        listed = self.points or ((),)
        merged = []
        for point in listed:
            names = {name for name, _ in point}
            for combo in combos:
                merged.append(tuple((n, v) for n, v in combo if n not in names) + point)
        return merged

    def varied(self) -> list[str]:
        """The dotted fields that vary across points, in the file's order."""
        names = [name for name, _ in self.grid]
        for point in self.points:
            names.extend(name for name, _ in point if name not in names)
        return names

    def scenario(self, assignment: Assignment, where: str = "") -> ScenarioConfig:
        """The base scenario with one point's values (raises :class:`ConfigError` if invalid)."""
        return point_scenario(self.base, self.base_fields, assignment, where or self.source)


def _list_of(value: Any, where: str, key: str, kind: type, what: str) -> list[Any]:
    if not isinstance(value, list) or not value:
        raise ConfigError(where, key, f"expected a non-empty list of {what}, got {value!r}")
    for i, item in enumerate(value):
        if (isinstance(item, bool) and kind is not bool) or not isinstance(item, kind):
            raise ConfigError(where, f"{key}[{i}]", f"expected {what}, got {item!r}")
    return value


def _check_point(
    point: dict[str, Any],
    grid: list[tuple[str, tuple[Value, ...]]],
    base: ScenarioConfig,
    base_fields: Sequence[tuple[str, Any]],
    where: str,
) -> None:
    """Check a listed point's values before anything runs, as the grid's are: the point as a whole
    (its values are meant together: ``chip.width = 4`` with a task on tile 3,0) against the base
    scenario.  If it is invalid there but a grid is given, it must be valid with at least one grid
    combination (the others are failed points, recorded); raises :class:`ConfigError` otherwise."""
    try:
        point_scenario(base, base_fields, tuple(point.items()), where)
        return
    except ConfigError as alone:
        if not grid:
            raise
        first = alone
    combos: list[dict[str, Any]] = [{}]
    for name, values in grid:  # the grid is at most MAX_POINTS combinations (checked when the plan is made)
        if name in point:  # the point's own value wins
            continue
        combos = [{**c, name: v} for c in combos for v in values]
        if len(combos) > MAX_POINTS:
            raise first
    for combo in combos:
        try:
            point_scenario(base, base_fields, tuple({**combo, **point}.items()), where)
            return
        except ConfigError:
            continue
    raise first


def _absolute_project(flat: dict[str, Any], folder: Path) -> dict[str, Any]:
    """``flat`` with a relative ``firmware.project`` folder made absolute from ``folder`` (the
    sweep or scenario file's), as a scenario file's own is from its folder."""
    return {**flat, PROJECT_FIELD: project_beside(flat[PROJECT_FIELD], folder)} if PROJECT_FIELD in flat else flat


def sweep_from_mapping(data: dict[str, Any], where: str, folder: Path, default_name: str) -> SweepConfig:
    """Validate a parsed sweep file (``folder`` resolves a relative ``scenario`` path)."""
    known = {"name", "scenario", "seeds", "metrics", "base", "grid", "points"}
    unknown = sorted(set(data) - known)
    if unknown:
        raise ConfigError(where, unknown[0], f"unknown field (known: {', '.join(sorted(known))})")
    name = data.get("name", default_name)
    if not isinstance(name, str) or not name or not all(c.isalnum() or c in "-_." for c in name):
        raise ConfigError(where, "name", f"expected a name of letters, digits, '-', '_' or '.', got {name!r}")

    base_data: dict[str, Any] = {}
    if "scenario" in data:
        path = data["scenario"]
        if not isinstance(path, str):
            raise ConfigError(where, "scenario", f"expected a file name, got {path!r}")
        scenario_path = folder / path
        scenario_flat = flatten(read_toml_mapping(scenario_path, "scenario TOML file"))
        scenario_flat = _absolute_project(scenario_flat, scenario_path.parent)
        base = scenario_from_fields(scenario_flat, str(scenario_path))
        base_data = scenario_flat
    else:
        base = ScenarioConfig()
    changes = data.get("base", {})
    if not isinstance(changes, dict):
        raise ConfigError(where, "base", f"expected a table of scenario fields, got {changes!r}")
    flat_changes = _absolute_project(flatten(changes), folder)  # quoted dotted keys as nested tables
    for key in flat_changes:
        check_field(key, where, f"base.{key}")
    base = point_scenario(base, tuple(base_data.items()), tuple(flat_changes.items()), f"{where}: [base]")
    base_data.update(flat_changes)

    grid_table = data.get("grid", {})
    if not isinstance(grid_table, dict):
        raise ConfigError(where, "grid", f"expected a table of field = [values], got {grid_table!r}")
    grid = []
    for key, values in flatten(grid_table).items():
        check_field(key, where, f"grid.{key}")
        if not isinstance(values, list) or not values:
            raise ConfigError(where, f"grid.{key}", f"expected a non-empty list of values, got {values!r}")
        values = [_absolute_project({key: v}, folder)[key] for v in values]
        for i, value in enumerate(values):
            point_scenario(base, tuple(base_data.items()), ((key, value),), f"{where}: grid.{key}[{i}]")
        grid.append((key, tuple(values)))

    raw_points = data.get("points", [])
    if not isinstance(raw_points, list) or not all(isinstance(p, dict) for p in raw_points):
        raise ConfigError(where, "points", "expected [[points]] tables of field = value")
    points = []
    for i, point in enumerate(raw_points):
        flat = _absolute_project(flatten(point), folder)
        if not flat:
            raise ConfigError(where, f"points[{i}]", "an empty point: name at least one field")
        for key in flat:
            check_field(key, where, f"points[{i}].{key}")
        _check_point(flat, grid, base, tuple(base_data.items()), f"{where}: points[{i}]")
        points.append(tuple(flat.items()))

    seeds = tuple(_list_of(data.get("seeds", [1]), where, "seeds", int, "seeds (integers)"))
    for i, seed in enumerate(seeds):
        try:
            check_seed(f"seeds[{i}]", seed)
        except ValueError as exc:
            field, _, reason = str(exc).partition(": ")
            raise ConfigError(where, field, reason) from exc
    if len(set(seeds)) != len(seeds):
        raise ConfigError(where, "seeds", f"a seed is listed twice: {list(seeds)}")
    defaults = list(default_metrics(base, grid, points))
    metrics = tuple(_list_of(data.get("metrics", defaults), where, "metrics", str, "dotted names"))
    if len(set(metrics)) != len(metrics):
        raise ConfigError(where, "metrics", f"a metric is listed twice: {list(metrics)}")

    config = SweepConfig(name, base, tuple(base_data.items()), tuple(grid), tuple(points), seeds, metrics, where)
    total = config.point_count() * len(seeds)  # counted, not built: a grid of 10**10 points never exists
    if total > MAX_POINTS:
        sizes = " × ".join([*(str(len(values)) for _, values in grid), *([str(len(points))] if points else [])])
        raise ConfigError(where, "grid", f"{total} runs ({sizes} points × {len(seeds)} seeds), more than {MAX_POINTS}")
    return config


TASK_METRICS = ("response_us_mean", "response_us_max", "energy_nj_mean")
"""Per-task metrics kept when a sweep file names none: ``tasks.<task>.<metric>`` for each task."""
DEFAULT_METRICS = ("deadline_misses", "flight.hover_rms_m", "energy.total_uj", "real_time_factor")
"""Metrics kept when a sweep file names none, after the per-task ones: flight quality and cost."""


def default_metrics(
    base: ScenarioConfig, grid: Sequence[tuple[str, Sequence[Any]]], points: Sequence[Sequence[tuple[str, Any]]]
) -> tuple[str, ...]:
    """The metrics of a sweep file that names none: :data:`TASK_METRICS` of every task of the
    firmware projects its points fly (each project a grid value or point names, and the base's if a
    point keeps it; their tasks in file order), then :data:`DEFAULT_METRICS`."""
    varied = any(key == PROJECT_FIELD for key, _ in grid)
    every_point = bool(points) and all(any(key == PROJECT_FIELD for key, _ in point) for point in points)
    folders = [] if varied or every_point else [base.firmware.project]  # the base's, if a point flies it
    folders += [str(v) for key, values in grid if key == PROJECT_FIELD for v in values]
    folders += [str(v) for point in points for key, v in point if key == PROJECT_FIELD]
    tasks: dict[str, None] = {}
    for folder in dict.fromkeys(folders):
        try:
            tasks.update(dict.fromkeys(FirmwareConfig(project=folder).load_project().task_names))
        except ValueError:  # a project that is not there: its points fail when they run, and say why
            continue
    return (*(f"tasks.{t}.{m}" for t in tasks for m in TASK_METRICS), *DEFAULT_METRICS)


def load_sweep(path: str | Path) -> SweepConfig:
    """Read and validate a sweep file.

    Raises:
        ConfigError: naming the file and the field (or the file's problem).
    """
    path = Path(path)
    data = read_toml_mapping(path, "sweep TOML file")
    return sweep_from_mapping(data, str(path), path.parent, path.stem)


__all__ = [
    "DEFAULT_METRICS",
    "MAX_POINTS",
    "TASK_METRICS",
    "SweepConfig",
    "check_field",
    "default_metrics",
    "field_names",
    "flatten",
    "load_sweep",
    "nest",
    "sweep_from_mapping",
]
