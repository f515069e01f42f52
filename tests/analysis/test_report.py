"""The HTML report: what it shows from a run folder, and that Chromium renders it offline."""

from __future__ import annotations

import csv
import json
import re
import shutil
from pathlib import Path

import numpy as np
import pytest

from headless_chromium import BROWSER, load
from robosoc.control.flight import ROW_FIELDS
from robosoc.outputs.report import write_report
from robosoc.outputs.run_folder import RunFolderError, read_run_folder

needs_chromium = pytest.mark.skipif(BROWSER is None, reason="chromium is not installed (.ci/run installs it)")

NETWORK_REFERENCE = re.compile(
    r"""(?:\b(?:src|href)\s*=\s*["']?\s*(?:https?:|//))|url\(\s*["']?(?:https?:|//)|@import""", re.I
)


def _plots(text: str) -> list[str]:
    return re.findall(r'<figure class="plot" data-plot="([^"]+)"', text)


@needs_chromium
def test_chip_run_report_renders_every_plot_without_console_messages(chip_run: Path, tmp_path: Path) -> None:
    page_path = write_report(chip_run)
    assert page_path == chip_run / "report.html"
    text = page_path.read_text()
    assert NETWORK_REFERENCE.search(text) is None  # nothing to fetch
    expected = ["trajectory", "attitude", "pwm", "response", "energy-task", "energy-tiles_uj", "energy-classes_uj"]
    assert _plots(text) == expected
    page = load(page_path, tmp_path)
    assert page.console == []
    assert page.body_attribute("data-plots") == str(len(expected))
    assert page.body_attribute("data-rendered") == str(len(expected))
    # the screenshot is not blank: many distinct colours (lines, bars), not only the white page
    pixels = page.screenshot[..., :3].reshape(-1, 3)
    assert len(np.unique((pixels * 255).astype(np.uint8), axis=0)) > 50
    assert (pixels.min(axis=1) < 0.5).mean() > 0.005  # some dark ink


@needs_chromium
def test_host_run_report_renders_without_jobs(host_run: Path, tmp_path: Path) -> None:
    page_path = write_report(host_run, tmp_path / "elsewhere.html")
    text = page_path.read_text()
    assert _plots(text) == ["trajectory", "attitude", "pwm"]
    assert "No job records (jobs.csv)" in text
    page = load(page_path, tmp_path)
    assert page.console == []
    assert page.body_attribute("data-rendered") == "3"


def test_the_detector_sees_console_errors_and_blank_pages(tmp_path: Path) -> None:
    """The checks above can fail: a page with a script error and no plot is caught."""
    if BROWSER is None:
        pytest.skip("chromium is not installed")
    bad = tmp_path / "bad.html"
    bad.write_text('<!DOCTYPE html><html><body><figure class="plot"></figure><script>nope();</script></body></html>')
    page = load(bad, tmp_path)
    assert any("nope is not defined" in message for message in page.console)
    assert page.body_attribute("data-rendered") is None


def test_report_figures_come_from_the_folder(chip_run: Path) -> None:
    text = write_report(chip_run).read_text()
    summary = json.loads((chip_run / "summary.json").read_text())
    clock = summary["chip"]["clock_ns"]
    with (chip_run / "jobs.csv").open(newline="") as handle:
        jobs = list(csv.DictReader(handle))
    for task in ("estimator", "pid"):
        cycles = [int(job["response_cycles"]) for job in jobs if job["task"] == task]
        mean, top = np.mean(cycles) * clock / 1000, max(cycles) * clock / 1000
        assert f"{task}: {len(cycles)} jobs, mean {mean:.1f} us, max {top:.1f} us" in text
    assert "controller chip" in text and "firmware fixed+mul" in text
    assert "name = &quot;default&quot;" in text  # the scenario, escaped
    assert f"{summary['energy']['total_uj']:.6g}" in text


def test_interrupted_flight_log_is_read_up_to_its_last_whole_line(host_run: Path) -> None:
    csv = host_run / "flight.csv"
    whole = csv.read_text().splitlines()
    csv.write_text("\n".join(whole) + "\n" + whole[-1][: len(whole[-1]) // 2])
    run = read_run_folder(host_run)
    assert run.rows is not None and len(run.rows) == len(whole) - 1
    assert run.rows.shape[1] == len(ROW_FIELDS)
    assert any("interrupted" in note for note in run.notes)
    assert "last line incomplete" in write_report(host_run).read_text()


def test_vehicle_sub_folders_get_their_own_sections(host_run: Path, tmp_path: Path) -> None:
    top = tmp_path / "fleet"
    for k in (1, 2):
        shutil.copytree(host_run, top / f"vehicle-{k}")
    (top / "summary.json").write_text(json.dumps({"schema": 1, "vehicles": []}))
    text = write_report(top).read_text()
    assert "Vehicle 1:" in text and "Vehicle 2:" in text
    assert _plots(text).count("trajectory") == 2


def test_bad_folders_are_named(tmp_path: Path) -> None:
    with pytest.raises(RunFolderError, match=f"{tmp_path / 'missing'}: folder not found"):
        write_report(tmp_path / "missing")
    (tmp_path / "empty").mkdir()
    with pytest.raises(RunFolderError, match="not a run folder"):
        write_report(tmp_path / "empty")
    bad = tmp_path / "bad"
    bad.mkdir()
    (bad / "flight.csv").write_text("a,b\n1,2\n")
    with pytest.raises(RunFolderError, match=r"flight\.csv: not a robosoc flight log"):
        write_report(bad)
    (bad / "flight.csv").unlink()
    (bad / "summary.json").write_text("{oops")
    with pytest.raises(RunFolderError, match=r"summary\.json: not JSON"):
        write_report(bad)
    assert not (bad / "report.html").exists()
