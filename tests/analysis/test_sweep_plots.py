"""The sweep's plots and page, read back from the figures' own data (markers, lines, labels) and
from the HTML, for records made by hand."""

from __future__ import annotations

import base64
import html.parser
import math
import re
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
import pytest

from robosoc.sweep.plots import metric_figure, pareto_figure, sweep_html, write_sweep_plots
from robosoc.sweep.point import FAILED, OK

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def record(arith: str, seed: int, response: float | None, energy: float | None, **extra: object) -> dict:
    figures = {"response_us_mean": response, "energy_nj_mean": energy}
    tasks = {"estimator": figures, "pid": figures}
    values = {"firmware.arith": arith, **extra}
    return {"status": OK, "values": values, "seed": seed, "summary": {"tasks": tasks}, "error": ""}


RECORDS = [
    record("fixed", 1, 10.0, 5.0),
    record("fixed", 2, 12.0, 4.0),
    record("float", 1, 30.0, 9.0),  # dominated by (10, 5)
    record("float", 2, 8.0, 7.0),
    {"status": FAILED, "values": {"firmware.arith": "float"}, "seed": 3, "summary": None, "error": "a <bad> point"},
]


def scatter_points(ax) -> dict[str, list[tuple[float, float]]]:
    """Each scatter's points by label (masked points, those without a figure, as NaN)."""
    out = {}
    for c in ax.collections:
        offsets = np.ma.filled(np.ma.asarray(c.get_offsets(), dtype=float), np.nan)
        out[c.get_label()] = [(float(x), float(y)) for x, y in offsets]
    return out


def test_pareto_figure_marks_every_ok_point_by_label_and_joins_the_front():
    fig = pareto_figure(RECORDS, ["firmware.arith"], "estimator")
    try:
        (ax,) = fig.axes
        assert scatter_points(ax) == {
            "arith=fixed": [(10.0, 5.0), (12.0, 4.0)],
            "arith=float": [(30.0, 9.0), (8.0, 7.0)],
        }
        (front,) = ax.lines
        assert front.get_label() == "Pareto front"
        assert list(zip(front.get_xdata(), front.get_ydata(), strict=True)) == [(8.0, 7.0), (10.0, 5.0), (12.0, 4.0)]
        assert ax.get_xlabel() == "estimator: mean response time [µs]"
        assert ax.get_ylabel() == "estimator: energy per job [nJ]"
        assert ax.get_title() == "estimator: energy against response time"
        assert [t.get_text() for t in ax.get_legend().get_texts()] == ["arith=fixed", "arith=float", "Pareto front"]
    finally:
        plt.close(fig)


def test_pareto_figure_of_a_task_without_figures_has_no_front_and_a_base_label():
    records = [record("fixed", 1, None, None), {**record("x", 1, 1.0, 1.0), "summary": {"tasks": {"estimator": True}}}]
    fig = pareto_figure(records, [], "pid")
    try:
        (ax,) = fig.axes
        assert not ax.lines
        (points,) = scatter_points(ax).values()
        assert all(math.isnan(x) and math.isnan(y) for x, y in points)
        assert [c.get_label() for c in ax.collections] == ["base"]
    finally:
        plt.close(fig)
    fig = pareto_figure([], [], "pid")
    try:
        assert fig.axes[0].get_legend() is None and not fig.axes[0].collections
    finally:
        plt.close(fig)


def test_metric_figure_places_categories_in_order_and_joins_the_means_over_seeds():
    fig = metric_figure(RECORDS, "tasks.estimator.energy_nj_mean", "firmware.arith")
    try:
        (ax,) = fig.axes
        (points,) = scatter_points(ax).values()
        assert points == [(0.0, 5.0), (0.0, 4.0), (1.0, 9.0), (1.0, 7.0)]
        (mean,) = ax.lines
        assert mean.get_label() == "mean over seeds"
        assert list(zip(mean.get_xdata(), mean.get_ydata(), strict=True)) == [(0, 4.5), (1, 8.0)]
        assert [t.get_text() for t in ax.get_xticklabels()] == ["fixed", "float"]
        assert ax.get_xlabel() == "firmware.arith" and ax.get_ylabel() == "tasks.estimator.energy_nj_mean"
    finally:
        plt.close(fig)


def test_metric_figure_of_a_numeric_field_uses_its_values_and_skips_missing_figures():
    records = [
        record("fixed", 1, 10.0, 2.0, **{"chip.width": 2}),
        record("fixed", 2, None, 4.0, **{"chip.width": 2}),
        record("fixed", 1, 30.0, 6.0, **{"chip.width": 4}),
        record("fixed", 2, 50.0, 6.0, **{"chip.width": 4}),
        {**record("fixed", 3, True, 1.0, **{"chip.width": 3})},  # a bool is not a figure
    ]
    fig = metric_figure(records, "tasks.estimator.response_us_mean", "chip.width")
    try:
        (ax,) = fig.axes
        (points,) = scatter_points(ax).values()
        assert len(points) == 5  # the points without a figure are masked
        assert [p for p in points if not math.isnan(p[1])] == [(2.0, 10.0), (4.0, 30.0), (4.0, 50.0)]
        (mean,) = ax.lines
        assert list(zip(mean.get_xdata(), mean.get_ydata(), strict=True)) == [(2.0, 10.0), (4.0, 40.0)]
        assert ax.get_legend() is not None
    finally:
        plt.close(fig)
    fig = metric_figure(
        [record("fixed", 1, None, None, **{"chip.width": 2})], "tasks.estimator.response_us_mean", "chip.width"
    )
    try:
        assert not fig.axes[0].lines and fig.axes[0].get_legend() is None
    finally:
        plt.close(fig)


def test_write_sweep_plots_writes_one_png_per_task_and_per_field_and_metric(tmp_path: Path):
    metrics = ["tasks.estimator.energy_nj_mean", "tasks.estimator.response_us_mean"]
    plots = write_sweep_plots(tmp_path, RECORDS, ["firmware.arith"], metrics)
    assert [(caption, path.relative_to(tmp_path).as_posix()) for caption, path, _ in plots] == [
        ("estimator: Pareto front", "plots/pareto-estimator.png"),
        ("pid: Pareto front", "plots/pareto-pid.png"),
        (
            "tasks.estimator.energy_nj_mean against firmware.arith",
            "plots/tasks.estimator.energy_nj_mean--firmware.arith.png",
        ),
        (
            "tasks.estimator.response_us_mean against firmware.arith",
            "plots/tasks.estimator.response_us_mean--firmware.arith.png",
        ),
    ]
    for _, path, data in plots:
        assert path.read_bytes().startswith(PNG_MAGIC)
        assert base64.b64decode(data) == path.read_bytes()
    assert plt.get_fignums() == []  # every figure closed
    width = int.from_bytes(plots[0][1].read_bytes()[16:20], "big")
    assert width == 700  # 7 in at 100 dpi
    assert int.from_bytes(plots[2][1].read_bytes()[16:20], "big") == 480  # 6 in at 80 dpi


class _Page(html.parser.HTMLParser):
    def __init__(self) -> None:
        super().__init__()
        self.tags: list[tuple[str, dict[str, str | None]]] = []
        self.text: list[str] = []

    def handle_starttag(self, tag, attrs):
        self.tags.append((tag, dict(attrs)))

    def handle_data(self, data):
        self.text.append(data)


def test_sweep_html_shows_counts_plots_failures_and_the_table():
    plots = [("a <plot>", Path("p.png"), "QUJD")]
    page = sweep_html("Sweep <1>", RECORDS, plots, "point,value\n0,<1>\n1,2\n")
    assert page.startswith('<!DOCTYPE html><html><head><meta charset="utf-8"><title>Sweep &lt;1&gt;</title>')
    assert page.endswith("</body></html>\n")
    parser = _Page()
    parser.feed(page)
    text = "".join(parser.text)
    assert "Sweep <1>" in text
    assert "5 points finished, 4 ok, 1 failed." in text
    imgs = [attrs for tag, attrs in parser.tags if tag == "img"]
    assert imgs == [{"alt": "a <plot>", "src": "data:image/png;base64,QUJD"}]
    assert "Failed points" in text
    assert '{"firmware.arith": "float"}, seed 3: a <bad> point' in text
    assert [tag for tag, _ in parser.tags].count("th") == 2 and [tag for tag, _ in parser.tags].count("tr") == 3
    assert "<td>&lt;1&gt;</td>" in page
    # nothing fetched from a network (the inlined images' base64 may spell "http" by chance)
    assert "http" not in re.sub(r"data:image/png;base64,[A-Za-z0-9+/=]*", "", page).replace("charset", "")


@pytest.mark.parametrize("table", ["", "only,a,header\n"])
def test_sweep_html_without_failures_or_rows(table):
    page = sweep_html("t", RECORDS[:2], [], table)
    assert "Failed points" not in page and "2 points finished, 2 ok, 0 failed." in page
    assert ("<h2>Points</h2>" in page) == bool(table)


def test_figure_styles_and_labels_of_deep_fields():
    records = [record("fixed", 1, 10.0, 5.0, **{"chip.noc.arbiter": "hermes"})]
    fig = pareto_figure(records, ["chip.noc.arbiter"], "estimator")
    try:
        (ax,) = fig.axes
        assert tuple(fig.get_size_inches()) == (7, 4.5)
        (points,) = ax.collections
        assert points.get_label() == "arbiter=hermes"  # the last part of the dotted name
        assert list(points.get_sizes()) == [28]
        (front,) = ax.lines
        assert (front.get_linestyle(), front.get_color(), front.get_linewidth()) == ("--", "k", 1)
        assert ax.get_legend().get_texts()[0].get_fontsize() == 7
        assert ax.xaxis.get_gridlines()[0].get_alpha() == 0.3
    finally:
        plt.close(fig)
    fig = metric_figure(RECORDS, "tasks.estimator.energy_nj_mean", "firmware.arith")
    try:
        (ax,) = fig.axes
        assert tuple(fig.get_size_inches()) == (6, 3.6)
        (points,) = ax.collections
        assert list(points.get_sizes()) == [18] and points.get_alpha() == 0.7
        (mean,) = ax.lines
        assert (mean.get_linestyle(), mean.get_color()) == ("-", "C1")
        assert ax.get_legend().get_texts()[0].get_fontsize() == 7
    finally:
        plt.close(fig)


def test_sweep_html_structure_is_exact_for_a_failure_and_a_table():
    page = sweep_html("t", RECORDS[4:], [], "a,b\n1,2\n")
    assert (
        "<h2>Failed points</h2><ul><li>{&quot;firmware.arith&quot;: &quot;float&quot;}, seed 3: a &lt;bad&gt; point"
        "</li></ul>"
    ) in page
    assert (
        "<table><thead><tr><th>a</th><th>b</th></tr></thead><tbody><tr><td>1</td><td>2</td></tr></tbody></table>"
        in page
    )
    assert "<style>body{font-family:sans-serif;margin:2em}figure{display:inline-block;margin:.5em}" in page
    assert "table{border-collapse:collapse;font-size:12px}td,th{border:1px solid #ccc;padding:2px 6px}</style>" in page


def test_write_sweep_plots_makes_the_plots_folder_and_its_parents(tmp_path: Path):
    out = tmp_path / "a" / "b"
    plots = write_sweep_plots(out, RECORDS, [], [])
    assert [p.name for _, p, _ in plots] == ["pareto-estimator.png", "pareto-pid.png"]
    again = write_sweep_plots(out, RECORDS, [], [])  # an existing folder is fine
    assert [p for _, p, _ in again] == [p for _, p, _ in plots]


def test_a_pareto_plot_per_task_that_ran_in_order_of_appearance(tmp_path: Path):
    """The tasks are those in the points' summaries (a project's own, two projects' together); a
    failed point's are not looked at."""
    mine = {"status": OK, "values": {}, "seed": 1, "error": "",
            "summary": {"tasks": {"controller": {"response_us_mean": 5.0, "energy_nj_mean": 2.0}}}}  # fmt: skip
    failed = {**mine, "status": FAILED, "summary": {"tasks": {"ghost": {}}}}
    plots = write_sweep_plots(tmp_path, [mine, failed, *RECORDS], [], [])
    assert [p.name for _, p, _ in plots] == ["pareto-controller.png", "pareto-estimator.png", "pareto-pid.png"]


def test_each_written_plot_is_the_figure_of_its_own_task_field_and_metric(tmp_path: Path):
    """The PNGs are byte for byte the figures drawn here for the same task, field and metric."""
    both = [record("fixed", 1, 10.0, 5.0, **{"chip.width": 2}), record("float", 1, 30.0, 9.0, **{"chip.width": 3})]
    varied = ["firmware.arith", "chip.width"]
    metric = "tasks.estimator.energy_nj_mean"
    plots = write_sweep_plots(tmp_path / "out", both, varied, [metric])
    expected = [(pareto_figure(both, varied, task), 100) for task in ("estimator", "pid")]
    # the chip was varied: the chip's whole energy against each task's response too
    expected += [(pareto_figure(both, varied, task, chip=True), 100) for task in ("estimator", "pid")]
    expected += [(metric_figure(both, metric, field), 80) for field in varied]
    assert len(plots) == len(expected)
    for (caption, path, _), (fig, dpi) in zip(plots, expected, strict=True):
        mine = tmp_path / "mine.png"
        fig.savefig(mine, dpi=dpi)
        plt.close(fig)
        assert path.read_bytes() == mine.read_bytes(), caption
    # two varied fields: each point's label names both, in the order given
    fig = pareto_figure(both, varied, "estimator")
    try:
        assert [c.get_label() for c in fig.axes[0].collections] == ["arith=fixed, width=2", "arith=float, width=3"]
    finally:
        plt.close(fig)


def test_the_points_table_has_one_row_per_line_in_order():
    page = sweep_html("t", RECORDS[:1], [], "point,value\n0,<1>\n1,2\n")
    assert (
        "<h2>Points</h2><table><thead><tr><th>point</th><th>value</th></tr></thead><tbody>"
        "<tr><td>0</td><td>&lt;1&gt;</td></tr><tr><td>1</td><td>2</td></tr></tbody></table>"
    ) in page


def test_the_chip_front_puts_the_chips_whole_energy_against_a_tasks_response() -> None:
    points = [record("fixed", 1, 10.0, 5.0, **{"chip.noc.clock_gating": g}) for g in (False, True)]
    for r, total in zip(points, (100.0, 20.0), strict=True):
        r["summary"]["energy"] = {"total_uj": total}
    fig = pareto_figure(points, ["chip.noc.clock_gating"], "estimator", chip=True)
    try:
        ax = fig.axes[0]
        assert "chip's energy" in ax.get_ylabel()
        ys = sorted(float(y) for c in ax.collections for _, y in c.get_offsets())
        assert ys == [20.0, 100.0]
    finally:
        plt.close(fig)
