"""Sweeps end to end: the local pool and a Dask LocalCluster agree bit for bit, an interrupted sweep
resumes with only the missing points, failed points are recorded, the plots and the page are written."""

from __future__ import annotations

import csv
import json
import re
from pathlib import Path

import pytest

from robosoc.config.sweep import load_sweep
from robosoc.config.validate import ConfigError
from robosoc.sweep.plan import plan
from robosoc.sweep.point import FAILED, OK
from robosoc.sweep.runner import run_sweep

#: Results that depend on the host's speed, not on the simulation.
HOST_TIMING = {"host_s", "real_time_factor", "worker_s"}

SIXTEEN = """
seeds = [1, 2]
metrics = ["tasks.estimator.response_us_mean", "tasks.pid.energy_nj_mean", "energy.total_uj", "flight.hover_max_m"]
[base]
duration_s = 0.05
[grid]
"firmware.arith" = ["fixed", "float"]
"firmware.multiplier" = [true, false]
"sensors.noise" = [true, false]
"""


PID_AT_3_0 = '[{task = "pid", tile = [3, 0]}]'
"""A sweep value moving the quadrotor project's PID task to tile (3, 0)."""


def _without_timing(value):
    if isinstance(value, dict):
        return {k: _without_timing(v) for k, v in value.items() if k not in HOST_TIMING}
    if isinstance(value, list):
        return [_without_timing(v) for v in value]
    return value


def _results(out: Path) -> dict[str, dict]:
    return {p.stem: _without_timing(json.loads(p.read_text())) for p in (out / "results").glob("*.json")}


def _files(out: Path) -> dict[str, bytes]:
    return {
        str(p.relative_to(out)): p.read_bytes()
        for p in sorted((out / "points").rglob("*"))
        if p.is_file() and p.name != "summary.json"
    }


def test_local_pool_and_dask_local_cluster_give_the_same_rows(tmp_path):
    sweep = tmp_path / "sixteen.toml"
    sweep.write_text(SIXTEEN)
    config = load_sweep(sweep)
    assert len(plan(config)) == 16
    local = run_sweep(config, tmp_path / "local", workers=2)
    dask = run_sweep(config, tmp_path / "dask", workers=2, dask="local")
    assert local.ran == dask.ran == 16 and not local.failures and not dask.failures
    assert _results(tmp_path / "local") == _results(tmp_path / "dask")
    assert _files(tmp_path / "local") == _files(tmp_path / "dask")  # flight.csv, jobs.csv: byte for byte
    with open(tmp_path / "local" / "points.csv") as file:
        rows = list(csv.DictReader(file))
    assert [int(r["index"]) for r in rows] == list(range(16))
    # the table's metrics are the summaries' values, and the builds differ where they must
    for row in rows:
        summary = json.loads((tmp_path / "local" / "points" / row["key"] / "summary.json").read_text())
        assert float(row["tasks.estimator.response_us_mean"]) == summary["tasks"]["estimator"]["response_us_mean"]
    by_build = {(r["firmware.arith"], r["firmware.multiplier"]) for r in rows}
    assert len(by_build) == 4
    estimator = {
        (r["firmware.arith"], r["firmware.multiplier"]): float(r["tasks.estimator.response_us_mean"])
        for r in rows
        if r["seed"] == "1" and r["sensors.noise"] == "true"
    }
    assert estimator[("fixed", "true")] < estimator[("float", "false")]  # the seed's ordering, at least here


def test_interrupted_sweep_resumes_with_only_the_missing_points(tmp_path):
    sweep = tmp_path / "s.toml"
    sweep.write_text('seeds = [1, 2, 3]\n[base]\nduration_s = 0.03\n[grid]\n"sensors.noise" = [true, false]\n')
    config = load_sweep(sweep)
    seen = []

    def stop_after_two(point, record):
        seen.append(point.key)
        if len(seen) == 2:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run_sweep(config, tmp_path / "out", workers=1, on_point=stop_after_two)
    kept = set(_results(tmp_path / "out"))
    assert set(seen) <= kept and len(kept) < 6
    started = []
    again = run_sweep(config, tmp_path / "out", workers=1, on_start=lambda todo, done: started.append((todo, done)))
    assert started == [(6 - len(kept), len(kept))]
    assert again.ran == 6 - len(kept) and again.skipped == len(kept) and again.missing == 0
    # a third run has nothing to do
    assert run_sweep(config, tmp_path / "out", workers=1).ran == 0
    with open(tmp_path / "out" / "points.csv") as file:
        assert len(list(csv.DictReader(file))) == 6


def test_failed_points_are_recorded_and_do_not_stop_the_sweep(tmp_path):
    sweep = tmp_path / "s.toml"
    # 4 ms is one sensor period at the base's 250 Hz but none at 100 Hz: that point is an invalid
    # combination; the PID on tile 3,0 is valid on the 4-wide chip only: with the 2-wide base, an
    # invalid combination (a listed point is checked as a whole, and is valid with one combination)
    sweep.write_text(
        "[base]\nduration_s = 0.03\n[base.sensors]\nrate_hz = 250.0\n[grid]\nduration_s = [0.004, 0.03]\n"
        '"chip.width" = [2, 4]\n'
        '[[points]]\n"sensors.rate_hz" = 100.0\n'
        f'[[points]]\n"firmware.placement" = {PID_AT_3_0}\n'
    )
    config = load_sweep(sweep)
    outcome = run_sweep(config, tmp_path / "out", workers=1)
    status = {json.dumps(r["values"]): (r["status"], r["error"]) for r in outcome.records.values()}
    assert status[json.dumps({"duration_s": 0.03, "chip.width": 2, "sensors.rate_hz": 100.0})][0] == OK
    for width in (2, 4):
        short = status[json.dumps({"duration_s": 0.004, "chip.width": width, "sensors.rate_hz": 100.0})]
        assert short[0] == FAILED and short[1].startswith("invalid combination") and "sensor period" in short[1]
    moved = [{"task": "pid", "tile": [3, 0]}]
    assert status[json.dumps({"duration_s": 0.03, "chip.width": 4, "firmware.placement": moved})][0] == OK
    for duration in (0.004, 0.03):
        bad = status[json.dumps({"duration_s": duration, "chip.width": 2, "firmware.placement": moved})]
        assert bad[0] == FAILED and bad[1].startswith("invalid combination") and "placement[0].tile" in bad[1]
    assert len(outcome.failures) == 4
    # --retry-failed runs exactly the failed ones again
    assert run_sweep(config, tmp_path / "out", workers=1, retry_failed=True).ran == 4


def test_a_listed_point_invalid_in_every_combination_is_refused_before_running(tmp_path):
    sweep = tmp_path / "s.toml"
    sweep.write_text(f'[grid]\nduration_s = [0.03, 0.05]\n[[points]]\n"firmware.placement" = {PID_AT_3_0}\n')
    with pytest.raises(
        ConfigError, match=r"points\[0\]: firmware.placement\[0\].tile: \[3, 0\] \(pid\) is outside the 2x2 mesh"
    ):
        load_sweep(sweep)
    sweep.write_text(f'[[points]]\n"chip.width" = 4\n"firmware.placement" = {PID_AT_3_0}\n')  # valid together
    moved = [{"task": "pid", "tile": [3, 0]}]
    assert load_sweep(sweep).points == ((("chip.width", 4), ("firmware.placement", moved)),)


def test_cli_sweep_writes_table_plots_and_page(tmp_path):
    from typer.testing import CliRunner

    from robosoc.cli import app

    sweep = tmp_path / "s.toml"
    sweep.write_text('[base]\nduration_s = 0.03\n[grid]\n"firmware.multiplier" = [true, false]\n')
    result = CliRunner().invoke(app, ["sweep", str(sweep), "--workers", "1", "--out", str(tmp_path / "out")])
    assert result.exit_code == 0, result.output
    out = tmp_path / "out"
    assert (out / "sweep.toml").read_text() == sweep.read_text()
    plots = sorted(p.name for p in (out / "plots").glob("*.png"))
    assert "pareto-estimator.png" in plots and "pareto-pid.png" in plots
    assert "tasks.estimator.response_us_mean--firmware.multiplier.png" in plots
    for plot in (out / "plots").glob("*.png"):
        assert plot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    page = (out / "sweep.html").read_text()
    assert page.count("data:image/png;base64,") == len(plots) and "http" not in re.sub(
        r"data:image/png;base64,[A-Za-z0-9+/=]*", "", page
    ).lower().replace("https://", "")
    assert "2 points finished, 2 ok" in page


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--dask", "nowhere"], "--dask: expected 'local' or a scheduler address"),
        (["--dask", "tcp://host:0"], "--dask: port must be 1..65535"),
        (["--dask", "ftp://host:80"], "--dask: expected 'local'"),
        (["--workers", "0"], "--workers"),
    ],
)
def test_cli_sweep_bad_options(tmp_path, args, message):
    from typer.testing import CliRunner

    from robosoc.cli import app

    sweep = tmp_path / "s.toml"
    sweep.write_text("[grid]\nduration_s = [0.03]\n")
    result = CliRunner().invoke(app, ["sweep", str(sweep), *args])
    assert result.exit_code == 2 and message in result.output and "Traceback" not in result.output


def test_cli_sweep_bad_file_names_file_and_field(tmp_path):
    from typer.testing import CliRunner

    from robosoc.cli import app

    sweep = tmp_path / "s.toml"
    sweep.write_text('[grid]\n"firmware.arithmetic" = ["fixed"]\n')
    result = CliRunner().invoke(app, ["sweep", str(sweep)])
    assert result.exit_code == 2 and "Traceback" not in result.output
    assert str(sweep) in result.output and "grid.firmware.arithmetic" in result.output and "arith" in result.output


def test_a_sweep_over_two_projects_and_their_mapping(tmp_path: Path) -> None:
    """Two firmware projects (copies of the blank and the quadrotor templates), each with its tasks
    where its robosoc.toml puts them and moved by [[firmware.placement]]: every point flies its own
    project's tasks on the tiles asked, and the default metrics cover both projects' tasks."""
    from typer.testing import CliRunner

    from robosoc.cli import app

    for template in ("blank", "quadrotor"):
        assert CliRunner().invoke(app, ["new", str(tmp_path / template), "--template", template]).exit_code == 0
    sweep = tmp_path / "s.toml"
    sweep.write_text(
        '[base]\nduration_s = 0.05\n"chip.powered_off" = []\n'
        '[[points]]\n"firmware.project" = "blank"\n'
        '[[points]]\n"firmware.project" = "blank"\n"firmware.placement" = [{task = "controller", tile = [1, 1]}]\n'
        '[[points]]\n"firmware.project" = "quadrotor"\n'
        '[[points]]\n"firmware.project" = "quadrotor"\n"firmware.placement" = [{task = "pid", tile = [1, 1]}]\n'
    )
    config = load_sweep(sweep)
    assert [m for m in config.metrics if m.startswith("tasks.")][::3] == [
        "tasks.controller.response_us_mean", "tasks.estimator.response_us_mean", "tasks.pid.response_us_mean"
    ]  # fmt: skip
    # the projects' folders are the sweep file's neighbours, whatever the working folder
    assert config.points[0] == (("firmware.project", str(tmp_path / "blank")),)
    outcome = run_sweep(config, tmp_path / "out", workers=1)
    tiles = {}
    for record in outcome.records.values():
        assert record["status"] == OK, record["error"]
        summary = record["summary"]
        assert all(t["jobs"] == 5 for t in summary["tasks"].values())  # one job per sample, 50 ms at 100 Hz
        tiles[json.dumps(record["values"], sort_keys=True)] = summary["firmware"]["tiles"]
    assert sorted(tiles.values(), key=json.dumps) == sorted(
        [
            {"controller": [0, 1]},
            {"controller": [1, 1]},
            {"estimator": [0, 1], "pid": [1, 0]},
            {"estimator": [0, 1], "pid": [1, 1]},
        ],
        key=json.dumps,
    )
