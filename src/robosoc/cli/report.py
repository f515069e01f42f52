"""``robosoc report RUN_DIR``: the HTML report of a run folder (and, on request, its MCAP)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from robosoc.cli import exit_codes, files
from robosoc.cli.console import make_console, plain
from robosoc.cli.errors import CliError
from robosoc.cli.typer_apps import app

RunDir = Annotated[Path, typer.Argument(help="A run folder of robosoc fly (flight.csv, jobs.csv, summary.json ...).")]
Out = Annotated[Path | None, typer.Option("--out", "-o", help="Write the page here (default: RUN_DIR/report.html).")]
Mcap = Annotated[bool, typer.Option("--mcap", help="Also write RUN_DIR/flight.mcap from its flight.csv.")]


@app.command("report", epilog=exit_codes.EPILOG)
def report_command(run_dir: RunDir, out: Out = None, mcap: Mcap = False) -> None:
    """Write one self-contained HTML page (no network needed) with the run's plots, figures and config."""
    from robosoc.outputs.run_folder import (
        FLIGHT_CSV,
        FLIGHT_MCAP,
        JOBS_CSV,
        REPORT_HTML,
        SCENARIO_TOML,
        SUMMARY_JSON,
        RunFolderError,
    )

    folder = files.input_dir(run_dir, None)
    inputs = [folder / name for name in (FLIGHT_CSV, JOBS_CSV, SUMMARY_JSON, SCENARIO_TOML)]
    target = files.output_file(
        out if out is not None else folder / REPORT_HTML, "--out" if out else None, inputs=inputs
    )
    if mcap and not (folder / FLIGHT_CSV).is_file():
        raise CliError(f"--mcap: {run_dir}: has no {FLIGHT_CSV} to convert")
    if mcap:
        files.output_file(folder / FLIGHT_MCAP, "--mcap", inputs=inputs)
    from robosoc.outputs.mcap_log import flight_csv_to_mcap
    from robosoc.outputs.report import write_report

    console = make_console()
    try:
        written = write_report(folder, target)
        if mcap:
            messages = flight_csv_to_mcap(folder / FLIGHT_CSV, folder / FLIGHT_MCAP)
    except (RunFolderError, ValueError) as exc:
        raise CliError(str(exc)) from exc
    plain(console, f"report: {written}")
    if mcap:
        plain(console, f"mcap: {folder / FLIGHT_MCAP} ({messages} messages)")
