"""The HTML report of a run folder: one self-contained page (``report.html``).

Plots are matplotlib figures inlined as SVG, styles inline, no script or font fetched from
anywhere: the page opens without a network.  It shows what the folder holds (see
:mod:`robosoc.outputs.run_folder`): trajectory and setpoints (a mission's waypoints over their holds and
from above, from ``summary.json``), estimated against true attitude,
motor PWM, the firmware's own telemetry values when it publishes any
(``flight.csv``); per-task response-time histograms and energy per task split into its
parts (``jobs.csv``); energy by tile and any other breakdown of ``summary.json``'s ``energy``
(by instruction class, ``classes_uj``, when present); where cycles and energy go per firmware
function, task and tile (``profile.json``, when the run was profiled: docs/profile.md); a battery
flight's power budget (``summary.json``'s ``power``, the pack's columns of ``flight.csv``); the key
figures of ``summary.json`` and the scenario (``scenario.toml``).  A missing file leaves its
section out with a line saying so.

A short script at the end of the page marks each plot that the browser laid out with a non-empty
size (``data-rendered``) and counts them on ``<body>``; the tests read that back from headless
Chromium.  The page needs no script to be read.
"""

from __future__ import annotations

import html
import io
import json
import math
from collections.abc import Callable
from pathlib import Path

import numpy as np

from robosoc import output_files
from robosoc.control.flight import ROW_FIELDS
from robosoc.outputs.run_folder import REPORT_HTML, RunFolder, finite, read_run_folder
from robosoc.records import POWER_CONSUMERS, POWER_FIELDS

MAX_POINTS = 5000
"""Most points drawn per line (longer flights are thinned evenly; the CSV keeps every row)."""

JOB_ENERGY_PARTS = ("task", "kernel", "noc", "idle")

_STYLE = """
body { font-family: system-ui, sans-serif; margin: 1.5em auto; max-width: 1100px; color: #222; }
h1 { font-size: 1.5em; } h2 { font-size: 1.2em; border-bottom: 1px solid #ccc; margin-top: 1.6em; }
figure.plot { margin: 0.8em 0; } figure.plot svg { width: 100%; height: auto; }
figcaption { font-size: 0.9em; color: #555; }
table { border-collapse: collapse; font-size: 0.9em; } td, th { padding: 2px 10px; text-align: left; }
tr:nth-child(even) { background: #f4f4f4; } td.num { text-align: right; font-variant-numeric: tabular-nums; }
pre { background: #f6f6f6; padding: 0.8em; overflow-x: auto; font-size: 0.85em; }
.note { color: #8a5a00; }
"""

_CHECK_SCRIPT = """
(function () {
  var figures = document.querySelectorAll("figure.plot");
  var rendered = 0;
  for (var i = 0; i < figures.length; i++) {
    var svg = figures[i].querySelector("svg");
    if (!svg) continue;
    var box = svg.getBoundingClientRect();
    if (box.width > 0 && box.height > 0 && svg.querySelectorAll("path, use, text").length > 0) {
      figures[i].setAttribute("data-rendered", "1");
      rendered++;
    }
  }
  document.body.setAttribute("data-plots", String(figures.length));
  document.body.setAttribute("data-rendered", String(rendered));
})();
"""


def _column(rows: np.ndarray, name: str) -> np.ndarray:
    return rows[:, ROW_FIELDS.index(name)]


def _thin(rows: np.ndarray) -> np.ndarray:
    step = max(1, math.ceil(len(rows) / MAX_POINTS))
    return rows[::step]


def _svg(
    draw: Callable[..., None], name: str, size: tuple[float, float], nrows: int = 1, *, sharex: bool = True
) -> str:
    """A matplotlib figure drawn by ``draw(axes)`` as inline SVG (ids salted by ``name``)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    with matplotlib.rc_context({"svg.fonttype": "none", "svg.hashsalt": name, "font.size": 9}):
        fig, axes = plt.subplots(nrows, 1, figsize=size, sharex=sharex and nrows > 1, squeeze=False)
        try:
            draw(*axes[:, 0])
            fig.tight_layout()
            buffer = io.StringIO()
            fig.savefig(buffer, format="svg", metadata={"Date": None})
        finally:
            plt.close(fig)
    text = buffer.getvalue()
    return text[text.index("<svg") :]


def _figure(name: str, caption: str, svg: str) -> str:
    head = f'<figure class="plot" data-plot="{html.escape(name)}">'
    return f"{head}{svg}<figcaption>{html.escape(caption)}</figcaption></figure>"


# --- flight plots -------------------------------------------------------------------------------


def _trajectory(rows: np.ndarray, waypoints: list[dict] | None = None) -> str:
    r = _thin(rows)
    t = _column(r, "t")

    def draw(ax_z, ax_xy) -> None:
        ax_z.plot(t, _column(r, "z"), label="true height z")
        ax_z.plot(t, _column(r, "sp_height"), "--", label="height setpoint")
        est = _column(r, "est_height")
        if np.isfinite(est).any():
            ax_z.plot(t, est, ":", label="estimated height")
        ax_z.set_ylabel("m")
        ax_z.legend(loc="best")
        ax_z.grid(alpha=0.3)
        x_line = ax_xy.plot(t, _column(r, "x"), label="x")[0]
        y_line = ax_xy.plot(t, _column(r, "y"), label="y")[0]
        for i, w in enumerate(waypoints or []):  # each waypoint over its hold
            for key, line in (("x", x_line), ("y", y_line)):
                label = f"waypoint {key} (hold)" if i == 0 else None
                ax_xy.hlines(w[key], w["arrive_s"], w["leave_s"], colors=line.get_color(), linewidth=4, alpha=0.35,
                             label=label)  # fmt: skip
        ax_xy.set_ylabel("m")
        ax_xy.set_xlabel("time [s]")
        ax_xy.legend(loc="best")
        ax_xy.grid(alpha=0.3)

    return _figure(
        "trajectory", "Trajectory: height against its setpoint, horizontal drift", _svg(draw, "traj", (10, 5), 2)
    )


def _mission_plan(rows: np.ndarray, mission: dict) -> str:
    """The mission from above: the path flown, each waypoint with its acceptance circle, the landing."""
    r = _thin(rows)
    armed = _column(r, "armed") > 0.5
    radius = mission.get("acceptance_m") or 0.0

    def draw(ax) -> None:
        ax.plot(_column(r, "x")[armed], _column(r, "y")[armed], label="path (armed)")
        for i, w in enumerate(mission.get("waypoints") or []):
            colour = "tab:green" if w.get("reached") else "tab:red"
            ax.add_patch(_circle((w["x"], w["y"]), radius, colour))
            ax.plot(w["x"], w["y"], "o", color=colour, label="waypoint (reached: green)" if i == 0 else None)
            ax.annotate(str(i + 1), (w["x"], w["y"]), textcoords="offset points", xytext=(6, 6))
        if mission.get("landed"):
            ax.plot(mission["landed_x"], mission["landed_y"], "kx", markersize=9, label="landed")
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m]")
        ax.set_aspect("equal", adjustable="datalim")
        ax.legend(loc="best")
        ax.grid(alpha=0.3)

    caption = f"Mission from above: waypoints with their acceptance radius ({radius * 100:.0f} cm), the path flown"
    return _figure("mission", caption, _svg(draw, "mission", (6, 6)))


def _circle(centre: tuple[float, float], radius: float, colour: str):
    """A circle patch (matplotlib is imported only when a report is drawn)."""
    from matplotlib.patches import Circle

    return Circle(centre, radius, fill=False, color=colour, alpha=0.6)


def _attitude(rows: np.ndarray) -> str:
    r = _thin(rows)
    t = _column(r, "t")

    def draw(*axes) -> None:
        for ax, axis in zip(axes, ("roll", "pitch", "yaw"), strict=True):
            ax.plot(t, np.degrees(_column(r, axis)), label=f"true {axis}")
            est = _column(r, f"est_{axis}")
            if np.isfinite(est).any():
                ax.plot(t, np.degrees(est), ":", label=f"estimated {axis}")
            ax.plot(t, np.degrees(_column(r, f"sp_{axis}")), "--", label="setpoint")
            ax.set_ylabel("deg")
            ax.legend(loc="best")
            ax.grid(alpha=0.3)
        axes[-1].set_xlabel("time [s]")

    has_estimate = np.isfinite(_column(rows, "est_roll")).any()
    caption = "Attitude: true, estimated and setpoint" + ("" if has_estimate else " (no estimate in this log)")
    return _figure("attitude", caption, _svg(draw, "att", (10, 7), 3))


def _pwm(rows: np.ndarray) -> str:
    r = _thin(rows)
    t = _column(r, "t")

    def draw(ax) -> None:
        for i in range(4):
            ax.step(t, _column(r, f"pwm{i}"), where="post", label=f"motor {i}")
        ax.set_ylabel("PWM count")
        ax.set_xlabel("time [s]")
        ax.legend(loc="best", ncols=4)
        ax.grid(alpha=0.3)

    return _figure("pwm", "Motor PWM commands", _svg(draw, "pwm", (10, 3)))


def _telemetry(rows: np.ndarray, telemetry: dict[str, np.ndarray]) -> str:
    """The firmware's own telemetry values over time, one small panel each (gaps before the first)."""
    step = max(1, math.ceil(len(rows) / MAX_POINTS))
    t = _column(rows, "t")[::step]
    names = list(telemetry)

    def draw(*axes) -> None:
        for ax, name in zip(axes, names, strict=True):
            ax.step(t, telemetry[name][::step], where="post", label=name)
            ax.set_ylabel(name)
            ax.grid(alpha=0.3)
        axes[-1].set_xlabel("time [s]")

    caption = f"Telemetry the firmware publishes ({', '.join(names)}; flight.csv)"
    return _figure("telemetry", caption, _svg(draw, "telem", (10, 0.6 + 1.4 * len(names)), len(names)))


# --- job plots ----------------------------------------------------------------------------------


def _tasks(jobs: dict[str, np.ndarray]) -> list[str]:
    return list(dict.fromkeys(str(t) for t in jobs["task"]))


def _response_histograms(jobs: dict[str, np.ndarray], clock_ns: float | None) -> str:
    tasks = _tasks(jobs)
    scale, unit = (clock_ns / 1000.0, "us") if clock_ns else (1.0, "cycles")

    def draw(*axes) -> None:
        for ax, task in zip(axes, tasks, strict=True):
            mine = jobs["task"] == task
            values = jobs["response_cycles"][mine] * scale
            ax.hist(values, bins=min(50, max(5, len(values) // 4)))
            ax.set_ylabel("jobs")
            ax.set_title(f"{task}: {len(values)} jobs, mean {values.mean():.1f} {unit}, max {values.max():.1f} {unit}")
            ax.grid(alpha=0.3)
        axes[-1].set_xlabel(f"response time (release to completion) [{unit}]")

    return _figure(
        "response", "Response time per task", _svg(draw, "resp", (10, 2.6 * len(tasks)), len(tasks), sharex=False)
    )


def _job_energy(jobs: dict[str, np.ndarray]) -> str:
    tasks = _tasks(jobs)

    def draw(ax) -> None:
        bottom = np.zeros(len(tasks))
        for part in JOB_ENERGY_PARTS:
            values = np.array([jobs[f"{part}_pj"][jobs["task"] == task].sum() / 1e6 for task in tasks])
            ax.bar(tasks, values, bottom=bottom, label=part)
            bottom += values
        ax.set_ylabel("energy of all jobs [uJ]")
        ax.legend(loc="best")
        ax.grid(alpha=0.3, axis="y")

    return _figure(
        "energy-task", "Energy by task, split into the task itself, kernel, NoC and idle", _svg(draw, "etask", (7, 3.2))
    )


def _bars(name: str, caption: str, values: dict[str, float], unit: str) -> str:
    def draw(ax) -> None:
        labels = list(values)
        ax.bar(labels, [values[k] for k in labels])
        ax.set_ylabel(unit)
        ax.grid(alpha=0.3, axis="y")
        if len(labels) > 6:
            ax.tick_params(axis="x", labelrotation=45)

    return _figure(name, caption, _svg(draw, name, (7, 3.2)))


def _energy_breakdowns(summary: dict) -> list[str]:
    energy = summary.get("energy")
    if not isinstance(energy, dict):
        return []
    out = []
    for key, value in energy.items():
        if not isinstance(value, dict):
            continue
        read = {str(k): finite(v) for k, v in value.items()}
        numbers = {k: v for k, v in read.items() if v is not None}
        if not numbers:
            continue
        if key == "tiles_uj":
            noc = finite(energy.get("noc_uj"))
            if noc is not None:
                numbers["NoC"] = noc
            numbers = {(f"tile {k}" if k != "NoC" else k): v for k, v in numbers.items()}
        what = key.removesuffix("_uj").replace("_", " ")
        out.append(_bars(f"energy-{key}", f"Energy by {what}", numbers, "uJ"))
    return out


# --- the per-function profile (profile.json) ----------------------------------------------------

PROFILE_TOP = 8
"""Functions shown per task in the profile's plot and table."""


def _profile_tasks(profile: dict) -> dict[tuple[str, int], list[dict]]:
    """The rows of each (tile, task) with at least one instruction, largest cycles first."""
    out: dict[tuple[str, int], list[dict]] = {}
    for r in profile["rows"]:
        if r["tile"] and r["task"] is not None:
            out.setdefault((str(r["tile"]), int(r["task"])), []).append(r)
    for key, rows in list(out.items()):
        if not any(r["instructions"] for r in rows):
            del out[key]
        else:
            rows.sort(key=lambda r: (-r["cycles"], str(r["function"])))
    return dict(sorted(out.items()))


def _profile_plot(tasks: dict[tuple[str, int], list[dict]]) -> str:
    keys = list(tasks)

    def draw(*axes) -> None:
        for ax, key in zip(axes, keys, strict=True):
            rows = [r for r in tasks[key] if r["instructions"]][:PROFILE_TOP][::-1]
            ax.barh([str(r["function"]) for r in rows], [r["cycles"] for r in rows])
            ax.set_title(f"tile {key[0]}, {rows[0]['task_name'] if rows else ''} (task {key[1]})", fontsize=9)
            ax.grid(alpha=0.3, axis="x")
        axes[-1].set_xlabel("cycles")

    size = (9, 0.35 * sum(min(PROFILE_TOP, len(v)) for v in tasks.values()) + 0.9 * len(keys))
    return _figure(
        "profile",
        f"Cycles of the {PROFILE_TOP} costliest functions of each task (exact counts, profile.json)",
        _svg(draw, "profile", size, len(keys), sharex=False),
    )


def _profile_table(tasks: dict[tuple[str, int], list[dict]]) -> str:
    head = "<tr><th>tile</th><th>task</th><th>function</th><th>cycles</th><th>% of task</th>"
    head += "<th>instructions</th><th>energy nJ</th></tr>"
    body = []
    for (tile, task), rows in tasks.items():
        total = sum(r["cycles"] for r in rows) or 1
        for r in rows[:PROFILE_TOP]:
            cells = [tile, f"{r['task_name']} ({task})", str(r["function"])]
            numbers = [f"{r['cycles']:,}", f"{100 * r['cycles'] / total:.1f}", f"{r['instructions']:,}",
                       f"{r['energy_nj']:,.1f}"]  # fmt: skip
            body.append(
                "<tr>" + "".join(f"<td>{html.escape(c)}</td>" for c in cells)
                + "".join(f"<td class='num'>{n}</td>" for n in numbers) + "</tr>"
            )  # fmt: skip
    return f"<table>{head}{''.join(body)}</table>"


# --- power (a battery flight, docs/power.md) -----------------------------------------------------


def _power_plot(rows: np.ndarray, power: np.ndarray) -> str:
    step = max(1, math.ceil(len(rows) / MAX_POINTS))
    t = _column(rows, "t")[::step]
    p = {name: power[::step, i] for i, name in enumerate(POWER_FIELDS)}

    def draw(ax_v, ax_w, ax_soc) -> None:
        ax_v.plot(t, p["pack_v"], label="pack voltage [V]")
        ax_v.set_ylabel("V")
        ax_v.grid(alpha=0.3)
        ax_v.legend(loc="best")
        ax_w.plot(t, p["motors_w"], label="motors")
        ax_w.plot(t, p["chip_w"] * 1000, label="chip [mW]")
        ax_w.set_ylabel("W")
        ax_w.grid(alpha=0.3)
        ax_w.legend(loc="best")
        ax_soc.plot(t, p["soc"], label="state of charge")
        ax_soc.set_ylabel("SoC")
        ax_soc.set_xlabel("time [s]")
        ax_soc.grid(alpha=0.3)
        ax_soc.legend(loc="best")

    return _figure(
        "power",
        "The pack under load: terminal voltage, the motors' and the chip's power, state of charge (flight.csv)",
        _svg(draw, "power", (10, 6), 3),
    )


def _power_section(power: dict) -> list[str]:
    """The budget by consumer, the chip's share, the pack and the endurance estimate of ``summary.json``."""
    energy = power.get("energy_j") or {}
    total = finite(energy.get("total")) or 0.0
    rows = []
    for name in (*POWER_CONSUMERS, "total"):
        value = finite(energy.get(name))
        if value is None:
            continue
        share = f"{100 * value / total:.3f} %" if total > 0 else "n/a"
        rows.append(
            f"<tr><th>{html.escape(name)}</th><td class='num'>{value:,.3f}</td><td class='num'>{share}</td></tr>"
        )
    out = [f"<table><tr><th>consumer</th><th>energy J</th><th>share</th></tr>{''.join(rows)}</table>"]
    endurance = power.get("endurance") or {}
    hover = finite(endurance.get("hover_s"))
    at = finite(endurance.get("at_power_w"))
    if hover is not None and at is not None:
        out.append(
            f"<p><b>Endurance estimate</b>: {hover / 60:.1f} min of hover at {at:.1f} W (the flight's mean power "
            f"from take-off), from state of charge {endurance.get('from_soc')} to {endurance.get('to_soc')} "
            f"({html.escape(str(endurance.get('ended_by', '')))}).</p>"
            f"<p class='note'>Assumptions: {html.escape(str(endurance.get('assumptions', '')))}.</p>"
        )
    failsafe = power.get("failsafe")
    if isinstance(failsafe, dict):
        out.append(
            f"<p class='note'>Low-battery failsafe: the pack fell below its reserve (state of charge "
            f"{_number(failsafe.get('reserve_soc'))}) at {_number(failsafe.get('at_s'))} s; "
            f"{html.escape(str(failsafe.get('outcome', '')))}.</p>"
        )
    if power.get("after_empty"):
        out.append(
            f"<p class='note'>The pack ran empty at {_number(power.get('empty_at_s'))} s: "
            f"{html.escape(str(power['after_empty']))}.</p>"
        )
    return out


# --- tables -------------------------------------------------------------------------------------


def _flatten(prefix: str, value: object, out: list[tuple[str, str]]) -> None:
    if isinstance(value, dict):
        for k, v in value.items():
            _flatten(f"{prefix}.{k}" if prefix else str(k), v, out)
    elif isinstance(value, list):
        if all(not isinstance(v, dict | list) for v in value):
            out.append((prefix, ", ".join(_number(v) for v in value)))
        else:
            for i, v in enumerate(value):
                _flatten(f"{prefix}[{i}]", v, out)
    else:
        out.append((prefix, _number(value)))


def _number(value: object) -> str:
    if value is None:
        return "n/a"
    if isinstance(value, float):
        return f"{value:.6g}"
    return str(value)


def _summary_table(summary: dict) -> str:
    items: list[tuple[str, str]] = []
    _flatten("", summary, items)
    rows = "".join(f"<tr><th>{html.escape(k)}</th><td class='num'>{html.escape(v)}</td></tr>" for k, v in items)
    return f"<table>{rows}</table>"


def _title(run: RunFolder) -> str:
    s = run.summary or {}
    parts = [str(s.get("scenario", run.path.name))]
    if "controller" in s:
        parts.append(f"controller {s['controller']}")
    firmware = s.get("firmware")
    if isinstance(firmware, dict) and firmware.get("build"):
        parts.append(f"firmware {firmware['build']}")
    if "seed" in s:
        parts.append(f"seed {s['seed']}")
    if s.get("complete") is False:
        parts.append("INCOMPLETE (interrupted or crashed)")
    return ", ".join(parts)


def _section(run: RunFolder, level: int) -> str:
    h = f"h{level}"
    body: list[str] = [f"<p class='note'>{html.escape(n)}</p>" for n in run.notes]
    body.append(f"<{h}>Flight</{h}>")
    if run.rows is not None and len(run.rows):
        mission = (run.summary or {}).get("mission")
        waypoints = mission.get("waypoints") if isinstance(mission, dict) else None
        body.append(_trajectory(run.rows, waypoints))
        if isinstance(mission, dict) and waypoints:
            body.append(_mission_plan(run.rows, mission))
        body += [_attitude(run.rows), _pwm(run.rows)]
        if run.telemetry:
            body.append(_telemetry(run.rows, run.telemetry))
    else:
        body.append("<p>No flight log (flight.csv) in this folder.</p>")
    body.append(f"<{h}>Tasks on the chip</{h}>")
    if run.jobs is not None and len(run.jobs["task"]):
        body += [_response_histograms(run.jobs, run.clock_ns), _job_energy(run.jobs)]
        if run.clock_ns is None:
            body.append("<p class='note'>No chip clock in summary.json: response times in cycles.</p>")
    else:
        body.append("<p>No job records (jobs.csv): a host-controller flight, or the chip ran no job.</p>")
    if run.profile is not None:
        tasks = _profile_tasks(run.profile)
        if tasks:
            body.append(f"<{h}>Where cycles and energy go, per function (profile.json)</{h}>")
            body += [_profile_plot(tasks), _profile_table(tasks)]
    power = (run.summary or {}).get("power")
    if isinstance(power, dict):
        body.append(f"<{h}>Power budget</{h}>")
        if run.rows is not None and run.power is not None and len(run.rows):
            body.append(_power_plot(run.rows, run.power))
        body += _power_section(power)
    if run.summary is not None:
        energy = _energy_breakdowns(run.summary)
        if energy:
            body.append(f"<{h}>Energy</{h}>")
            body += energy
        body.append(f"<{h}>Summary</{h}>")
        body.append(_summary_table(run.summary))
    else:
        body.append("<p>No summary.json in this folder.</p>")
    body.append(f"<{h}>Configuration (scenario.toml)</{h}>")
    if run.scenario_text is not None:
        body.append(f"<pre>{html.escape(run.scenario_text)}</pre>")
    else:
        body.append("<p>No scenario.toml in this folder.</p>")
    if run.summary is not None:
        text = json.dumps(run.summary, indent=2)
        body.append(f"<details><summary>summary.json</summary><pre>{html.escape(text)}</pre></details>")
    for k, vehicle in enumerate(run.vehicles, start=1):
        body.append(f"<h2>Vehicle {k}: {html.escape(_title(vehicle))}</h2>")
        body.append(_section(vehicle, 3))
    return "\n".join(body)


def render_report(run: RunFolder) -> str:
    """The report page of ``run`` as HTML text."""
    title = html.escape(_title(run))
    return (
        "<!DOCTYPE html>\n<html lang='en'><head><meta charset='utf-8'>"
        f"<title>robosoc: {title}</title><style>{_STYLE}</style></head>\n<body>\n"
        f"<h1>robosoc run: {title}</h1>\n<p>Folder: <code>{html.escape(str(run.path))}</code></p>\n"
        f"{_section(run, 2)}\n<script>{_CHECK_SCRIPT}</script>\n</body></html>\n"
    )


def write_report(run_dir: Path, out: Path | None = None) -> Path:
    """Write the report of the run folder ``run_dir`` to ``out`` (default ``run_dir/report.html``).

    The page is written to a temporary name and renamed.

    Raises:
        robosoc.outputs.run_folder.RunFolderError: ``run_dir`` is not a run folder, or a file in it
            is malformed (the message names it).
    """
    run = read_run_folder(run_dir)
    target = out if out is not None else run_dir / REPORT_HTML
    output_files.write_atomic(target, render_report(run))
    return target


__all__ = ["MAX_POINTS", "render_report", "write_report"]
