"""Running one point of a sweep, in whatever process a worker is (local pool or Dask).

:func:`run_point` never raises: an invalid combination of values, a firmware deadline miss or
any error of the run comes back as a failed :class:`PointResult` with its reason, so one bad
point cannot stop a sweep.  The run folder's files travel back in the result (they are small),
so the worker needs no file system in common with the machine that stores the sweep.
"""

from __future__ import annotations

import dataclasses
import tempfile
import time
import traceback
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from robosoc.config.scenario import ScenarioConfig
from robosoc.config.sweep import point_scenario
from robosoc.config.validate import ConfigError
from robosoc.sweep.plan import Point

OK = "ok"
FAILED = "failed"


@dataclass
class PointResult:
    """What a worker sends back for one point."""

    key: str
    status: str
    error: str = ""
    summary: dict[str, Any] | None = None
    files: dict[str, bytes] = field(default_factory=dict)
    worker_s: float = 0.0


def metric(summary: dict[str, Any] | None, name: str) -> Any:
    """The value of a dotted field of a summary (``tasks.pid.response_us_mean``), or None."""
    node: Any = summary
    for part in name.split("."):
        if not isinstance(node, dict) or part not in node:
            return None
        node = node[part]
    return node


def run_point(
    base: ScenarioConfig, point: Point, source: str, base_fields: Sequence[tuple[str, Any]] = ()
) -> PointResult:
    """Fly ``point`` (the base scenario with its values; ``base_fields``, the fields that made the
    base, for a point that flies another project: :func:`robosoc.config.sweep.point_scenario`) and
    return its summary and files."""
    start = time.perf_counter()
    try:
        scenario = point_scenario(base, base_fields, point.assignment, f"{source}: {point.label}")
        scenario = dataclasses.replace(scenario, seed=point.seed)
    except ConfigError as exc:
        return PointResult(point.key, FAILED, f"invalid combination: {exc}", worker_s=time.perf_counter() - start)
    with tempfile.TemporaryDirectory(prefix="robosoc-point-") as tmp:
        folder = Path(tmp)
        try:
            summary = fly_point(scenario, folder)
            status, error = OK, ""
            misses = summary.get("deadline_misses") or 0
            if misses:
                status, error = FAILED, f"{misses} deadline misses"
        except Exception as exc:  # a point's failure is data, not a crash of the sweep
            summary = None
            status = FAILED
            where = traceback.extract_tb(exc.__traceback__)[-1]
            error = f"{type(exc).__name__}: {exc} (at {Path(where.filename).name}:{where.lineno})"
        files = {p.relative_to(folder).as_posix(): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}
    return PointResult(point.key, status, error, summary, files, time.perf_counter() - start)


def fly_point(scenario: ScenarioConfig, folder: Path) -> dict[str, Any]:
    """Fly ``scenario``, writing its run folder into ``folder``; its summary."""
    from robosoc.outputs.flight_session import fly_scenario

    return fly_scenario(scenario, folder, plot=False, logs=False).summary


__all__ = ["FAILED", "OK", "PointResult", "fly_point", "metric", "run_point"]
