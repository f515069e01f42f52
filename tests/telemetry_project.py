"""A firmware project that publishes telemetry under a name of its own, for the tests of every mode
that logs it: the blank template with a counter of its controller's jobs (one job per sensor
sample, each done within its period, so the count read at the close of period k is k + 1)."""

from __future__ import annotations

from pathlib import Path

from typer.testing import CliRunner

from robosoc.cli import app

COUNTER = """
[[telemetry]]
name = "jobs_counted"
task = "controller"
value = "jobs_done"
type = "u32"
"""


def counting_project(folder: Path, name: str = "jobs_counted") -> Path:
    """``folder``/p: the blank template whose controller counts its jobs in ``jobs_done``, published
    as the telemetry value ``name``."""
    project = folder / "p"
    result = CliRunner().invoke(app, ["new", str(project)])
    assert result.exit_code == 0, result.output
    source = project / "controller.c"
    text = source.read_text()
    entry = "    (void)arg;\n"
    assert entry in text
    counter = "static uint32_t jobs_done; /* jobs so far */\n"
    text = text.replace("static est_t estimator;", counter + "static est_t estimator;")
    source.write_text(text.replace(entry, entry + "    jobs_done++;\n", 1))
    toml = project / "robosoc.toml"
    toml.write_text(toml.read_text() + COUNTER.replace("jobs_counted", name))
    return project
