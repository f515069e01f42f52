"""``sweep --dask tcp://...`` (issue 34, item 8): the banner counted this machine's cores as the cluster's
workers; it now names the scheduler and the sweep says how many workers it found there.  ``--workers``
with a scheduler (which brings its own) is refused instead of being ignored."""

from __future__ import annotations

from pathlib import Path

import pytest
from typer.testing import CliRunner

from robosoc.cli import app, exit_codes

distributed = pytest.importorskip("distributed")


def _sweep(tmp_path: Path) -> Path:
    sweep = tmp_path / "small.toml"
    sweep.write_text('[base]\nduration_s = 0.1\ncontroller = "host"\n[grid]\n"wind.gust_sigma" = [0.0, 1.0]\n')
    return sweep


def test_the_banner_counts_the_schedulers_workers_not_this_machines_cores(tmp_path: Path) -> None:
    with distributed.LocalCluster(
        n_workers=3, threads_per_worker=1, processes=False, protocol="tcp://", dashboard_address=None
    ) as c:
        address = c.scheduler_address
        result = CliRunner().invoke(
            app, ["sweep", str(_sweep(tmp_path)), "--dask", address, "--out", str(tmp_path / "o")]
        )
    assert result.exit_code == 0, result.output
    lines = result.output.splitlines()
    assert lines[0] == f"sweep small: 2 runs (2 points × 1 seeds) on Dask at {address}"
    assert f"the Dask scheduler at {address} has 3 workers" in lines
    assert "2 ok, 0 failed" in result.output


def test_workers_with_a_scheduler_is_refused(tmp_path: Path) -> None:
    result = CliRunner().invoke(
        app, ["sweep", str(_sweep(tmp_path)), "--dask", "tcp://127.0.0.1:9", "--workers", "4", "--out", str(tmp_path)]
    )
    assert result.exit_code == exit_codes.USAGE, result.output
    assert result.output.startswith("robosoc sweep: --workers: a Dask scheduler (tcp://127.0.0.1:9) brings its own")
