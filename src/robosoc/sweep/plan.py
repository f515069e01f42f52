"""A sweep's points: every assignment of the sweep file, once per seed, each with a stable key.

A point's key is a hash of everything that decides its result: the resolved base scenario, the
point's field values and the seed.  The same point in a later run of the same (or an edited)
sweep file has the same key, which is how a re-run finds the points already done.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
from dataclasses import dataclass
from typing import Any

from robosoc.config.scenario import ScenarioConfig
from robosoc.config.sweep import Assignment, SweepConfig, nest
from robosoc.config.validate import ConfigError

KEY_DIGITS = 16
"""Hex digits of a point's key (64 bits: collisions are not a concern for any real sweep)."""


@dataclass(frozen=True)
class Point:
    """One run of a sweep: the base scenario with ``assignment`` applied, flown with ``seed``."""

    index: int
    key: str
    assignment: Assignment
    seed: int

    @property
    def label(self) -> str:
        """``firmware.arith=fixed, seed=1``: how progress and errors name the point."""
        values = [f"{name}={json.dumps(value)}" for name, value in self.assignment]
        return ", ".join([*values, f"seed={self.seed}"])

    def changes(self) -> dict[str, Any]:
        """The point's values as nested tables, for :func:`robosoc.config.validate.from_mapping`."""
        return nest(self.assignment)


def _canonical(value: Any) -> Any:
    """JSON-able form of a scenario (tuples as lists, nested dataclasses as tables)."""
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {f.name: _canonical(getattr(value, f.name)) for f in dataclasses.fields(value)}
    if isinstance(value, list | tuple):
        return [_canonical(v) for v in value]
    return value


def point_key(base: ScenarioConfig, assignment: Assignment, seed: int) -> str:
    """The stable key of a point (see the module docstring)."""
    text = json.dumps(
        {"base": _canonical(base), "set": [[n, v] for n, v in assignment], "seed": seed},
        sort_keys=True,
        separators=(",", ":"),
    )
    return hashlib.sha256(text.encode()).hexdigest()[:KEY_DIGITS]


def check_metrics(config: SweepConfig) -> None:
    """Raise :class:`ConfigError` (naming ``metrics[i]`` and the fields where the name went wrong)
    for a metric that is not a number of ``summary.json``: it would be an empty column."""
    from robosoc.outputs.run_summary import metric_error  # the summary's shape, in one place

    for i, metric in enumerate(config.metrics):
        reason = metric_error(metric)
        if reason is not None:
            raise ConfigError(config.source, f"metrics[{i}]", reason)


def plan(config: SweepConfig) -> list[Point]:
    """The sweep's points: assignments in file order, each with every seed.

    Raises:
        ConfigError: two points are the same run, or a metric is not in ``summary.json`` (:func:`check_metrics`).
    """
    check_metrics(config)
    points: list[Point] = []
    seen: dict[str, Point] = {}
    for assignment in config.assignments():
        for seed in config.seeds:
            point = Point(len(points), point_key(config.base, assignment, seed), assignment, seed)
            if point.key in seen:
                raise ConfigError(
                    config.source, "points", f"two points are the same run ({seen[point.key].label}): list it once"
                )
            seen[point.key] = point
            points.append(point)
    return points


__all__ = ["KEY_DIGITS", "Point", "check_metrics", "plan", "point_key"]
