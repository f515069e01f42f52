"""Plots of a sweep: the Pareto front of energy against response time, and each metric against
each swept field; and the sweep's self-contained HTML page (plots inline as SVG, no network).
"""

from __future__ import annotations

import csv
import html
import io
import json
import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from robosoc.output_files import save_figure
from robosoc.sweep.point import OK, metric

RESPONSE = "tasks.{task}.response_us_mean"
ENERGY = "tasks.{task}.energy_nj_mean"
CHIP_ENERGY = "energy.total_uj"


def pareto_front(costs: Sequence[tuple[float, float]]) -> list[int]:
    """Indices of the points no other point beats in both costs (both minimised), by first cost.

    A point is dominated when another is no worse in both costs and better in one; equal points
    are all on the front.  NaN costs are never on it.
    """
    order = sorted(
        (i for i, (x, y) in enumerate(costs) if not (math.isnan(x) or math.isnan(y))), key=lambda i: costs[i]
    )
    front: list[int] = []
    best_y = math.inf
    last: tuple[float, float] | None = None
    for i in order:
        x, y = costs[i]
        if y < best_y or (last is not None and (x, y) == last):
            front.append(i)
            best_y = min(best_y, y)
            last = (x, y)
    return front


def _number(value: Any) -> float:
    return float(value) if isinstance(value, int | float) and not isinstance(value, bool) else math.nan


def _label(record: dict[str, Any], varied: Sequence[str]) -> str:
    values = record["values"]
    return ", ".join(f"{name.rsplit('.', 1)[-1]}={values.get(name)}" for name in varied) or "base"


def _png(fig, path: Path, dpi: int) -> str:
    """Save ``fig`` as PNG at ``path`` and close it; the PNG as base64 for an inline image."""
    import base64

    data = save_figure(fig, path, dpi=dpi)
    _pyplot().close(fig)
    return base64.b64encode(data).decode("ascii")


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def pareto_figure(records: Sequence[dict[str, Any]], varied: Sequence[str], task: str, *, chip: bool = False):
    """Energy per job (``chip``: the chip's whole energy, :data:`CHIP_ENERGY`) against mean response
    time of ``task``, one marker per point, front joined."""
    plt = _pyplot()
    ok = [r for r in records if r["status"] == OK]
    energy = CHIP_ENERGY if chip else ENERGY.format(task=task)
    costs = [(_number(metric(r["summary"], RESPONSE.format(task=task))), _number(metric(r["summary"], energy)))
             for r in ok]  # fmt: skip
    fig, ax = plt.subplots(figsize=(7, 4.5))
    labels = sorted({_label(r, varied) for r in ok})
    for label in labels:
        xs = [c[0] for c, r in zip(costs, ok, strict=True) if _label(r, varied) == label]
        ys = [c[1] for c, r in zip(costs, ok, strict=True) if _label(r, varied) == label]
        ax.scatter(xs, ys, label=label, s=28)
    front = pareto_front(costs)
    if front:
        ax.plot([costs[i][0] for i in front], [costs[i][1] for i in front], "k--", linewidth=1, label="Pareto front")
    ax.set_xlabel(f"{task}: mean response time [µs]")
    ax.set_ylabel("the chip's energy over the flight [µJ]" if chip else f"{task}: energy per job [nJ]")
    ax.set_title(
        f"the chip's energy against {task}'s response time" if chip else f"{task}: energy against response time"
    )
    ax.grid(alpha=0.3)
    if labels:
        ax.legend(fontsize=7, loc="best")
    fig.tight_layout()
    return fig


def metric_figure(records: Sequence[dict[str, Any]], name: str, field: str):
    """``name`` against the swept ``field``: each point, and the mean over seeds per value."""
    plt = _pyplot()
    ok = [r for r in records if r["status"] == OK]
    values = [r["values"].get(field) for r in ok]
    ys = [_number(metric(r["summary"], name)) for r in ok]
    fig, ax = plt.subplots(figsize=(6, 3.6))
    numeric = all(isinstance(v, int | float) and not isinstance(v, bool) for v in values)
    categories = sorted({str(v) for v in values}) if not numeric else []
    xs = [float(v) for v in values] if numeric else [categories.index(str(v)) for v in values]
    ax.scatter(xs, ys, s=18, alpha=0.7)
    groups: dict[float, list[float]] = {}
    for x, y in zip(xs, ys, strict=True):
        if not math.isnan(y):
            groups.setdefault(x, []).append(y)
    means = sorted((x, sum(v) / len(v)) for x, v in groups.items())
    if means:
        ax.plot([m[0] for m in means], [m[1] for m in means], "-", color="C1", label="mean over seeds")
        ax.legend(fontsize=7)
    if not numeric:
        ax.set_xticks(range(len(categories)), categories)
    ax.set_xlabel(field)
    ax.set_ylabel(name)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    return fig


def write_sweep_plots(
    folder: Path, records: Sequence[dict[str, Any]], varied: Sequence[str], metrics: Sequence[str]
) -> list[tuple[str, Path, str]]:
    """Every plot as a PNG in ``folder``/plots: (caption, path, base64 of the PNG) per plot."""
    out = folder / "plots"
    out.mkdir(parents=True, exist_ok=True)
    plots = []
    tasks = dict.fromkeys(  # every task any point ran (a sweep may fly several projects), in order
        task for r in records if r["status"] == OK for task in (r.get("summary") or {}).get("tasks") or {}
    )
    for task in tasks:
        path = out / f"pareto-{task}.png"
        plots.append((f"{task}: Pareto front", path, _png(pareto_figure(records, varied, task), path, 100)))
    # the chip's whole energy (idle routers and sleeping cores included: what clock gating and DVFS
    # change) against each task's response time, when the points varied the chip
    if any(field.startswith("chip.") for field in varied):
        for task in tasks:
            path = out / f"pareto-chip-{task}.png"
            figure = pareto_figure(records, varied, task, chip=True)
            plots.append((f"chip energy against {task} response: Pareto front", path, _png(figure, path, 100)))
    for field in varied:
        for name in metrics:
            path = out / f"{name}--{field}.png"
            plots.append((f"{name} against {field}", path, _png(metric_figure(records, name, field), path, 80)))
    return plots


def sweep_html(
    title: str, records: Sequence[dict[str, Any]], plots: Sequence[tuple[str, Path, str]], table_csv: str
) -> str:
    """The sweep's page: the plots (inline PNG), the failures and the table; needs no network."""
    parts = [f"<h1>{html.escape(title)}</h1>"]
    ok = sum(1 for r in records if r["status"] == OK)
    parts.append(f"<p>{len(records)} points finished, {ok} ok, {len(records) - ok} failed.</p>")
    parts.extend(
        f'<figure><img alt="{html.escape(caption)}" src="data:image/png;base64,{data}">'
        f"<figcaption>{html.escape(caption)}</figcaption></figure>"
        for caption, _, data in plots
    )
    failed = [r for r in records if r["status"] != OK]
    if failed:
        parts.append("<h2>Failed points</h2><ul>")
        parts.extend(
            f"<li>{html.escape(json.dumps(r['values']))}, seed {r['seed']}: {html.escape(r['error'])}</li>"
            for r in failed
        )
        parts.append("</ul>")
    rows = list(csv.reader(io.StringIO(table_csv)))
    if rows:
        head = "".join(f"<th>{html.escape(c)}</th>" for c in rows[0])
        body = "".join("<tr>" + "".join(f"<td>{html.escape(c)}</td>" for c in row) + "</tr>" for row in rows[1:])
        parts.append(f"<h2>Points</h2><table><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>")
    style = (
        "body{font-family:sans-serif;margin:2em}figure{display:inline-block;margin:.5em}img{max-width:640px}"
        "table{border-collapse:collapse;font-size:12px}td,th{border:1px solid #ccc;padding:2px 6px}"
    )
    return (
        f'<!DOCTYPE html><html><head><meta charset="utf-8"><title>{html.escape(title)}</title>'
        f"<style>{style}</style></head><body>{''.join(parts)}</body></html>\n"
    )


__all__ = ["metric_figure", "pareto_figure", "pareto_front", "sweep_html", "write_sweep_plots"]
