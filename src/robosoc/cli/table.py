"""``robosoc table``: the seed's Table I measured in the four firmware builds (docs/results.md)."""

from __future__ import annotations

import csv
import json
from pathlib import Path
from typing import Annotated

import typer

from robosoc import output_files
from robosoc.cli import exit_codes, files, options
from robosoc.cli.app import app
from robosoc.cli.console import make_console, plain
from robosoc.cli.project_check import check_inputs, load_checked
from robosoc.config.firmware import FirmwareConfig

RELEASES = ("event", "periodic", "both")
MAX_ITERATIONS = 10_000
MAX_WORKERS = 64


def _workers() -> int:
    from robosoc.sweep.table_one import default_workers

    return default_workers()


@app.command("table", epilog=exit_codes.EPILOG)
def table(
    iterations: Annotated[
        int,
        typer.Option(
            help=f"Samples measured per build from take-off on, 1..{MAX_ITERATIONS}.",
            callback=options.int_range(1, MAX_ITERATIONS),
        ),
    ] = 100,
    release: Annotated[
        str,
        typer.Option(
            help="event (a job per sensor message, as in the seed; the default), periodic (both tasks periodic "
            "on the ~1 ms tick: robosoc's option) or both.",
            callback=options.choice(*RELEASES),
        ),
    ] = "event",
    closed_loop: Annotated[
        bool, typer.Option("--closed-loop", help="Fly each build closed-loop instead of replaying the built-in stream.")
    ] = False,
    seed: Annotated[int, typer.Option(help="The flight's seed.", callback=options.seed())] = 1,
    workers: Annotated[
        int | None,
        typer.Option(
            help=f"Builds measured at once in worker processes, 1..{MAX_WORKERS} (default: the cores, at most 4).",
            callback=options.int_range(1, MAX_WORKERS),
        ),
    ] = None,
    out: Annotated[Path | None, typer.Option("--out", help="Folder for table.csv and table.json.")] = None,
    firmware: Annotated[
        Path | None,
        typer.Option(
            metavar="DIR",
            help="Measure the firmware project in DIR (one row per task of its robosoc.toml, the builds it "
            "supports) instead of the built-in application (docs/firmware-projects.md).",
        ),
    ] = None,
) -> None:
    """Table I: response time, execution time and energy per job of the EKF and PID tasks in the four
    builds (soft-float / Q16.16, with / without multiplier) beside the seed's figures, the seed's
    orderings checked, and the accuracy of estimates and PWM commands.
    """
    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

    from robosoc.sweep import table_one

    folder = files.output_dir(out, "--out", names=("table.csv", "table.json")) if out is not None else None
    project = ""
    if firmware is not None:
        if release != "event":
            raise options.fail("--release", "a project's tasks have their own release (its robosoc.toml)")
        project = str(firmware.absolute())
        loaded = load_checked(project, FirmwareConfig(project=project).default_chip(), "--firmware")
        if not closed_loop:
            what = "the replay of the built-in sensor stream (--closed-loop flies each build instead)"
            check_inputs(loaded, "--firmware", ("sensor",), what)
    spec = table_one.TableSpec(
        iterations=iterations,
        releases=("event", "periodic") if release == "both" else (release,),
        closed_loop=closed_loop,
        seed=seed,
        workers=workers if workers is not None else _workers(),
        project=project,
    )
    console = make_console(stderr=True)
    builds = 4 * len(spec.releases)
    columns = (TextColumn("{task.description}"), BarColumn(), TextColumn("{task.completed}/{task.total}"),
               TimeElapsedColumn())  # fmt: skip
    with Progress(*columns, console=console, transient=True) as progress:
        bar = progress.add_task(f"{builds} builds ({'closed-loop' if closed_loop else 'replay'})", total=builds)
        done: dict[str, float] = {}

        def on_progress(key: str, k: int, total: int) -> None:
            done[key] = k / total if total else 1.0
            progress.update(bar, completed=round(sum(done.values()), 2))

        result = table_one.measure_table(spec, on_progress)
    stdout = make_console()
    for line in table_one.format_table(result):
        plain(stdout, line)
    if folder is None:
        return
    _write_atomic(folder / "table.json", json.dumps(table_one.to_json(result), indent=2, allow_nan=False) + "\n")
    rows = [table_one.CSV_FIELDS, *table_one.csv_rows(result)]
    with output_files.atomic_open(folder / "table.csv", "w", newline="") as handle:
        csv.writer(handle).writerows(rows)
    plain(stdout, f"wrote {folder / 'table.csv'} and {folder / 'table.json'}")


def _write_atomic(path: Path, text: str) -> None:
    output_files.write_atomic(path, text)
