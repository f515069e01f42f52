"""Ctrl-C at any moment of ``robosoc fly``: the printed message and ``summary.json`` agree, and no
scratch file (``*.partial``, ``*.tmp``) is left in the run folder (issue 34, item 6)."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from typer.testing import CliRunner

import robosoc.control.flight_plot as flight_plot
import robosoc.outputs.flight_session as flight_session
import robosoc.outputs.run_logs as run_logs
from robosoc.cli import app

SRC = Path(__file__).resolve().parents[2] / "src"


def _fly(out: Path):
    return CliRunner().invoke(app, ["fly", "--controller", "host", "--duration", "0.3", "--out", str(out)])


def _complete(out: Path) -> bool | None:
    path = out / "summary.json"
    return json.loads(path.read_text())["complete"] if path.exists() else None


def _scratch(out: Path) -> list[str]:
    return sorted(p.name for p in out.rglob("*") if p.suffix in (".partial", ".tmp"))


def _agree(output: str, complete: bool | None) -> None:
    if complete is True:
        assert "complete true" in output and "complete false" not in output, output
    elif complete is False:
        assert "complete false" in output and "complete true" not in output, output
    else:
        assert "complete" not in output.replace("incomplete", ""), output


def _sigint() -> None:
    os.kill(os.getpid(), signal.SIGINT)  # as Ctrl-C: Python raises KeyboardInterrupt at the next instruction
    time.sleep(0.05)


def test_ctrl_c_during_the_flight_says_complete_false(tmp_path, monkeypatch):
    real = flight_session.fly_lockstep_fleet

    def flies_then_stops(*args, on_row, **kwargs):
        def row(i, r):
            on_row(i, r)
            if r[0] >= 0.1:
                _sigint()

        return real(*args, on_row=row, **kwargs)

    monkeypatch.setattr(flight_session, "fly_lockstep_fleet", flies_then_stops)
    result = _fly(tmp_path / "run")
    assert result.exit_code == 130
    assert _complete(tmp_path / "run") is False
    _agree(result.output, False)
    assert _scratch(tmp_path / "run") == []


def test_ctrl_c_while_the_summary_is_written_waits_for_it(tmp_path, monkeypatch):
    real = flight_session.write_summary

    def interrupted_write(summary, path):
        _sigint()  # held back until the summary and job records are written
        real(summary, path)

    monkeypatch.setattr(flight_session, "write_summary", interrupted_write)
    result = _fly(tmp_path / "run")
    assert result.exit_code == 130
    assert _complete(tmp_path / "run") is True
    _agree(result.output, True)
    assert "not written: flight.png, flight.mcap, report.html" in result.output
    assert _scratch(tmp_path / "run") == []


@pytest.mark.parametrize("stage", ["plot", "mcap", "report"])
def test_ctrl_c_after_the_flight_says_complete_true_and_leaves_no_scratch_file(tmp_path, monkeypatch, stage):
    def half_written(name):
        def write(*args, **kwargs):
            folder = tmp_path / "run"
            (folder / f"{name}.partial").write_bytes(b"half")  # what a writer cut short leaves
            raise KeyboardInterrupt

        return write

    if stage == "plot":
        monkeypatch.setattr(flight_plot, "plot_flight", half_written("flight.png"))
    elif stage == "mcap":
        monkeypatch.setattr(run_logs, "write_flight_mcap", half_written("flight.mcap"))
    else:
        monkeypatch.setattr(run_logs, "write_report", half_written("report.html"))
    result = _fly(tmp_path / "run")
    assert result.exit_code == 130
    assert _complete(tmp_path / "run") is True
    _agree(result.output, True)
    assert _scratch(tmp_path / "run") == []


def test_an_earlier_runs_summary_does_not_speak_for_an_interrupted_one(tmp_path, monkeypatch):
    out = tmp_path / "run"
    out.mkdir()
    (out / "summary.json").write_text(json.dumps({"complete": True}))

    def stops(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(flight_session, "_controllers", stops)  # Ctrl-C while the firmware is built
    result = _fly(out)
    assert result.exit_code == 130 and _complete(out) is None
    _agree(result.output, None)


def test_real_sigint_at_several_moments(tmp_path):
    """The command as a user runs it, Ctrl-C'd from its first line to past its end: never a
    traceback, the message agrees with summary.json, no scratch file.  (Ctrl-C is sent once the
    command has printed its first line: before, the interpreter itself may still be starting.)"""
    env = dict(os.environ, PYTHONPATH=str(SRC))
    for k, delay in enumerate((0.0, 0.5, 1.0, 1.5, 2.0, 3.0, 4.0)):
        out = tmp_path / f"run-{k}"
        command = [sys.executable, "-m", "robosoc", "fly", "--controller", "host", "--duration", "3", "--out", str(out)]
        process = subprocess.Popen(command, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        first = process.stdout.readline()  # type: ignore[union-attr]
        time.sleep(delay)
        process.send_signal(signal.SIGINT)
        rest, _ = process.communicate(timeout=120)
        output = first + rest
        assert "Traceback" not in output, output
        assert process.returncode in (0, 130, -signal.SIGINT), output
        complete = _complete(out) if out.exists() else None
        if process.returncode != 0 and "run folder:" not in output:
            _agree(output, complete)
        if out.exists():
            assert _scratch(out) == [], output
