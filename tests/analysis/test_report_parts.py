"""The report's flight plots, energy bars, tables, title and sections, from hand-made rows and
summaries: the axes read back (``report._svg`` replaced by a stand-in that keeps them), the HTML
compared piece by piece."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
import pytest

from robosoc.control.flight import ROW_FIELDS
from robosoc.outputs import report
from robosoc.outputs.run_folder import RunFolder


def flight(n: int = 5, estimate: bool = True) -> np.ndarray:
    """``n`` rows 0.01 s apart, each column a known ramp: column c of row k is c + k / 10."""
    rows = np.array([[c + k / 10 for c in range(len(ROW_FIELDS))] for k in range(n)], dtype=float)
    rows[:, ROW_FIELDS.index("t")] = np.arange(n) * 0.01
    if not estimate:
        for name in ("est_height", "est_roll", "est_pitch", "est_yaw"):
            rows[:, ROW_FIELDS.index(name)] = np.nan
    return rows


def col(rows: np.ndarray, name: str) -> np.ndarray:
    return rows[:, ROW_FIELDS.index(name)]


def lines(ax) -> list[tuple[str, str, list[float]]]:
    return [(line.get_label(), line.get_linestyle(), list(line.get_ydata())) for line in ax.lines]


def test_trajectory_plots_height_with_setpoint_and_estimate_then_drift(drawn):
    rows = flight()
    page = report._trajectory(rows)
    assert page == (
        '<figure class="plot" data-plot="trajectory"><svg id=\'traj\'/><figcaption>Trajectory: height against its'
        " setpoint, horizontal drift</figcaption></figure>"
    )
    ((name, size, nrows, sharex, (ax_z, ax_xy), _),) = drawn
    assert (name, size, nrows, sharex) == ("traj", (10, 5), 2, True)
    assert lines(ax_z) == [
        ("true height z", "-", list(col(rows, "z"))),
        ("height setpoint", "--", list(col(rows, "sp_height"))),
        ("estimated height", ":", list(col(rows, "est_height"))),
    ]
    assert list(ax_z.lines[0].get_xdata()) == list(col(rows, "t"))
    assert lines(ax_xy) == [("x", "-", list(col(rows, "x"))), ("y", "-", list(col(rows, "y")))]
    assert (ax_z.get_ylabel(), ax_xy.get_ylabel(), ax_xy.get_xlabel()) == ("m", "m", "time [s]")
    for ax in (ax_z, ax_xy):
        assert [t.get_text() for t in ax.get_legend().get_texts()] == [line.get_label() for line in ax.lines]
        assert ax.yaxis.get_gridlines()[0].get_visible() and ax.yaxis.get_gridlines()[0].get_alpha() == 0.3


def test_without_an_estimate_the_plots_leave_it_out_and_say_so(drawn):
    rows = flight(estimate=False)
    report._trajectory(rows)
    page = report._attitude(rows)
    assert "<figcaption>Attitude: true, estimated and setpoint (no estimate in this log)</figcaption>" in page
    (_, (ax_z, _)), (_, axes) = ((p[0], p[4]) for p in drawn)
    assert [line.get_label() for line in ax_z.lines] == ["true height z", "height setpoint"]
    for ax, axis in zip(axes, ("roll", "pitch", "yaw"), strict=True):
        assert [line.get_label() for line in ax.lines] == [f"true {axis}", "setpoint"]


def test_attitude_plots_each_axis_in_degrees(drawn):
    rows = flight()
    page = report._attitude(rows)
    assert "<figcaption>Attitude: true, estimated and setpoint</figcaption>" in page
    ((name, size, nrows, sharex, axes, _),) = drawn
    assert (name, size, nrows, sharex) == ("att", (10, 7), 3, True)
    for ax, axis in zip(axes, ("roll", "pitch", "yaw"), strict=True):
        got = lines(ax)
        assert [(label, style) for label, style, _ in got] == [
            (f"true {axis}", "-"), (f"estimated {axis}", ":"), ("setpoint", "--")
        ]  # fmt: skip
        for (_, _, y), name in zip(got, (axis, f"est_{axis}", f"sp_{axis}"), strict=True):
            assert y == pytest.approx(np.degrees(col(rows, name)))
        assert ax.get_ylabel() == "deg" and ax.get_legend() is not None
        assert ax.yaxis.get_gridlines()[0].get_alpha() == 0.3
    assert axes[-1].get_xlabel() == "time [s]" and axes[0].get_xlabel() == ""


def test_pwm_plot_steps_each_motor(drawn):
    rows = flight()
    page = report._pwm(rows)
    assert "<figcaption>Motor PWM commands</figcaption>" in page and 'data-plot="pwm"' in page
    ((name, size, nrows, _, (ax,), _),) = drawn
    assert (name, size, nrows) == ("pwm", (10, 3), 1)
    assert [line.get_label() for line in ax.lines] == [f"motor {i}" for i in range(4)]
    for i, line in enumerate(ax.lines):
        assert line.get_drawstyle() == "steps-post"
        assert list(line.get_ydata()) == list(col(rows, f"pwm{i}"))
    assert (ax.get_ylabel(), ax.get_xlabel()) == ("PWM count", "time [s]")
    assert ax.get_legend()._ncols == 4


def test_long_flights_are_thinned_to_at_most_max_points(drawn):
    n = report.MAX_POINTS * 2 + 1
    rows = np.zeros((n, len(ROW_FIELDS)))
    rows[:, ROW_FIELDS.index("t")] = np.arange(n)
    report._pwm(rows)
    ((*_, (ax,), _),) = drawn
    x = list(ax.lines[0].get_xdata())
    assert x == list(range(0, n, 3))  # every third row: ceil(n / MAX_POINTS) = 3
    assert len(report._thin(rows[: report.MAX_POINTS])) == report.MAX_POINTS  # short enough: every row


def test_energy_bars_per_summary_object_with_the_noc_beside_the_tiles(drawn):
    summary = {
        "energy": {
            "total_uj": 9.0,
            "tiles_uj": {"0,1": 3.0, "1,0": 1.5, "1,1": None},
            "noc_uj": 0.5,
            "classes_uj": {"add": 1.0, "memory": 2.0, "bad": "x"},
            "empty_uj": {"a": None},
        }
    }
    figures = report._energy_breakdowns(summary)
    assert len(figures) == 2
    assert figures[0].startswith('<figure class="plot" data-plot="energy-tiles_uj">')
    assert figures[0].endswith("<figcaption>Energy by tiles</figcaption></figure>")
    assert figures[1].startswith('<figure class="plot" data-plot="energy-classes_uj">')
    assert figures[1].endswith("<figcaption>Energy by classes</figcaption></figure>")
    (name, size, nrows, _, (tiles,), _), (_, _, _, _, (classes,), _) = drawn
    assert (name, size, nrows) == ("energy-tiles_uj", (7, 3.2), 1)
    assert [t.get_text() for t in tiles.get_xticklabels()] == ["tile 0,1", "tile 1,0", "NoC"]
    assert [b.get_height() for b in tiles.patches] == [3.0, 1.5, 0.5]
    assert [t.get_text() for t in classes.get_xticklabels()] == ["add", "memory"]
    for ax in (tiles, classes):
        assert ax.get_ylabel() == "uJ"
        assert ax.yaxis.get_gridlines()[0].get_alpha() == 0.3 and not ax.xaxis.get_gridlines()[0].get_visible()
        assert all(t.get_rotation() == 0 for t in ax.get_xticklabels())


def test_energy_bars_turn_their_labels_when_there_are_more_than_six(drawn):
    seven = {f"c{k}": float(k) for k in range(7)}
    report._energy_breakdowns({"energy": {"classes_uj": dict(list(seven.items())[:6])}})
    report._energy_breakdowns({"energy": {"classes_uj": seven}})
    six, many = drawn[0][4][0], drawn[1][4][0]
    assert all(t.get_rotation() == 0 for t in six.get_xticklabels())
    assert all(t.get_rotation() == 45 for t in many.get_xticklabels())


def test_energy_without_numbers_gives_no_bars(drawn):
    for summary in ({}, {"energy": None}, {"energy": {"total_uj": 1.0}}, {"energy": {"tiles_uj": {"0,1": None}}}):
        assert report._energy_breakdowns(summary) == []
    # tiles without the NoC figure: the tiles alone
    assert len(report._energy_breakdowns({"energy": {"tiles_uj": {"0,1": 2.0}, "noc_uj": None}})) == 1
    assert [t.get_text() for t in drawn[0][4][0].get_xticklabels()] == ["tile 0,1"]


def test_the_summary_table_flattens_nested_values_into_named_rows():
    summary = {
        "seed": 3,
        "ratio": 0.123456789,
        "missing": None,
        "tasks": {"pid": {"jobs": 4}},
        "list": [1, 2.5, None],
        "vehicles": [{"a": 1}, {"a": 2}],
        "<tag>": "x&y",
    }
    assert report._summary_table(summary) == (
        "<table>"
        "<tr><th>seed</th><td class='num'>3</td></tr>"
        "<tr><th>ratio</th><td class='num'>0.123457</td></tr>"
        "<tr><th>missing</th><td class='num'>n/a</td></tr>"
        "<tr><th>tasks.pid.jobs</th><td class='num'>4</td></tr>"
        "<tr><th>list</th><td class='num'>1, 2.5, n/a</td></tr>"
        "<tr><th>vehicles[0].a</th><td class='num'>1</td></tr>"
        "<tr><th>vehicles[1].a</th><td class='num'>2</td></tr>"
        "<tr><th>&lt;tag&gt;</th><td class='num'>x&amp;y</td></tr>"
        "</table>"
    )
    assert report._number(True) == "True" and report._number(1e-9) == "1e-09"


@pytest.mark.parametrize(
    ("summary", "title"),
    [
        (None, "run-7"),
        ({}, "run-7"),
        ({"scenario": "hover", "controller": "chip", "firmware": {"build": "fixed+mul"}, "seed": 4},
         "hover, controller chip, firmware fixed+mul, seed 4"),
        ({"scenario": "s", "firmware": {"build": ""}, "complete": False}, "s, INCOMPLETE (interrupted or crashed)"),
        ({"scenario": "s", "firmware": "fixed", "complete": True, "seed": 0}, "s, seed 0"),
    ],
)  # fmt: skip
def test_the_title_names_scenario_controller_build_seed_and_an_incomplete_run(summary, title):
    assert report._title(RunFolder(Path("/runs/run-7"), summary=summary)) == title


def test_a_section_says_what_is_missing(drawn):
    page = report._section(RunFolder(Path("x"), notes=["flight.csv: last line incomplete"]), 2)
    assert page.split("\n") == [
        "<p class='note'>flight.csv: last line incomplete</p>",
        "<h2>Flight</h2>",
        "<p>No flight log (flight.csv) in this folder.</p>",
        "<h2>Tasks on the chip</h2>",
        "<p>No job records (jobs.csv): a host-controller flight, or the chip ran no job.</p>",
        "<p>No summary.json in this folder.</p>",
        "<h2>Configuration (scenario.toml)</h2>",
        "<p>No scenario.toml in this folder.</p>",
    ]
    assert drawn == []


def test_a_full_section_in_order_with_vehicles_one_level_down(drawn):
    jobs = {
        "task": np.array(["pid", "pid"]), "response_cycles": np.array([100, 200]),
        "task_pj": np.array([1.0, 2.0]), "kernel_pj": np.zeros(2), "noc_pj": np.zeros(2), "idle_pj": np.zeros(2),
    }  # fmt: skip
    vehicle = RunFolder(Path("v"), summary={"scenario": "v1", "seed": 2})
    run = RunFolder(
        Path("r"), rows=flight(), jobs=jobs, summary={"energy": {"noc_uj": 1.0}, "seed": 1},
        scenario_text="name = '<x>'\n", vehicles=[vehicle],
    )  # fmt: skip
    page = report._section(run, 2)
    heads = [line for line in page.split("\n") if line.startswith("<h")]
    assert heads == [
        "<h2>Flight</h2>", "<h2>Tasks on the chip</h2>", "<h2>Summary</h2>", "<h2>Configuration (scenario.toml)</h2>",
        "<h2>Vehicle 1: v1, seed 2</h2>", "<h3>Flight</h3>", "<h3>Tasks on the chip</h3>", "<h3>Summary</h3>",
        "<h3>Configuration (scenario.toml)</h3>",
    ]  # fmt: skip
    assert [p[0] for p in drawn] == ["traj", "att", "pwm", "resp", "etask"]
    assert "<p class='note'>No chip clock in summary.json: response times in cycles.</p>" in page
    assert "<pre>name = &#x27;&lt;x&gt;&#x27;\n</pre>" in page
    assert "<details><summary>summary.json</summary><pre>{\n  &quot;energy&quot;: {" in page
    assert "<h2>Energy</h2>" not in page  # no per-part energy object


def _legend_plot(ax) -> None:
    ax.plot([0, 1], [1, 2], label="hello <x>")
    ax.legend()


def test_a_plot_is_inline_svg_of_its_size_with_text_kept_as_text_and_no_date():
    svg = report._svg(_legend_plot, "one", (7, 3.2))
    assert svg.startswith('<svg xmlns:xlink="http://www.w3.org/1999/xlink" width="504pt" height="230.4pt"')
    assert svg.count("<svg") == 1 and svg.rstrip().endswith("</svg>")
    assert "hello &lt;x&gt;" in svg and "<text" in svg  # text stays text (svg.fonttype none), searchable
    assert "font-size: 9px" in svg and "font-size: 10px" not in svg
    assert "<dc:date>" not in svg  # no date: the same plot gives the same bytes
    assert report._svg(_legend_plot, "one", (7, 3.2)) == svg
    other = report._svg(_legend_plot, "two", (7, 3.2))
    assert other != svg and len(other) == len(svg)  # ids salted by the name: two plots on one page differ
    assert plt.get_fignums() == []  # closed


def test_stacked_plots_share_their_time_axis_unless_asked_not_to():
    seen: list[tuple] = []

    def draw(*axes) -> None:
        seen.append(tuple(axes))

    report._svg(draw, "a", (4, 3), 2)
    report._svg(draw, "b", (4, 3), 2, sharex=False)
    report._svg(draw, "c", (4, 3))
    (a1, a2), (b1, b2), (c1,) = seen
    assert a1.get_shared_x_axes().joined(a1, a2)
    assert not b1.get_shared_x_axes().joined(b1, b2)
    assert not c1.get_shared_x_axes().joined(c1, a1) and c1.get_figure().get_size_inches().tolist() == [4, 3]


def test_profile_rows_are_grouped_by_tile_and_task_with_the_chip_row_left_out():
    def row(tile, task, function, cycles, instructions=1):  # type: ignore[no-untyped-def]
        return {"tile": tile, "task": task, "function": function, "cycles": cycles, "instructions": instructions}

    profile = {
        "rows": [
            row("1,0", 2, "b", 10), row("1,0", 2, "a", 10), row("1,0", 2, "c", 30),
            row("0,1", 1, "main", 5), row("", None, "(NoC)", 0, 0), row("0,1", 0, "(sleep)", 99, 0),
        ]
    }  # fmt: skip
    tasks = report._profile_tasks(profile)
    assert list(tasks) == [("0,1", 1), ("1,0", 2)]  # sorted; the NoC row and a task without instructions out
    assert [r["function"] for r in tasks[("1,0", 2)]] == ["c", "a", "b"]  # most cycles first, then by name


def test_the_page_heads_with_the_title_and_folder_and_writes_where_asked(tmp_path: Path):
    run = RunFolder(tmp_path / "run <1>", summary={"scenario": "hover"}, scenario_text="x = 1\n")
    page = report.render_report(run)
    assert "<title>robosoc: hover</title>" in page and "<h1>robosoc run: hover</h1>" in page
    assert f"<p>Folder: <code>{tmp_path}/run &lt;1&gt;</code></p>" in page
    assert "<h2>Summary</h2>" in page and "<h3>" not in page
    folder = tmp_path / "run"
    folder.mkdir()
    (folder / "summary.json").write_text('{"scenario": "s"}')
    target = tmp_path / "elsewhere.html"
    assert report.write_report(folder, target) == target
    assert target.read_text(encoding="utf-8").startswith("<!DOCTYPE html>")
    assert sorted(p.name for p in folder.iterdir()) == ["summary.json"]  # nothing written in the run folder
    assert report.write_report(folder) == folder / "report.html" and (folder / "report.html").is_file()
