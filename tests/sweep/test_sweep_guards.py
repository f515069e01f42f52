"""Sweeps refuse what cannot work before running, and leave nothing behind (issue 34, item 5):
``[[points]]`` values checked like grid values, unknown metrics refused, a sweep whose every run
failed exits 3, one sweep at a time per folder, OS errors named as such, and workers that die with
a SIGKILLed sweep."""

from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from typer.testing import CliRunner

from robosoc.cli import app, exit_codes
from robosoc.config.sweep import load_sweep
from robosoc.config.validate import ConfigError
from robosoc.sweep.store import FolderInUse, SweepStore

SRC = Path(__file__).resolve().parents[2] / "src"
HOST = '[base]\nduration_s = 0.03\ncontroller = "host"\n'


def _sweep(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "s.toml"
    path.write_text(text)
    return path


def _invoke(*args: object):
    return CliRunner().invoke(app, [str(a) for a in args])


@pytest.mark.parametrize(
    ("point", "message"),
    [
        ('"sensors.rate_hz" = -5.0', "points[0]: sensors.rate_hz"),
        ('"firmware.arith" = "decimal"', "points[0]: firmware.arith"),
        ('"duration_s" = "long"', "points[0]: duration_s"),
        ('"chip.width" = 0', "points[0]: chip.width"),
    ],
)
def test_listed_point_values_are_checked_before_anything_runs(tmp_path, point, message) -> None:
    path = _sweep(tmp_path, HOST + f"[[points]]\n{point}\n")
    with pytest.raises(ConfigError) as caught:
        load_sweep(path)
    assert message in str(caught.value) and str(path) in str(caught.value)
    result = _invoke("sweep", path, "--out", tmp_path / "out")
    assert result.exit_code == 2 and message in result.output and "Traceback" not in result.output
    assert not (tmp_path / "out" / "results").exists()


@pytest.mark.parametrize(
    ("metric", "message"),
    [
        ("flight.hover", "'flight.hover' is not a field of summary.json (flight has: hover_rms_m"),
        ("tasks.ekf.nonsense", "(tasks.ekf has: jobs, response_us_mean"),
        ("energy.tiles_uj", "is not a number of summary.json"),
        ("nonsense", "(summary.json has: schema, complete"),
    ],
)
def test_a_metric_that_is_not_in_the_summary_is_refused(tmp_path, metric, message) -> None:
    path = _sweep(tmp_path, f'metrics = ["{metric}"]\n' + HOST)
    result = _invoke("sweep", path, "--out", tmp_path / "out")
    assert result.exit_code == 2 and "metrics[0]" in result.output and message in result.output


def test_known_metrics_are_accepted(tmp_path) -> None:
    names = ["tasks.pid.response_us_max", "energy.tiles_uj.0,1", "cycles.tiles.1,0", "flight.tracking_rms_deg.roll",
             "deadline_misses", "real_time_factor", "complete"]  # fmt: skip
    config = load_sweep(_sweep(tmp_path, f"metrics = {names!r}\n".replace("'", '"') + HOST))
    assert config.metrics == tuple(names)


def test_a_sweep_whose_every_run_failed_exits_3(tmp_path) -> None:
    # each grid value is valid alone (4 ms is one sensor period at the base's 250 Hz), but a 4 ms
    # flight is shorter than a 100 Hz or 50 Hz sensor period: every run is an invalid combination
    base = '[base]\nduration_s = 0.03\ncontroller = "host"\n[base.sensors]\nrate_hz = 250.0\n'
    path = _sweep(tmp_path, base + '[grid]\nduration_s = [0.004]\n"sensors.rate_hz" = [100.0, 50.0]\n')
    result = _invoke("sweep", path, "--out", tmp_path / "out", "--workers", "1")
    assert result.exit_code == exit_codes.ALL_FAILED == 3, result.output
    assert "every one of the 2 runs failed" in result.output
    # some runs that fly: exit 0 with the failures listed
    path.write_text(base + '[grid]\nduration_s = [0.004, 0.03]\n"sensors.rate_hz" = [100.0, 50.0]\n')
    result = _invoke("sweep", path, "--out", tmp_path / "out", "--workers", "1")
    assert result.exit_code == 0 and "2 ok, 2 failed" in result.output, result.output


def test_a_second_sweep_into_the_same_folder_is_refused_naming_the_first(tmp_path) -> None:
    out = tmp_path / "out"
    SweepStore(out)
    holding = (
        "import sys, time\nfrom pathlib import Path\nfrom robosoc.sweep.store import SweepStore\n"
        "with SweepStore(Path(sys.argv[1])).lock():\n    print('held', flush=True)\n    time.sleep(60)\n"
    )
    holder = subprocess.Popen(
        [sys.executable, "-c", holding, str(out)],
        env={**os.environ, "PYTHONPATH": str(SRC)},
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        assert holder.stdout.readline().strip() == "held"  # type: ignore[union-attr]
        result = _invoke("sweep", _sweep(tmp_path, HOST), "--out", out, "--workers", "1")
        assert result.exit_code == 2, result.output
        assert f"--out: {out}: in use by another sweep (pid {holder.pid})" in result.output
        assert "Dask" not in result.output and not (out / "sweep.toml").exists()
        with pytest.raises(FolderInUse), SweepStore(out).lock():
            pass
    finally:
        holder.kill()
        holder.wait()
    with SweepStore(out).lock(), SweepStore(out).lock():  # free again; re-entrant within a process
        pass
    assert _invoke("sweep", _sweep(tmp_path, HOST), "--out", out, "--workers", "1").exit_code == 0


def test_an_os_error_is_reported_as_one_not_as_dask(tmp_path, monkeypatch) -> None:
    import robosoc.sweep.store as store

    def full(path, data):
        raise OSError(28, "No space left on device", str(path))

    monkeypatch.setattr(store, "write_atomic", full)
    result = _invoke("sweep", _sweep(tmp_path, HOST), "--out", tmp_path / "out", "--workers", "1")
    assert result.exit_code == 2 and "Traceback" not in result.output
    assert (
        "no space left on device" in result.output and "Dask" not in result.output and "scheduler" not in result.output
    )


def _descendants(pid: int) -> set[int]:
    children: dict[int, list[int]] = {}
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            fields = (entry / "stat").read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        children.setdefault(int(fields[1]), []).append(int(entry.name))
    found, todo = set(), [pid]
    while todo:
        for child in children.get(todo.pop(), []):
            if child not in found:
                found.add(child)
                todo.append(child)
    return found


def _alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"


@pytest.mark.skipif(not Path("/proc").is_dir(), reason="needs /proc (Linux)")
def test_sigkill_of_a_sweep_leaves_no_process_behind(tmp_path) -> None:
    path = _sweep(tmp_path, 'seeds = [1, 2, 3, 4]\n[base]\nduration_s = 30.0\ncontroller = "host"\n')
    sweep = subprocess.Popen(
        [sys.executable, "-m", "robosoc", "sweep", str(path), "--out", str(tmp_path / "out"), "--workers", "2"],
        env={**os.environ, "PYTHONPATH": str(SRC)}, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
    )  # fmt: skip
    try:
        deadline = time.monotonic() + 120
        workers: set[int] = set()
        while time.monotonic() < deadline:  # the resource tracker and both workers
            workers = _descendants(sweep.pid)
            if len(workers) >= 3:
                break
            assert sweep.poll() is None
            time.sleep(0.2)
        assert len(workers) >= 3, workers
        time.sleep(2.0)  # the workers are past their start, flying
        workers = _descendants(sweep.pid)
        sweep.send_signal(signal.SIGKILL)
        sweep.wait()
        time.sleep(5.0)
        left = [pid for pid in workers if _alive(pid)]
        assert left == [], [Path(f"/proc/{p}/cmdline").read_bytes()[:120] for p in left]
    finally:
        for pid in _descendants(sweep.pid) | workers:
            with contextlib.suppress(OSError):
                os.kill(pid, signal.SIGKILL)
