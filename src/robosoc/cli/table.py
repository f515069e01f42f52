"""``robosoc table``: the seed's Table I measured in the four firmware builds (docs/results.md)."""

from __future__ import annotations

import csv
import json
from pathlib import Path
from typing import Annotated

import typer

from robosoc import output_files
from robosoc.cli import exit_codes, files, options
from robosoc.cli.console import make_console, plain
from robosoc.cli.errors import CliError
from robosoc.cli.project_check import check_inputs, load_checked
from robosoc.cli.scenario_flags import TABLE, ScenarioFlags, resolve, takes_scenario
from robosoc.cli.typer_apps import app
from robosoc.config.scenario import ScenarioConfig

RELEASES = ("event", "periodic", "both")
MAX_ITERATIONS = 10_000
MAX_WORKERS = 64


def _workers() -> int:
    from robosoc.sweep.table_one import default_workers

    return default_workers()


@app.command("table", epilog=exit_codes.EPILOG)
@takes_scenario(TABLE)
def table(
    iterations: Annotated[
        int,
        typer.Option(
            help=f"Samples measured per build from take-off on, 1..{MAX_ITERATIONS}.",
            callback=options.int_range(1, MAX_ITERATIONS),
        ),
    ] = 100,
    release: Annotated[
        str | None,
        typer.Option(
            help="event (a job per sensor message: the seed's release), periodic (both tasks periodic on the "
            "~1 ms tick: robosoc's addition, not the seed's) or both (default: the scenario's, event).",
            callback=options.choice(*RELEASES),
        ),
    ] = None,
    closed_loop: Annotated[
        bool, typer.Option("--closed-loop", help="Fly each build closed-loop instead of replaying the built-in stream.")
    ] = False,
    workers: Annotated[
        int | None,
        typer.Option(
            help=f"Builds measured at once in worker processes, 1..{MAX_WORKERS} (default: the cores, at most 4).",
            callback=options.int_range(1, MAX_WORKERS),
        ),
    ] = None,
    out: Annotated[Path | None, typer.Option("--out", help="Folder for table.csv and table.json.")] = None,
    *,
    flags: ScenarioFlags,
) -> None:
    """Table I: response time, execution time and energy per job of the EKF and PID tasks in the four
    builds (soft-float / Q16.16, with / without multiplier) beside the seed's figures, the seed's
    orderings checked, and the accuracy of estimates and PWM commands; under the built-in scenario or
    SCENARIO (its sensors and noise, vehicle, chip, task mapping, kernel settings and Q16.16 multiply
    routine; each build sets its own arithmetic and multiplier).
    """
    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

    from robosoc.sweep import table_one
    from robosoc.sweep.table_one import OWN_RELEASE

    resolved = resolve(flags)
    scenario = resolved.config
    folder = (
        files.output_dir(out, "--out", names=("table.csv", "table.json"), inputs=resolved.inputs)
        if out is not None
        else None
    )
    release = release or scenario.firmware.release
    project = scenario.firmware.project
    if project:
        source = resolved.source_of("firmware.project")
        checked = load_checked(project, scenario.chip, source, scenario.firmware.mapping)
        if release != "event" and not checked.project.main:
            raise options.fail("--release", OWN_RELEASE)
        if not closed_loop:
            what = "the replay of the built-in sensor stream (--closed-loop flies each build instead)"
            check_inputs(checked, source, ("sensor",), what)
    spec = table_one.TableSpec(
        iterations=iterations,
        releases=("event", "periodic") if release == "both" else (release,),
        closed_loop=closed_loop,
        seed=scenario.seed,
        workers=workers if workers is not None else _workers(),
        project=project,
        base=None if scenario == ScenarioConfig(seed=scenario.seed) else scenario,  # the default: as before
        scenario_file=str(resolved.path) if resolved.path is not None else "",
    )
    if spec.base is not None:  # every build must fit the scenario's chip
        for rel in spec.releases:
            for arith, mul in table_one.BUILDS:
                try:
                    spec.build_scenario(spec.firmware(arith, mul, rel))
                except ValueError as exc:
                    where = f"{resolved.path}: " if resolved.path is not None else ""
                    raise CliError(f"{where}{exc} (the {arith}{'+mul' if mul else '-no-mul'} build)") from exc
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
