"""The report's plots hold the data they claim: read back from the matplotlib axes each one draws.

``report._svg`` is replaced by a stand-in that draws on real axes and keeps them, so the bars,
histograms, labels and titles can be compared with figures worked out here from hand-made jobs.
"""

from __future__ import annotations

import numpy as np
import pytest

from robosoc.outputs import report


def jobs() -> dict[str, np.ndarray]:
    """Three estimator jobs and two PID jobs, estimator first."""
    return {
        "task": np.array(["estimator", "pid", "estimator", "estimator", "pid"]),
        "response_cycles": np.array([1000, 250, 3000, 2000, 750]),
        "task_pj": np.array([1e6, 2e6, 3e6, 4e6, 5e6]),
        "kernel_pj": np.array([1e5, 2e5, 3e5, 4e5, 5e5]),
        "noc_pj": np.array([0.0, 1e6, 0.0, 0.0, 1e6]),
        "idle_pj": np.array([5e5, 0.0, 5e5, 0.0, 0.0]),
    }


def test_response_histograms_one_per_task_in_microseconds(drawn):
    page = report._response_histograms(jobs(), 4.0)
    assert "Response time per task" in page and 'data-plot="response"' in page
    ((name, size, nrows, sharex, axes, _),) = drawn
    assert (name, size, nrows, sharex) == ("resp", (10, 2.6 * 2), 2, False)
    est, pid = axes
    assert est.get_title() == "estimator: 3 jobs, mean 8.0 us, max 12.0 us"  # 1000..3000 cycles at 4 ns
    assert pid.get_title() == "pid: 2 jobs, mean 2.0 us, max 3.0 us"
    for ax, n, (lo, hi) in ((est, 3, (4.0, 12.0)), (pid, 2, (1.0, 3.0))):
        bars = ax.patches
        assert len(bars) == 5  # min(50, max(5, n // 4)) bins
        assert sum(b.get_height() for b in bars) == n
        assert bars[0].get_x() == pytest.approx(lo) and bars[-1].get_x() + bars[-1].get_width() == pytest.approx(hi)
        assert ax.get_ylabel() == "jobs"
    assert pid.get_xlabel() == "response time (release to completion) [us]" and est.get_xlabel() == ""


def test_response_histograms_in_cycles_without_a_clock_and_more_bins_for_many_jobs(drawn):
    many = {"task": np.array(["pid"] * 400), "response_cycles": np.arange(400) * 10 + 100}
    report._response_histograms(many, None)
    ((_, size, nrows, _, (ax,), _),) = drawn
    assert (size, nrows) == ((10, 2.6), 1)
    assert len(ax.patches) == 50  # 400 // 4 capped at 50
    assert ax.get_title() == "pid: 400 jobs, mean 2095.0 cycles, max 4090.0 cycles"
    assert ax.get_xlabel() == "response time (release to completion) [cycles]"
    report._response_histograms({"task": np.array(["pid"] * 40), "response_cycles": np.arange(40)}, None)
    assert len(drawn[1][4][0].patches) == 10  # 40 // 4


def test_job_energy_stacks_the_parts_of_each_task_in_microjoules(drawn):
    page = report._job_energy(jobs())
    assert "Energy by task, split into the task itself, kernel, NoC and idle" in page
    ((name, size, _, _, (ax,), _),) = drawn
    assert (name, size) == ("etask", (7, 3.2))
    parts = {c.get_label(): c for c in ax.containers}
    assert list(parts) == ["task", "kernel", "noc", "idle"]
    expected = {  # per part: (estimator, pid) in uJ
        "task": (1 + 3 + 4, 2 + 5),
        "kernel": (0.1 + 0.3 + 0.4, 0.2 + 0.5),
        "noc": (0.0, 2.0),
        "idle": (1.0, 0.0),
    }
    bottom = np.zeros(2)
    for part, values in expected.items():
        bars = parts[part].patches
        assert [b.get_height() for b in bars] == pytest.approx(values, rel=1e-12, abs=1e-15)
        assert [b.get_y() for b in bars] == pytest.approx(bottom)  # stacked on the parts before
        bottom += values
    assert [t.get_text() for t in ax.get_xticklabels()] == ["estimator", "pid"]
    assert ax.get_ylabel() == "energy of all jobs [uJ]"
    assert [t.get_text() for t in ax.get_legend().get_texts()] == ["task", "kernel", "noc", "idle"]


def profile_tasks() -> dict[tuple[str, int], list[dict]]:
    def row(name: str, cycles: int, instructions: int) -> dict:
        return {"function": name, "cycles": cycles, "instructions": instructions, "task_name": "ekf",
                "energy_nj": cycles / 100}  # fmt: skip

    many = [row(f"f{k}", 1000 - k, 10) for k in range(10)] + [row("idle-row", 5000, 0)]
    many.sort(key=lambda r: -r["cycles"])
    return {("0,1", 1): many, ("1,0", 2): [row("main", 30, 3), row("helper", 10, 1)]}


def test_profile_plot_shows_the_costliest_functions_of_each_task(drawn):
    tasks = profile_tasks()
    page = report._profile_plot(tasks)
    assert f"Cycles of the {report.PROFILE_TOP} costliest functions of each task" in page
    ((name, size, nrows, sharex, (first, second), _),) = drawn
    assert (name, nrows, sharex) == ("profile", 2, False)
    assert size == (9, pytest.approx(0.35 * (8 + 2) + 0.9 * 2))
    # the top 8 with instructions (the row without any is left out), costliest at the top
    assert [t.get_text() for t in first.get_yticklabels()] == [f"f{k}" for k in range(7, -1, -1)]
    assert [b.get_width() for b in first.patches] == [1000 - k for k in range(7, -1, -1)]
    assert first.get_title() == "tile 0,1, ekf (task 1)"
    assert [b.get_width() for b in second.patches] == [10, 30]
    assert second.get_title() == "tile 1,0, ekf (task 2)" and second.get_xlabel() == "cycles"


def test_profile_table_lists_the_top_functions_with_their_share_of_the_task():
    tasks = {("1,0", 2): [{"function": "main", "cycles": 30, "instructions": 1234, "task_name": "pid",
                           "energy_nj": 1500.25},
                          {"function": "<f&g>", "cycles": 10, "instructions": 1, "task_name": "pid",
                           "energy_nj": 0.5}]}  # fmt: skip
    table = report._profile_table(tasks)
    assert table == (
        "<table><tr><th>tile</th><th>task</th><th>function</th><th>cycles</th><th>% of task</th>"
        "<th>instructions</th><th>energy nJ</th></tr>"
        "<tr><td>1,0</td><td>pid (2)</td><td>main</td><td class='num'>30</td><td class='num'>75.0</td>"
        "<td class='num'>1,234</td><td class='num'>1,500.2</td></tr>"
        "<tr><td>1,0</td><td>pid (2)</td><td>&lt;f&amp;g&gt;</td><td class='num'>10</td><td class='num'>25.0</td>"
        "<td class='num'>1</td><td class='num'>0.5</td></tr></table>"
    )
    many = report._profile_table(profile_tasks())
    assert many.count("<tr>") == 1 + report.PROFILE_TOP + 2
